"""RAPID's operators on values: arithmetic, string concatenation, comparison, logic, pos/orient algebra.

Each ``OPERATORS[op]`` takes two values and returns the result, raising the error a controller
raises: ``ERR_DIVZERO``, ``ERR_STRTOOLNG`` for a concatenation over 80 characters, and a fatal error
for operand types RAPID does not combine (the compiler refuses most of those at load time already).
"""

from __future__ import annotations

from typing import Any, TypeGuard
import math

from .errors import RapidFatalError, RapidRuntimeError
from .values import MAX_STRING, Record, TYPES, describe

__all__ = ["OPERATORS", "negate", "logical_not", "is_number", "equal"]


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _pos(values) -> Record:
    return Record(TYPES["pos"], {"x": values[0], "y": values[1], "z": values[2]})


def _xyz(r: Record) -> tuple:
    f = r.fields
    return f["x"], f["y"], f["z"]


def _is(v: object, name: str) -> TypeGuard[Record]:
    return isinstance(v, Record) and v.type.name == name


def _bad(op: str, a, b):
    return RapidFatalError(f"operator {op} cannot combine {describe(a)} and {describe(b)}")


def add(a: Any, b: Any) -> Any:
    if is_number(a) and is_number(b):
        return a + b
    if isinstance(a, str) and isinstance(b, str):
        if len(a) + len(b) > MAX_STRING:
            raise RapidRuntimeError("ERR_STRTOOLNG", f"{len(a) + len(b)} characters (a string holds {MAX_STRING})")
        return a + b
    if _is(a, "pos") and _is(b, "pos"):
        return _pos([x + y for x, y in zip(_xyz(a), _xyz(b))])
    raise _bad("+", a, b)


def sub(a: Any, b: Any) -> Any:
    if is_number(a) and is_number(b):
        return a - b
    if _is(a, "pos") and _is(b, "pos"):
        return _pos([x - y for x, y in zip(_xyz(a), _xyz(b))])
    raise _bad("-", a, b)


def mul(a: Any, b: Any) -> Any:
    if is_number(a) and is_number(b):
        return a * b
    if is_number(a) and _is(b, "pos"):
        return _pos([a * v for v in _xyz(b)])
    if _is(a, "pos") and is_number(b):
        return _pos([b * v for v in _xyz(a)])
    if _is(a, "orient") and _is(b, "orient"):
        w1, x1, y1, z1 = a.fields.values()
        w2, x2, y2, z2 = b.fields.values()
        q = (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
             w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)
        return Record(TYPES["orient"], dict(zip(("q1", "q2", "q3", "q4"), q)))
    raise _bad("*", a, b)


def div(a: Any, b: Any) -> Any:
    if is_number(a) and is_number(b):
        if b == 0:
            raise RapidRuntimeError("ERR_DIVZERO", "division by zero")
        return a / b
    if _is(a, "pos") and is_number(b):
        if b == 0:
            raise RapidRuntimeError("ERR_DIVZERO", "division by zero")
        return _pos([v / b for v in _xyz(a)])
    raise _bad("/", a, b)


def _integers(op: str, a, b) -> tuple[int, int]:
    if not (is_number(a) and is_number(b)):
        raise _bad(op, a, b)
    if a != int(a) or b != int(b):
        raise RapidFatalError(f"{op} needs integer operands; got {a:g} {op} {b:g}")
    if b == 0:
        raise RapidRuntimeError("ERR_DIVZERO", f"{op} by zero")
    return int(a), int(b)


def int_div(a: Any, b: Any) -> Any:
    x, y = _integers("DIV", a, b)
    return float(abs(x) // abs(y) * (1 if (x >= 0) == (y >= 0) else -1))


def mod(a: Any, b: Any) -> Any:
    x, y = _integers("MOD", a, b)
    return float(math.fmod(x, y))


def equal(a: Any, b: Any) -> bool:
    if is_number(a) and is_number(b):
        return a == b
    if type(a) is not type(b) and not (isinstance(a, Record) and isinstance(b, Record)):
        raise _bad("=", a, b)
    return a == b


def _ordered(op: str, test):
    def compare(a, b):
        if not (is_number(a) and is_number(b)):
            raise _bad(op, a, b)
        return test(a, b)
    return compare


def _logic(op: str, test):
    def combine(a, b):
        if not (isinstance(a, bool) and isinstance(b, bool)):
            raise _bad(op, a, b)
        return test(a, b)
    return combine


OPERATORS = {
    "+": add, "-": sub, "*": mul, "/": div, "DIV": int_div, "MOD": mod,
    "=": equal, "<>": lambda a, b: not equal(a, b),
    "<": _ordered("<", lambda a, b: a < b), ">": _ordered(">", lambda a, b: a > b),
    "<=": _ordered("<=", lambda a, b: a <= b), ">=": _ordered(">=", lambda a, b: a >= b),
    "AND": _logic("AND", lambda a, b: a and b), "OR": _logic("OR", lambda a, b: a or b),
    "XOR": _logic("XOR", lambda a, b: a != b),
}


def negate(v: Any) -> Any:
    if is_number(v):
        return -v
    if _is(v, "pos"):
        return _pos([-x for x in _xyz(v)])
    raise RapidFatalError(f"unary - cannot take {describe(v)}")


def logical_not(v: Any) -> bool:
    if not isinstance(v, bool):
        raise RapidFatalError(f"NOT needs a bool, got {describe(v)}")
    return not v
