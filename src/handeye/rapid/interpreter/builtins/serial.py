"""Serial channels: Open, Close, ReadStr, WriteStrBin, Write, ClearIOBuff.

An ``iodev`` holds the serial binding's handle. ``ReadStr`` reads up to the line end (LF, not
returned), at most 80 characters; ``\\Time`` defaults to 60 s (``WAIT_MAX``: for ever) and a
timeout raises ``ERR_DEV_MAXTIME``. Files (``HOME:``) are not supported.
"""

from __future__ import annotations

from ..errors import RapidFatalError, RapidRuntimeError
from ..values import format_value
from . import builtin
from .system import seconds

_DEFAULT_TIME_S = 60.0


def _line(task):
    return task.bindings.need("serial", "serial channels")


def _handle(device, what: str):
    if device.state is None:
        raise RapidRuntimeError("ERR_FILEACC", f"{what}: the channel is not open (Open first)")
    return device.state


@builtin("Open", "Object:string, IODevice:iodev, \\Read, \\Write, \\Append, \\Bin")
def _open(task, a):
    name, device, *_modes, binary = a
    if device.state is not None:
        raise RapidRuntimeError("ERR_FILEOPEN", f"Open {name}: the iodev is already open")
    device.state = _line(task).open(task, name, bool(binary))


@builtin("Close", "IODevice:iodev")
def _close(task, a):
    device = a[0]
    if device.state is not None:
        _line(task).close(device.state)
        device.state = None


@builtin("ReadStr", "IODevice:iodev, \\Delim:string, \\RemoveCR, \\DiscardHeaders, \\Time:num", returns="string")
def _readstr(task, a):
    device, delimiter, remove_cr, _headers, timeout = a
    if delimiter is not None:
        raise RapidFatalError("ReadStr \\Delim is not supported by the interpreter")
    data = _line(task).read_line(task, _handle(device, "ReadStr"), seconds(timeout, "ReadStr \\Time",
                                                                           _DEFAULT_TIME_S))
    text = data.decode("latin-1")
    return text[:-1] if remove_cr and text.endswith("\r") else text


@builtin("WriteStrBin", "IODevice:iodev, Str:string")
def _writestrbin(task, a):
    _line(task).write(task, _handle(a[0], "WriteStrBin"), a[1].encode("latin-1"))


@builtin("Write", "IODevice:iodev, String:string, \\Num:num, \\Bool:bool, \\Pos:pos, \\Orient:orient, \\NoNewLine")
def _write(task, a):
    device, text, *values, no_newline = a
    extra = "".join(format_value(v) for v in values if v is not None)
    _line(task).write(task, _handle(device, "Write"), (text + extra + ("" if no_newline else "\n")).encode("latin-1"))


@builtin("ClearIOBuff", "IODevice:iodev")
def _clear(task, a):
    _line(task).clear(_handle(a[0], "ClearIOBuff"))
