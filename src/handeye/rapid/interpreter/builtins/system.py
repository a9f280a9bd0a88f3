"""Program flow and the controller itself: TPWrite, Stop, waits, clocks, timer interrupts,
GetSysInfo, ErrWrite, Incr/Decr/Add/Clear, CDate/CTime."""

from __future__ import annotations

from typing import Any, TYPE_CHECKING
import time

import numpy as np

from ..errors import RapidFatalError, RapidRuntimeError
from ..frames import StopSignal
from ..values import format_value, to_num
from . import builtin

if TYPE_CHECKING:
    from ..runtime import Task

__all__ = ["wait_for", "WAIT_MAX"]

#: ``WAIT_MAX``: a time argument this large means "for ever".
WAIT_MAX = 8388608.0


def seconds(value: Any, what: str, default: float | None = None) -> float | None:
    """A time argument in seconds (None: for ever)."""
    if value is None:
        return default
    if value < 0:
        raise RapidFatalError(f"{what}: a time must be >= 0; got {value:g}")
    return None if value >= WAIT_MAX else float(value)


def wait_for(task: Task, condition, max_time, flag, poll: float, what: str) -> None:
    """Poll ``condition`` until it holds; after ``max_time`` set ``flag`` TRUE or raise ERR_WAIT_MAXTIME."""
    limit = seconds(max_time, f"{what} \\MaxTime")
    met = task.poll_until(condition, limit, poll)
    if flag is not None:
        flag.set(not met)
    elif not met:
        raise RapidRuntimeError("ERR_WAIT_MAXTIME", f"{what}: {max_time:g} s passed")


@builtin("TPWrite", "String:string, \\Num:num, \\Bool:bool, \\Pos:pos, \\Orient:orient, \\Dnum:dnum")
def _tpwrite(task, a):
    text, *values = a
    extra = [format_value(v) for v in values if v is not None]
    if len(extra) > 1:
        raise RapidFatalError("TPWrite takes one of \\Num, \\Bool, \\Pos, \\Orient, \\Dnum")
    task.write_pendant(text + "".join(extra))


@builtin("TPErase")
def _tperase(task, a):
    task.pendant.clear()


@builtin("ErrWrite", "\\W, Header:string, Reason:string, \\RL2:string, \\RL3:string, \\RL4:string")
def _errwrite(task, a):
    warning, header, *reasons = a
    kind = "warning" if warning else "error"
    task.write_pendant(f"event log {kind}: {header}: " + " ".join(r for r in reasons if r))


@builtin("Stop", "\\NoRegain, \\AllMoveTasks")
def _stop(task, a):
    pendant = task.bindings.flexpendant
    if a[0] and pendant is not None:  # Stop \NoRegain with an operator: wait for Start, then go on
        pendant.stop_here(task)
        return
    raise StopSignal()


@builtin("WaitTime", "\\InPos, Time:num")
def _waittime(task, a):
    task.idle(seconds(a[1], "WaitTime"))


@builtin("WaitUntil", "\\InPos, lazy Cond:bool, \\MaxTime:num, \\ref TimeFlag:bool, \\PollRate:num")
def _waituntil(task, a):
    _, condition, max_time, flag, poll = a
    poll = 0.1 if poll is None else poll  # the manual's default polling rate
    if poll < float(np.float32(0.01)):  # a num holds 0.01 as its float32 value, a hair below 0.01
        raise RapidFatalError(f"WaitUntil \\PollRate must be >= 0.01 s; got {poll:g}")
    wait_for(task, condition, max_time, flag, poll, "WaitUntil")


def _clock(handle) -> dict:
    if handle.state is None:
        handle.state = {"running": False, "start": 0.0, "elapsed": 0.0}
    return handle.state


@builtin("ClkReset", "Clock:clock")
def _clkreset(task, a):
    _clock(a[0]).update(running=False, elapsed=0.0)


@builtin("ClkStart", "Clock:clock")
def _clkstart(task, a):
    clock = _clock(a[0])
    if not clock["running"]:
        clock.update(running=True, start=task.clock())


@builtin("ClkStop", "Clock:clock")
def _clkstop(task, a):
    clock = _clock(a[0])
    if clock["running"]:
        clock.update(running=False, elapsed=clock["elapsed"] + task.clock() - clock["start"])


@builtin("ClkRead", "Clock:clock, \\HighRes", returns="num")
def _clkread(task, a):
    clock = _clock(a[0])
    value = clock["elapsed"] + (task.clock() - clock["start"] if clock["running"] else 0.0)
    return value if a[1] else round(value, 3)


@builtin("IDelete", "ref Interrupt:intnum")
def _idelete(task, a):
    task.delete_interrupt(a[0])


@builtin("ITimer", "\\Single, \\SingleSafe, Time:num, Interrupt:intnum")
def _itimer(task, a):
    single, safe, period, number = a
    if period < 0.01:
        raise RapidFatalError(f"ITimer: the time must be >= 0.01 s; got {period:g}")
    if not task.interrupt(number):
        raise RapidRuntimeError("ERR_INT_NOTVAL", "ITimer: the interrupt is not connected (CONNECT ... WITH first)")
    task.order_timer(int(number), float(period), bool(single or safe))


@builtin("ISleep", "Interrupt:intnum")
def _isleep(task, a):
    task.sleep_interrupt(int(a[0]), True)


@builtin("IWatch", "Interrupt:intnum")
def _iwatch(task, a):
    task.sleep_interrupt(int(a[0]), False)


@builtin("GetSysInfo", "\\SerialNo, \\SWVersion, \\RobotType, \\CtrlId, \\LanIp, \\CtrlLang, \\SystemName",
         returns="string")
def _getsysinfo(task, a):
    keys = ("SerialNo", "SWVersion", "RobotType", "CtrlId", "LanIp", "CtrlLang", "SystemName")
    chosen = [k for k, on in zip(keys, a) if on]
    if len(chosen) != 1:
        raise RapidFatalError("GetSysInfo takes exactly one switch")
    return str(task.bindings.sysinfo.get(chosen[0], ""))


@builtin("Incr", "ref Name:num")
def _incr(task, a):
    a[0].set(to_num(a[0].get() + 1))


@builtin("Decr", "ref Name:num")
def _decr(task, a):
    a[0].set(to_num(a[0].get() - 1))


@builtin("Add", "ref Name:num, AddValue:num")
def _add(task, a):
    a[0].set(to_num(a[0].get() + a[1]))


@builtin("Clear", "ref Name:num")
def _clear(task, a):
    a[0].set(0.0)


@builtin("CDate", returns="string")
def _cdate(task, a):
    return time.strftime("%Y-%m-%d")


@builtin("CTime", returns="string")
def _ctime(task, a):
    return time.strftime("%H:%M:%S")
