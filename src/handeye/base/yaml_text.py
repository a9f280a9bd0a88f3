"""The one YAML reader of the package: PyYAML's safe loader with two of YAML's traps closed.

Every file the package reads as YAML (station configs, sessions and posture files, imports,
quality thresholds, robot files, register maps, stereo models) goes through :func:`parse_yaml`.

- **A key written twice in one mapping is refused**, at any depth, naming the key and both lines.
  PyYAML keeps the last value silently ("last wins"): a station file with a second ``cell:`` section
  would lose the first one's keep-out volumes without a word. Keys brought in by a merge (``<<:``)
  are not duplicates: YAML lets explicit keys override them.
- **Numbers in exponent form are numbers**: YAML 1.1 (PyYAML's dialect) reads ``1e30`` and
  ``1.5e3`` as text because its float pattern wants a dot and a signed exponent. YAML 1.2, JSON and
  every person read them as floats; so does this reader (``1e30`` -> ``1e+30``).

Everything PyYAML raises becomes one line naming the file (and the line where PyYAML knows it).
"""

from __future__ import annotations

import re
from typing import Any

import yaml

from .errors import SessionError

__all__ = ["parse_yaml", "DuplicateKeyError", "AliasBombError", "ALIAS_EXPANSION_BUDGET", "expanded_size"]

#: PyYAML's safe loader on libyaml when it is built in: many times faster, linear in the nesting depth
#: and limited to 1000 levels (the pure-Python scanner is quadratic in the depth of ``[[[[...``).
_BASE_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

#: Floats YAML 1.1 misses: an exponent without a dot (``1e30``) or without a sign (``2.5e3``).
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")


class DuplicateKeyError(yaml.YAMLError):
    """A mapping holds the same key twice; ``key``, ``first_line`` and ``second_line`` (1-based)."""

    def __init__(self, key: object, first_line: int, second_line: int):
        super().__init__(f"key {key!r} on lines {first_line} and {second_line}")
        self.key, self.first_line, self.second_line = key, first_line, second_line


#: Aliases may repeat at most this many values beyond those written (an alias bomb of 400 bytes
#: expands to billions: refused from the composed node graph, before anything is built from it).
ALIAS_EXPANSION_BUDGET = 100_000


class AliasBombError(yaml.YAMLError):
    """Aliases expand the document beyond :data:`ALIAS_EXPANSION_BUDGET` values."""


def expanded_size(node: yaml.Node, limit: int) -> tuple[int, int]:
    """``(values the document holds once every alias is expanded, capped just past limit; distinct
    nodes visited)``: each distinct node is counted once (memoised), so the cost is that of the text.

    Parameters
    ----------
    node : yaml.Node
    limit : int
        Counting stops once the expanded size exceeds it.
    """
    sizes: dict = {}
    stack = [(node, False)]
    while stack:
        current, done = stack.pop()
        key = id(current)
        if key in sizes and not done:
            continue
        children = []
        if isinstance(current, yaml.MappingNode):
            children = [n for pair in current.value for n in pair]
        elif isinstance(current, yaml.SequenceNode):
            children = list(current.value)
        if not done:
            sizes[key] = None  # in progress (YAML aliases cannot form cycles through the safe composer)
            stack.append((current, True))
            stack.extend((c, False) for c in children if id(c) not in sizes)
            continue
        sizes[key] = min(limit + 1, 1 + sum(sizes.get(id(c)) or 0 for c in children))
    return sizes[id(node)] or 0, len(sizes)


class _StrictLoader(_BASE_LOADER):
    """The safe loader that refuses duplicated keys and alias bombs, and reads ``1e30`` as a float."""

    def get_single_node(self):
        node = super().get_single_node()
        if node is not None:
            size, distinct = expanded_size(node, 10**12)
            if size > distinct + ALIAS_EXPANSION_BUDGET:
                raise AliasBombError(f"aliases expand the document beyond {ALIAS_EXPANSION_BUDGET} repeated values")
        return node

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            _refuse_duplicate_keys(self, node)
        return super().construct_mapping(node, deep=deep)


