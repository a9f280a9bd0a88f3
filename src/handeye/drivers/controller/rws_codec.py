"""The RAPID value codec of the ``rws`` back end: RAPID aggregate literals as RWS prints and reads
them (``[TRUE,[[1,2,3],[1,0,0,0]],...]``, ``"text"``, ``9E+09``), and ``tooldata`` as nested values.
The mock RWS controller reads its writes with the same functions."""

from __future__ import annotations

import re
from typing import Any, Union

from .types import ToolData

__all__ = ["rapid_literal", "parse_rapid_value", "tooldata_value", "tool_of_value"]


#: What :func:`rapid_literal` writes: nested lists or tuples of numbers and bools.
RapidData = Union[bool, float, list["RapidData"], tuple["RapidData", ...]]


def rapid_literal(values: RapidData) -> str:
    """A RAPID aggregate literal of nested numbers and bools: ``[TRUE,[[1,2,3],[1,0,0,0]],...]``."""
    if isinstance(values, bool):
        return "TRUE" if values else "FALSE"
    if isinstance(values, (list, tuple)):
        return "[" + ",".join(rapid_literal(v) for v in values) + "]"
    value = float(values)
    return str(int(value)) if value == int(value) and abs(value) < 1e9 else repr(value)


_TOKEN = re.compile(r"\s*(\[|\]|,|\"(?:[^\"]|\"\")*\"|TRUE|FALSE|[-+0-9.eE]+)", re.IGNORECASE)


def parse_rapid_value(text: str) -> Any:
    """A RAPID value as RWS prints it (``[1,2,3]``, ``TRUE``, ``"text"``, ``9E+09``) as nested lists (of
    the shape the controller sent: typed ``Any``, as :func:`json.loads` is).

    Raises
    ------
    ValueError
        Not a RAPID literal of numbers, bools and strings.
    """
    pos, stack = 0, [[]]
    text = str(text).strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise ValueError(f"not a RAPID value at {text[pos:pos + 20]!r}")
        tok, pos = m.group(1), m.end()
        if tok == "[":
            stack.append([])
        elif tok == "]":
            if len(stack) < 2:
                raise ValueError("unbalanced ']'")
            done = stack.pop()
            stack[-1].append(done)
        elif tok == ",":
            continue
        elif tok.upper() in ("TRUE", "FALSE"):
            stack[-1].append(tok.upper() == "TRUE")
        elif tok.startswith('"'):
            stack[-1].append(tok[1:-1].replace('""', '"'))
        else:
            stack[-1].append(float(tok))
    if len(stack) != 1 or len(stack[0]) != 1:
        raise ValueError("not one RAPID value")
    return stack[0][0]


def tooldata_value(tool: ToolData, robhold: bool = True) -> list:
    """A :class:`ToolData` as the nested values of a RAPID ``tooldata`` (inertia axes identity, 0)."""
    return [robhold, [list(tool.position_mm), list(tool.quaternion_wxyz)],
            [tool.mass_kg, list(tool.cog_mm), [1, 0, 0, 0], 0, 0, 0]]


def tool_of_value(value: Any) -> ToolData:
    """The :class:`ToolData` of a parsed RAPID ``tooldata`` value (``ValueError`` when it is not one)."""
    try:
        (_, (p, q), (mass, cog, *_)) = value
        return ToolData(tuple(float(v) for v in p), tuple(float(v) for v in q), float(mass),
                        tuple(float(v) for v in cog))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"not a tooldata value ({exc})") from None
