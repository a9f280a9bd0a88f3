"""The FlexPendant's questions: TPReadFK (S4C+ and later) and UIMessageBox (RobotWare 6/7), answered by the
operator through the task's :class:`~handeye.rapid.interpreter.pendant.FlexPendant` binding."""

from __future__ import annotations

from ..errors import RapidFatalError, RapidRuntimeError
from ..values import to_num
from . import builtin
from .system import seconds


def _pendant(task, what: str):
    pendant = task.bindings.flexpendant
    if pendant is None:
        raise RapidFatalError(f"{what}: this controller has no pendant to answer it")
    return pendant


def _ask(task, what: str, text: str, keys: dict, max_time, flag) -> int | None:
    """The operator's key, or None after ``max_time`` (``flag`` set to ERR_TP_MAXTIME, else the error)."""
    if not keys:
        raise RapidFatalError(f"{what}: no answer offered (every key text is empty)")
    limit = seconds(max_time, f"{what} \\MaxTime")
    answer = _pendant(task, what).ask(task, text, keys, limit)
    if answer is not None:
        if flag is not None:
            flag.set(0.0)
        return answer
    if flag is not None:
        from ..errors import ERROR_NUMBERS

        flag.set(float(ERROR_NUMBERS["ERR_TP_MAXTIME"]))
        return None
    raise RapidRuntimeError("ERR_TP_MAXTIME", f"{what}: nobody answered within {max_time:g} s")


@builtin("TPReadFK", "ref TPAnswer:num, TPText:string, TPFK1:string, TPFK2:string, TPFK3:string, TPFK4:string, "
                     "TPFK5:string, \\MaxTime:num, \\ref BreakFlag:errnum")
def _tpreadfk(task, a):
    answer, text, *labels = a[:7]
    keys = {k: label for k, label in enumerate(labels, 1) if label}
    key = _ask(task, "TPReadFK", text, keys, a[7], a[8])
    if key is not None:
        answer.set(to_num(key))


@builtin("UIMessageBox", "\\Header:string, \\Message:string, \\MsgArray:any, \\Wrap, \\BtnArray:any, "
                         "\\DefaultBtn:num, \\MaxTime:num, \\ref BreakFlag:errnum", returns="num")
def _uimessagebox(task, a):
    header, message, lines, _wrap, buttons, default, max_time, flag = a
    if message is not None and lines is not None:
        raise RapidFatalError("UIMessageBox takes \\Message or \\MsgArray, not both")
    if buttons is None:
        raise RapidFatalError("UIMessageBox: give the buttons with \\BtnArray (the interpreter has no \\Buttons sets)")
    body = [message] if message is not None else [str(line) for line in (lines or ()) if str(line)]
    text = " / ".join(([header] if header else []) + body)
    keys = {k: str(label) for k, label in enumerate(buttons, 1) if str(label)}
    key = _ask(task, "UIMessageBox", text, keys, max_time, flag)
    return to_num(key if key is not None else (default or 0))
