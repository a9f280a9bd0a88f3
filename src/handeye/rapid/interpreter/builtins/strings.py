"""String functions: StrLen, StrFind, StrMatch, StrMemb, StrPart, StrToVal, NumToStr, ValToStr.

Character positions are 1-based. A position outside the string (``ChPos`` not in 1..StrLen, a part
that reaches past the end) is an execution error, as the manual says ("a runtime error is generated
if the position is outside the string"); the interpreter reads it strictly, so an empty string has
no valid position at all. ``StrFind`` and ``StrMatch`` return StrLen + 1 when nothing is found.
"""

from __future__ import annotations

from .. import syntax as S
from ..errors import RapidFatalError, RapidLoadError, RapidRuntimeError
from ..parser import parse_expression
from ..values import MAX_STRING, Aggregate, coerce, format_value
from . import builtin

__all__ = ["num_to_str", "str_to_val"]


def _position(text: str, position: float, what: str) -> int:
    if position != int(position) or not 1 <= position <= len(text):
        raise RapidFatalError(f"{what}: character position {position:g} outside the string (1..{len(text)})")
    return int(position)


@builtin("StrLen", "Str:string", returns="num")
def _strlen(task, a):
    return float(len(a[0]))


@builtin("StrFind", "Str:string, ChPos:num, Set:string, \\NotInSet", returns="num")
def _strfind(task, a):
    text, start, chars, not_in = a
    i = _position(text, start, "StrFind")
    for j in range(i - 1, len(text)):
        if (text[j] in chars) != not_in:
            return float(j + 1)
    return float(len(text) + 1)


@builtin("StrMatch", "Str:string, ChPos:num, Pattern:string", returns="num")
def _strmatch(task, a):
    text, start, pattern = a
    i = _position(text, start, "StrMatch")
    found = text.find(pattern, i - 1)
    return float(found + 1 if found >= 0 else len(text) + 1)


@builtin("StrMemb", "Str:string, ChPos:num, Set:string", returns="bool")
def _strmemb(task, a):
    text, position, chars = a
    return text[_position(text, position, "StrMemb") - 1] in chars


@builtin("StrPart", "Str:string, ChPos:num, Len:num", returns="string")
def _strpart(task, a):
    text, start, length = a
    i = _position(text, start, "StrPart")
    if length != int(length) or length < 0 or i + int(length) - 1 > len(text):
        raise RapidFatalError(f"StrPart: {length:g} characters from position {i} reach outside the string "
                              f"(length {len(text)})")
    return text[i - 1:i - 1 + int(length)]


def num_to_str(value: float, decimals: float, exponent: bool = False) -> str:
    """``NumToStr``: ``decimals`` after the point, trailing zeros (and a bare point) removed, no ``-0``."""
    if decimals != int(decimals) or not 0 <= decimals <= 9:
        raise RapidFatalError(f"NumToStr: Dec must be a whole number 0..9; got {decimals:g}")
    d = int(decimals)
    if exponent:
        mantissa, _, power = f"{value:.{d}E}".partition("E")
        return f"{mantissa}E{int(power):+03d}"
    text = f"{value:.{d}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


@builtin("NumToStr", "Val:num, Dec:num, \\Exp", returns="string")
def _numtostr(task, a):
    return num_to_str(a[0], a[1], a[2])


@builtin("DNumToStr", "Val:dnum, Dec:num, \\Exp", returns="string")
def _dnumtostr(task, a):
    return num_to_str(a[0], a[1], a[2])


@builtin("ValToStr", "Val:any", returns="string")
def _valtostr(task, a):
    text = format_value(a[0])
    if len(text) > MAX_STRING:
        text = text[:MAX_STRING]
    return text


def _literal(node):
    """The value of a literal expression (numbers, strings, bools, aggregates of them), else ValueError."""
    if isinstance(node, (S.Num, S.Str, S.Bool)):
        return node.value
    if isinstance(node, S.Unary) and node.op == "-" and isinstance(node.operand, S.Num):
        return -node.operand.value
    if isinstance(node, S.Aggregate):
        return Aggregate(_literal(item) for item in node.items)
    raise ValueError("not a literal")


def str_to_val(text: str, type_info, records=None):
    """``StrToVal``: the value ``text`` writes for ``type_info``, or None when it writes none."""
    try:
        value = _literal(parse_expression(text, "StrToVal"))
        return coerce(value, type_info, records, "StrToVal")
    except (RapidLoadError, RapidFatalError, RapidRuntimeError, ValueError, OverflowError):
        return None  # not a literal of that type, or out of its range (ERR_OVERFLOW, ERR_STRTOOLNG)


@builtin("StrToVal", "Str:string, ref Val:any", returns="bool")
def _strtoval(task, a):
    text, ref = a
    value = str_to_val(text, ref.type, task.program.records)
    if value is None:
        return False
    ref.set(value)
    return True
