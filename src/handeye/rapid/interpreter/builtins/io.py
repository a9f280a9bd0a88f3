"""I/O signals: SetDO, SetGO, SetAO, Set, Reset, DInput, DOutput, GInput, GOutput, GInputDnum,
GOutputDnum, AInput, AOutput, WaitDI, WaitDO.

Signals live in the controller's I/O configuration; the program names them and the I/O binding
reads and writes them. A group signal takes a whole number within its width (``ERR_GO_LIM``).
"""

from __future__ import annotations

from ..errors import RapidFatalError, RapidRuntimeError
from ..values import to_num
from . import builtin
from .system import wait_for

#: How often WaitDI/WaitDO look at the signal (they react to a change on a controller).
_SIGNAL_POLL_S = 0.01


def _io(task):
    return task.bindings.need("io", "I/O signals")


def _digital(value, name: str) -> int:
    if value not in (0, 1):
        raise RapidFatalError(f"{name}: a digital signal takes 0 or 1; got {value:g}")
    return int(value)


@builtin("SetDO", "\\SDelay:num, \\Sync, Signal:signaldo, Value:num")
def _setdo(task, a):
    _io(task).write(a[2], _digital(a[3], a[2]))


@builtin("Set", "Signal:signaldo")
def _set(task, a):
    _io(task).write(a[0], 1)


@builtin("Reset", "Signal:signaldo")
def _reset(task, a):
    _io(task).write(a[0], 0)


@builtin("SetGO", "Signal:signalgo, Value:dnum")
def _setgo(task, a):
    io, (name, value) = _io(task), a
    high = 2 ** io.bits(name) - 1
    if value != int(value) or not 0 <= value <= high:
        raise RapidRuntimeError("ERR_GO_LIM", f"SetGO {name}, {value:g}: outside 0..{high}")
    io.write(name, int(value))


@builtin("SetAO", "Signal:signalao, Value:num")
def _setao(task, a):
    _io(task).write(a[0], float(a[1]))


def _reader(name: str, signal_type: str, dnum: bool = False):
    def read(task, a):
        value = float(_io(task).read(a[0]))
        return value if dnum else to_num(value)
    builtin(name, f"Signal:{signal_type}", returns="dnum" if dnum else "num")(read)


for _name, _type in (("DInput", "signaldi"), ("DOutput", "signaldo"), ("GInput", "signalgi"),
                     ("GOutput", "signalgo"), ("AInput", "signalai"), ("AOutput", "signalao")):
    _reader(_name, _type)
_reader("GInputDnum", "signalgi", dnum=True)
_reader("GOutputDnum", "signalgo", dnum=True)


def _wait_digital(what: str):
    def wait(task, a):
        name, value, max_time, flag = a
        wanted = _digital(value, name)
        io = _io(task)
        wait_for(task, lambda: io.read(name) == wanted, max_time, flag, _SIGNAL_POLL_S, what)
    return wait


builtin("WaitDI", "Signal:signaldi, Value:num, \\MaxTime:num, \\ref TimeFlag:bool")(_wait_digital("WaitDI"))
builtin("WaitDO", "Signal:signaldo, Value:num, \\MaxTime:num, \\ref TimeFlag:bool")(_wait_digital("WaitDO"))
