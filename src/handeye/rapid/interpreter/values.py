"""RAPID data: the types, values of records and arrays, conversions, and the predefined data.

- ``num`` is a 32-bit float on a controller: a value stored into a ``num`` (variable, component,
  element, parameter) is rounded to float32, as the controller keeps it; ``dnum`` keeps a double.
  Expressions compute in double and are rounded where stored.
- A record is a :class:`Record` (its type and a dict of components); an array a :class:`Array`
  (a list, 1-based in RAPID). Both are copied on assignment: RAPID data are values.
- Non-value types (``socketdev``, ``iodev``, ``clock``, ``shapedata``) hold a :class:`Handle`, a
  mutable object that is never copied (a ``socketdev`` cannot be assigned).
- ``[a, b, c]`` evaluates to an :class:`Aggregate`, which becomes a record or an array where the
  expected type is known.
"""

from __future__ import annotations

from typing import Any, TypeVar, overload
import struct
from dataclasses import dataclass

from .errors import RapidFatalError, RapidRuntimeError

__all__ = ["TypeInfo", "Record", "Array", "Aggregate", "Handle", "TYPES", "type_info", "to_num", "default_value",
           "coerce", "copy_value", "compatible", "format_value", "aggregate", "MAX_STRING", "NUM_TYPES", "SIGNAL_TYPES"]

MAX_STRING = 80
_F32 = struct.Struct("f")
_F32_MAX = 3.4028234663852886e38
_V = TypeVar("_V")


def to_num(value: float) -> float:
    """``value`` as a float32 (what a ``num`` holds)."""
    v = float(value)
    if v != v or abs(v) > _F32_MAX:
        raise RapidRuntimeError("ERR_OVERFLOW", f"{v:g} does not fit a num")
    return _F32.unpack(_F32.pack(v))[0]


@dataclass(frozen=True)
class TypeInfo:
    """A data type: ``kind`` is ``atomic`` (num, dnum, bool, string), ``record`` or ``handle``;
    ``base`` is the atomic type an alias stands for (``errnum`` -> ``num``)."""

    name: str
    kind: str
    base: str | None = None
    fields: tuple = ()  # ((name, type name), ...) of a record
    factory: object = None  # handle types: makes a new handle

    @property
    def key(self) -> str:
        return (self.base or self.name).lower()

    def field_type(self, name: str) -> str | None:
        for fname, ftype in self.fields:
            if fname.lower() == name.lower():
                return ftype
        return None


class Handle:
    """A non-value datum (``socketdev``, ``iodev``, ``clock``, ``shapedata``): state kept by its owner."""

    __slots__ = ("type", "state")

    def __init__(self, type_name: str, state=None):
        self.type, self.state = type_name, state

    def __repr__(self) -> str:
        return f"<{self.type}>"


class Record:
    """A record value: ``type`` (a :class:`TypeInfo`) and ``fields`` (lower-case name -> value)."""

    __slots__ = ("type", "fields")

    def __init__(self, type_: TypeInfo, fields: dict):
        self.type, self.fields = type_, fields

    def __getitem__(self, name: str):
        return self.fields[name]

    def __eq__(self, other) -> bool:
        return isinstance(other, Record) and other.type.name == self.type.name and other.fields == self.fields

    def __repr__(self) -> str:
        return format_value(self)


class Array(list):
    """An array value (0-based inside, 1-based in RAPID); ``element`` is its element type."""

    __slots__ = ("element",)

    def __init__(self, items, element: TypeInfo):
        super().__init__(items)
        self.element = element


class Aggregate(tuple):
    """The value of ``[a, b, ...]`` before it is given a type."""


def _record(name: str, *fields: str) -> TypeInfo:
    return TypeInfo(name, "record", fields=tuple(tuple(f.split(":")) for f in fields))


NUM_TYPES = frozenset({"num", "dnum"})
SIGNAL_TYPES = frozenset({"signaldi", "signaldo", "signalgi", "signalgo", "signalai", "signalao"})

#: The data types RAPID provides that the interpreter knows (lower-case name -> TypeInfo).
TYPES: dict[str, TypeInfo] = {t.name.lower(): t for t in [
    TypeInfo("num", "atomic"), TypeInfo("dnum", "atomic"), TypeInfo("bool", "atomic"), TypeInfo("string", "atomic"),
    *[TypeInfo(alias, "atomic", base="num") for alias in ("errnum", "intnum", "byte", "socketstatus", "iounit_state", "btnres")],
    _record("pos", "x:num", "y:num", "z:num"),
    _record("orient", "q1:num", "q2:num", "q3:num", "q4:num"),
    _record("pose", "trans:pos", "rot:orient"),
    _record("confdata", "cf1:num", "cf4:num", "cf6:num", "cfx:num"),
    _record("robjoint", *(f"rax_{i}:num" for i in range(1, 7))),
    _record("extjoint", *(f"eax_{c}:num" for c in "abcdef")),
    _record("jointtarget", "robax:robjoint", "extax:extjoint"),
    _record("robtarget", "trans:pos", "rot:orient", "robconf:confdata", "extax:extjoint"),
    _record("loaddata", "mass:num", "cog:pos", "aom:orient", "ix:num", "iy:num", "iz:num"),
    _record("tooldata", "robhold:bool", "tframe:pose", "tload:loaddata"),
    _record("wobjdata", "robhold:bool", "ufprog:bool", "ufmec:string", "uframe:pose", "oframe:pose"),
    _record("speeddata", "v_tcp:num", "v_ori:num", "v_leax:num", "v_reax:num"),
    _record("zonedata", "finep:bool", "pzone_tcp:num", "pzone_ori:num", "pzone_eax:num", "zone_ori:num",
            "zone_leax:num", "zone_reax:num"),
    _record("wztemporary", "wz:num"), _record("wzstationary", "wz:num"),
    *[TypeInfo(name, "handle") for name in ("socketdev", "iodev", "clock", "shapedata")],
    *[TypeInfo(name, "handle") for name in sorted(SIGNAL_TYPES)],
]}


