"""The rules a station config's values are checked by, declared on the settings dataclasses.

Each key of the station YAML is a dataclass field declared with :func:`setting`: its default, its
:class:`Rule` (type, range or choices), its unit and a one-line doc, in one place. The checking of a
file (:func:`check_section`), the known keys, the key list the example file must document
(:func:`schema_keys`) and the masking of secrets all come from these declarations, so a new field
without a rule cannot be written.

Messages name the key (``controller.port must be between 1 and 65535; got 70000``) and quote the
bad value with :func:`~handeye.base.errors.brief` (bounded, never an expanded YAML alias).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterator
from typing import Protocol
from dataclasses import dataclass, field, fields, replace

from ...base import ConfigError, brief

__all__ = ["Rule", "Number", "Numbers", "Range", "Text", "Flag", "Optional", "Custom", "Section", "setting", "section",
           "rule_of", "key_rule", "NameChoices", "check_section", "chosen_of", "declared_fields", "schema_keys", "secret_fields", "number", "numbers", "text"]

#: Largest finite float: ``abs(v) <= _FLOAT_MAX`` is false for NaN, inf and integers too large for a
#: float (where ``math.isfinite`` would raise OverflowError).
_FLOAT_MAX = sys.float_info.max


class Rule:
    """How one value is checked: ``rule(value, key, context) -> the value to keep``.

    ``context`` holds what other keys decided (``robot``: the robot model of the config).
    """

    def __call__(self, value, key: str, context: dict):
        raise NotImplementedError


def number(value, key: str, low: float = -math.inf, high: float = math.inf, integer: bool = False):
    """``value`` as a float (int when ``integer``) within ``[low, high]``, else ConfigError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) <= _FLOAT_MAX:
        raise ConfigError(f"{key} must be a {'whole ' if integer else ''}number; got {brief(value)}")
    if integer and int(value) != value:
        raise ConfigError(f"{key} must be a whole number; got {brief(value)}")
    if not low <= value <= high:
        raise ConfigError(f"{key} must be between {low:g} and {high:g}; got {brief(value)}")
    return int(value) if integer else float(value)


def numbers(value, key: str, count: int, low=-math.inf, high=math.inf) -> tuple:
    """A list of ``count`` numbers within ``[low, high]``, as a tuple of floats."""
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise ConfigError(f"{key} must be a list of {count} numbers; got {brief(value)}")
    return tuple(number(v, f"{key}[{i}]", low, high) for i, v in enumerate(value))


def text(value, key: str, choices=(), what: str = "") -> str:
    """A non-empty text, one of ``choices`` when given; ``what`` (``the controller's IP address or host
    name``) says what an empty one should have held."""
    if isinstance(value, str) and not value.strip():
        raise ConfigError(f"{key} must not be empty{': ' + what if what else ''}")
    if not isinstance(value, str):
        raise ConfigError(f"{key} must be a text{': ' + what if what else ''}; got {brief(value)}")
    if choices and value not in choices:
        refusal = getattr(choices, "refusal", None)  # a registry's choices say why one of its names is not
        why = refusal(value) if refusal is not None else None
        listed = choices.listed() if hasattr(choices, "listed") else ", ".join(choices)
        raise ConfigError(f"{key} must be one of {listed}; got {brief(value)}" + (f": {why}" if why else ""))
    return value


@dataclass(frozen=True)
class Number(Rule):
    """A number in ``[low, high]`` (a whole number when ``integer``)."""

    low: float = -math.inf
    high: float = math.inf
    integer: bool = False

    def __call__(self, value, key, context):
        return number(value, key, self.low, self.high, self.integer)


@dataclass(frozen=True)
class Numbers(Rule):
    """``count`` numbers in ``[low, high]``."""

    count: int
    low: float = -math.inf
    high: float = math.inf

    def __call__(self, value, key, context):
        return numbers(value, key, self.count, self.low, self.high)


@dataclass(frozen=True)
class Range(Rule):
    """``[min, max]`` with ``low <= min < max <= high``."""

    low: float = 0.0
    high: float = math.inf

    def __call__(self, value, key, context):
        pair = numbers(value, key, 2, self.low, self.high)
        if pair[0] >= pair[1]:
            raise ConfigError(f"{key} must be [min, max] with min < max; got {list(value)!r}")
        return pair


class NameChoices(Protocol):
    """What a :class:`Text` may be: a tuple of names, or a registry's ``base.registry.Choices`` (which also
    says why a name is refused and lists its names itself)."""

    def __contains__(self, value: object, /) -> bool: ...

    def __iter__(self) -> Iterator[str]: ...


@dataclass(frozen=True)
class Text(Rule):
    """A non-empty text; ``choices`` (a callable returning them: registries grow) limits it; ``what``
    says what it holds when it is left empty."""

    choices: Callable[[], NameChoices] | None = None
    what: str = ""

    def __call__(self, value, key, context):
        return text(value, key, self.choices() if self.choices else (), self.what)


@dataclass(frozen=True)
class Flag(Rule):
    """``true`` or ``false``."""

    def __call__(self, value, key, context):
        if not isinstance(value, bool):
            raise ConfigError(f"{key} must be true or false; got {brief(value)}")
        return value


@dataclass(frozen=True)
class Optional(Rule):
    """``null``, or a value ``rule`` accepts."""

    rule: Rule

    def __call__(self, value, key, context):
        return None if value is None else self.rule(value, key, context)