_StrictLoader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT, list("-+.0123456789"))


def _refuse_duplicate_keys(loader, node) -> None:
    """Raise :class:`DuplicateKeyError` for the first key of ``node`` written twice (merges excepted)."""
    seen = {}
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue
        key, line = loader.construct_object(key_node, deep=True), key_node.start_mark.line + 1
        try:
            if key in seen:
                raise DuplicateKeyError(key, seen[key], line)
            seen[key] = line
        except TypeError:  # an unhashable key: PyYAML itself refuses it with its line
            continue


def parse_yaml(text: str, source: object, error: type[Exception] = SessionError, hint: str = "") -> Any:
    """The YAML document in ``text``; text that cannot be loaded raises ``error`` naming ``source``.

    Parameters
    ----------
    text : str
        The document.
    source : str or Path
        What the text is (a file's path), for the messages.
    error : type
        Exception class raised (the caller's room's one-line error).
    hint : str
        Appended to the message of malformed YAML (what the file should look like).

    Raises
    ------
    error
        A key written twice in one mapping (naming the key and both lines); malformed YAML (named
        with its line); what PyYAML's constructors raise as other exceptions: impossible dates
        (``2020-13-45``), integers of more than 4300 digits, explicit tags whose value has the wrong
        form (``!!float abc`` raises ValueError, ``!!timestamp x`` AttributeError), and nesting too
        deep for the parser.
    """
    try:
        return yaml.load(text, Loader=_StrictLoader)
    except DuplicateKeyError as exc:
        raise error(_duplicate_message(text, source, exc)) from None
    except AliasBombError as exc:
        raise error(f"{source}: not read as YAML: {exc} (an alias bomb?); write the values out{hint}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise error(f"{source}: not valid YAML{where}{hint}") from None
    except RecursionError:
        raise error(f"{source}: nested too deeply to be read as YAML{hint}") from None
    except (ValueError, OverflowError) as exc:
        reason = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
        raise error(f"{source}: not valid YAML: a value cannot be read ({reason}){hint}") from None
    except Exception:  # noqa: BLE001 - PyYAML's safe constructors raise assorted types on tagged values
        raise error(f"{source}: not valid YAML: a tagged value (such as !!timestamp) has the wrong form{hint}") from None


def _duplicate_message(text: str, source, exc: DuplicateKeyError) -> str:
    """One line naming the duplicated key (with the sections it sits in) and both of its lines."""
    path = _key_path(yaml.compose(text, Loader=_BASE_LOADER), (exc.second_line - 1, str(exc.key)), ())
    name = ".".join(path) if path else _brief_key(exc.key)
    where = (f"twice on line {exc.first_line}" if exc.first_line == exc.second_line
             else f"twice (lines {exc.first_line} and {exc.second_line})")
    return f"{source}: the key {name} is written {where}; a reader would silently keep only the last: merge them into one"


def _key_path(node, wanted: tuple, path: tuple) -> tuple | None:
    """Names of the keys leading to the key node ``wanted`` = (0-based line, text), or ``None``."""
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            step = (*path, str(getattr(key_node, "value", "?")))
            if isinstance(key_node, yaml.ScalarNode) and (key_node.start_mark.line, key_node.value) == wanted:
                found = step
            else:
                found = _key_path(value_node, wanted, step)
            if found:
                return found
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            found = _key_path(item, wanted, (*path[:-1], f"{path[-1]}[{index}]") if path else (f"[{index}]",))
            if found:
                return found
    return None


def _brief_key(key) -> str:
    """The key as the message quotes it: short, on one line."""
    text = repr(key) if not isinstance(key, str) else f"'{key}'"
    return text if len(text) <= 60 else text[:57] + "...'"