def type_info(name: str, records: dict | None = None) -> TypeInfo | None:
    """The type called ``name`` (the program's own records first), or None."""
    key = name.lower()
    if records and key in records:
        return records[key]
    return TYPES.get(key)


def _known_type(name: str, records: dict | None) -> TypeInfo:
    """:func:`type_info` of a record field's type, which the program must know."""
    t = type_info(name, records)
    if t is None:
        raise RapidFatalError(f"unknown data type {name!r}")
    return t


def _types_of(records):
    return lambda name: type_info(name, records)


def default_value(t: TypeInfo, records: dict | None = None, dims: tuple = ()):
    """The value a fresh variable of type ``t`` holds (0, FALSE, "", records of those, new handles)."""
    if dims:
        return Array([default_value(t, records, dims[1:]) for _ in range(int(dims[0]))],
                     t if len(dims) == 1 else TypeInfo(t.name, "array"))
    if t.kind == "record":
        return Record(t, {name.lower(): default_value(_known_type(ftype, records), records) for name, ftype in t.fields})
    if t.kind == "handle":
        return Handle(t.name)
    return {"num": 0.0, "dnum": 0.0, "bool": False, "string": ""}[t.key]


@overload
def copy_value(value: Record) -> Record: ...
@overload
def copy_value(value: Array) -> Array: ...
@overload
def copy_value(value: _V) -> _V: ...
def copy_value(value: Any):
    """A deep copy of a record or array (atomic values and handles are shared)."""
    if isinstance(value, Record):
        return Record(value.type, {k: copy_value(v) for k, v in value.fields.items()})
    if isinstance(value, Array):
        return Array([copy_value(v) for v in value], value.element)
    return value


def compatible(target: TypeInfo | None, source: TypeInfo | None) -> bool:
    """Whether a value of static type ``source`` may be stored where ``target`` is declared (None: not known)."""
    if target is None or source is None:
        return True
    if target.key in NUM_TYPES and source.key in NUM_TYPES:
        return True
    return target.key == source.key


def coerce(value: Any, t: TypeInfo, records: dict | None = None, what: str = "value"):
    """``value`` as type ``t``: num rounded to float32, aggregates made records or arrays, records copied.

    Raises
    ------
    RapidFatalError
        The value is not of that type (aggregates of the wrong length included).
    RapidRuntimeError
        ``ERR_STRTOOLNG`` for a string over 80 characters, ``ERR_OVERFLOW`` for a num out of range.
    """
    key = t.key
    if key in ("num", "dnum"):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise RapidFatalError(f"{what}: expected a {t.name}, got {describe(value)}")
        return to_num(value) if key == "num" else float(value)
    if key == "bool":
        if not isinstance(value, bool):
            raise RapidFatalError(f"{what}: expected a bool, got {describe(value)}")
        return value
    if key == "string":
        if not isinstance(value, str):
            raise RapidFatalError(f"{what}: expected a string, got {describe(value)}")
        if len(value) > MAX_STRING:
            raise RapidRuntimeError("ERR_STRTOOLNG", f"{what}: {len(value)} characters (a string holds {MAX_STRING})")
        return value
    if t.kind == "record":
        return _coerce_record(value, t, records, what)
    if t.kind == "handle":
        if not isinstance(value, Handle) or value.type.lower() != t.name.lower():
            raise RapidFatalError(f"{what}: expected a {t.name}, got {describe(value)}")
        return value
    raise RapidFatalError(f"{what}: cannot store a value of type {t.name}")


def _coerce_record(value, t: TypeInfo, records, what: str) -> Record:
    if isinstance(value, Record):
        if value.type.name.lower() != t.name.lower():
            raise RapidFatalError(f"{what}: expected a {t.name}, got a {value.type.name}")
        return copy_value(value)
    if isinstance(value, Aggregate):
        if len(value) != len(t.fields):
            raise RapidFatalError(f"{what}: a {t.name} has {len(t.fields)} components, the aggregate {len(value)}")
        return Record(t, {name.lower(): coerce(v, _known_type(ftype, records), records, f"{what}.{name}")
                          for (name, ftype), v in zip(t.fields, value)})
    raise RapidFatalError(f"{what}: expected a {t.name}, got {describe(value)}")