@dataclass(frozen=True)
class Custom(Rule):
    """A check of its own: ``check(value, key, context)``."""

    check: Callable

    def __call__(self, value, key, context):
        return self.check(value, key, context)


def setting(default, rule: Rule, doc: str, unit: str = "", *, required: bool = False, secret: bool = False,
            factory: Callable | None = None, keys: type | None = None):
    """A dataclass field of the station config: its default, rule, unit and one-line doc.

    Parameters
    ----------
    default
        The built-in value (use ``factory`` for mutable ones).
    rule : Rule
        How a value from a file is checked.
    doc : str
        One line: what the key is for.
    unit : str
        ``mm``, ``deg``, ``s``, ``kg`` ... (empty for none).
    required : bool
        A file must name it (the station's hardware).
    secret : bool
        Never printed: masked in ``repr`` and in the config's record.
    factory : callable, optional
        Makes the default (a mutable one).
    keys : type, optional
        A dataclass of :func:`setting` fields: the value is a section of those keys.
    """
    metadata = {"rule": rule, "doc": doc, "unit": unit, "required": required, "secret": secret, "keys": keys}
    if factory is not None:
        return field(default_factory=factory, metadata=metadata)
    return field(default=default, repr=not secret, metadata=metadata)


@dataclass(frozen=True)
class Section(Rule):
    """A mapping of the keys of ``cls`` (a dataclass of :func:`setting` fields); the missing keep
    their defaults. The keys declared elsewhere (:func:`declared_fields`) that differ from their
    default go, as a dict, into the field ``cls.EXTRA_FIELD``."""

    cls: type

    def __call__(self, value, key, context):
        changes = check_section(self.cls, value or {}, key, context)
        own = {f.name for f in fields(self.cls)}
        chosen = _chosen(self.cls, value)
        defaults = {f.name: f.default for f in declared_fields(self.cls, chosen) if f.name not in own}
        extra = {name: v for name, v in changes.items() if name in defaults and v != defaults[name]}
        changes = {name: v for name, v in changes.items() if name in own}
        if extra:
            changes[self.cls.EXTRA_FIELD] = extra
        return replace(self.cls(), **changes)


def section(cls, doc: str):
    """A dataclass field holding a whole section: an instance of ``cls``, checked key by key."""
    return setting(cls(), Section(cls), doc, keys=cls)


def rule_of(f) -> Rule | None:
    """The rule of a dataclass field (None: not a config key)."""
    return f.metadata.get("rule")


def key_rule(f) -> Rule:
    """The rule of a config key's field (made by :func:`setting`; :func:`rule_of` where one must be)."""
    rule = rule_of(f)
    if rule is None:
        raise TypeError(f"field {f.name} is not a config key (it was not made with setting())")
    return rule


def declared_fields(cls, chosen: str | None = None) -> list:
    """The config keys of ``cls``: its :func:`setting` fields, then the keys declared elsewhere that
    its section takes (``cls.extra_settings(chosen)``, fields made with :func:`setting` and named: the
    controller back ends' own link settings, which their registry describes; ``chosen`` is the back end
    the section names, whose keys it may hold beside those of handeye's own back ends; None: the keys of
    every back end, for the schema's documentation)."""
    own = [f for f in fields(cls) if rule_of(f) is not None]
    extra = getattr(cls, "extra_settings", None)
    return own + (list(extra(chosen)) if extra is not None else [])


def _chosen(cls, data):
    """The back end a section's data name (its ``cls.CHOSEN_BY`` key; "" when they name none)."""
    key = getattr(cls, "CHOSEN_BY", "")
    return data.get(key, "") if key and isinstance(data, dict) else ""


def _printable(key) -> str:
    return key if isinstance(key, str) and key.isprintable() else brief(key)


def check_section(cls, data, name: str, context: dict) -> dict:
    """Check one section of a file (a mapping) against the fields of ``cls``; returns the changes.

    Raises
    ------
    ConfigError
        The section is not a mapping, holds an unknown key, or a value its rule refuses.
    """
    section = data if data is not None else {}
    if not isinstance(section, dict):
        raise ConfigError(f"{name} must be a mapping of keys; got {brief(section)}")
    rules = {f.name: key_rule(f) for f in declared_fields(cls, _chosen(cls, section))}
    allowed = set(rules)
    unknown = sorted(set(section) - allowed, key=brief)
    if unknown:
        raise ConfigError(f"unknown key {name}.{_printable(unknown[0])}; known keys of {name}: {', '.join(sorted(allowed))}")
    return {key: rules[key](value, f"{name}.{key}", context) for key, value in section.items()}


def schema_keys(cls, prefix: str = ""):
    """``(key path, field)`` of every config key of ``cls``, sections expanded (``controller.port``)."""
    for f in declared_fields(cls):
        path = f"{prefix}{f.name}"
        if f.metadata.get("keys") is not None:
            yield from schema_keys(f.metadata["keys"], path + ".")
        else:
            yield path, f


def secret_fields(cls, chosen: str | None = None) -> tuple[str, ...]:
    """Names of the keys of ``cls`` declared secret (:func:`declared_fields`; ``chosen``: its back end)."""
    return tuple(f.name for f in declared_fields(cls, chosen) if f.metadata.get("secret"))


def chosen_of(settings) -> str:
    """The back end a section instance names (its class's ``CHOSEN_BY`` key; "" when none)."""
    key = getattr(type(settings), "CHOSEN_BY", "")
    return getattr(settings, key, "") if key else ""