def coerce_array(value: Any, element: TypeInfo, dims: tuple, records=None, what: str = "value") -> Array:
    """``value`` (an array or an aggregate) as an array of ``dims`` elements of type ``element``."""
    if not isinstance(value, (Array, Aggregate, list)) or len(value) != int(dims[0]):
        raise RapidFatalError(f"{what}: expected an array of {int(dims[0])} {element.name}")
    if len(dims) == 1:
        return Array([coerce(v, element, records, what) for v in value], element)
    return Array([coerce_array(v, element, dims[1:], records, what) for v in value], TypeInfo(element.name, "array"))


def describe(value: Any) -> str:
    """A short name of what ``value`` is, for messages."""
    if isinstance(value, bool):
        return "a bool"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, Record):
        return f"a {value.type.name}"
    if isinstance(value, Aggregate):
        return f"an aggregate of {len(value)}"
    if isinstance(value, Array):
        return "an array"
    if isinstance(value, Handle):
        return f"a {value.type}"
    return type(value).__name__


def format_num(value: float) -> str:
    """A num the way ``ValToStr`` and ``TPWrite \\Num`` write it: up to 6 significant digits."""
    if value == int(value) and abs(value) < 1e9:
        return str(int(value))
    text = f"{value:.6g}"
    return text.replace("e+", "E+").replace("e-", "E-")


def format_value(value: Any, number=None, other=repr) -> str:
    """``ValToStr`` of any value: ``[1,2,3]``, ``"text"``, ``TRUE``.

    ``number(float) -> str`` writes a num (default :func:`format_num`, ValToStr's 6 significant
    digits); ``other(value) -> str`` is called for a value that is none of RAPID's data (it may raise).
    """
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, (int, float)):
        return (number or format_num)(float(value))
    if isinstance(value, str):
        return '"' + value.replace('"', '""') + '"'
    if isinstance(value, Record):
        return "[" + ",".join(format_value(v, number, other) for v in value.fields.values()) + "]"
    if isinstance(value, (Array, Aggregate, list, tuple)):
        return "[" + ",".join(format_value(v, number, other) for v in value) + "]"
    return other(value)


def aggregate(value: Any):
    """Nested Python lists as nested :class:`Aggregate` literals (what a parsed ``[...]`` gives)."""
    return Aggregate(aggregate(v) for v in value) if isinstance(value, list) else value


class _Predefined:
    """Predefined data (``tool0``, ``wobj0``, ``fine``, ``v100``, ``STR_DIGIT`` ...): name -> (type, value)."""

    def __init__(self):
        self.table: dict = {}

    def add(self, name: str, type_name: str, value) -> None:
        t = TYPES[type_name]
        self.table[name.lower()] = (t, coerce(aggregate(value), t))


def _predefined() -> dict:
    data = _Predefined()
    ident = [[0, 0, 0], [1, 0, 0, 0]]
    data.add("tool0", "tooldata", [True, ident, [0.001, [0, 0, 0.001], [1, 0, 0, 0], 0, 0, 0]])
    data.add("wobj0", "wobjdata", [False, True, "", ident, ident])
    data.add("load0", "loaddata", [0, [0, 0, 0], [1, 0, 0, 0], 0, 0, 0])
    data.add("fine", "zonedata", [True, 0, 0, 0, 0, 0, 0])
    for size, (tcp, ori) in {0: (0.3, 0.3), 1: (1, 1), 5: (5, 8), 10: (10, 15), 15: (15, 23), 20: (20, 30),
                             30: (30, 45), 40: (40, 60), 50: (50, 75), 60: (60, 90), 80: (80, 120),
                             100: (100, 150), 150: (150, 225), 200: (200, 300)}.items():
        data.add(f"z{size}", "zonedata", [False, tcp, ori, ori, ori / 10, ori, ori / 10])
    for speed in (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 1500, 2000, 2500,
                  3000, 4000, 5000, 6000, 7000):
        data.add(f"v{speed}", "speeddata", [speed, 500, 5000, 1000])
    data.add("vmax", "speeddata", [7000, 500, 5000, 1000])
    data.add("STR_DIGIT", "string", "0123456789")
    data.add("STR_UPPER", "string", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")
    data.add("STR_LOWER", "string", "abcdefghijklmnopqrstuvwxyz")
    data.add("STR_WHITE", "string", " \t\n\r\x0b\x0c")
    data.add("WAIT_MAX", "num", 8388608)
    data.add("stEmpty", "string", "")
    data.add("pi", "num", 3.1415926535897931)
    for i, name in enumerate(("SOCKET_CREATED", "SOCKET_CONNECTED", "SOCKET_BOUND", "SOCKET_LISTENING",
                              "SOCKET_CLOSED"), 1):
        data.add(name, "socketstatus", i)
    return data.table


#: Predefined data of RAPID that programs may read (lower-case name -> (TypeInfo, value)).
PREDEFINED = _predefined()
