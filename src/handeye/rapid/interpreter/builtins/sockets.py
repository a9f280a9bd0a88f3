"""Socket Messaging (PC Interface option): SocketCreate, SocketBind, SocketListen, SocketAccept,
SocketConnect, SocketSend, SocketReceive, SocketClose, SocketGetStatus.

A ``socketdev`` holds the socket binding's handle. ``\\Time`` defaults to 60 s (``WAIT_MAX``: for
ever); a timeout raises ``ERR_SOCK_TIMEOUT``, a connection the peer closed ``ERR_SOCK_CLOSED``.
``SocketReceive \\Str`` takes what has arrived, at most 80 bytes; ``SocketClose`` of a closed
socket does nothing.
"""

from __future__ import annotations

from ..errors import RapidFatalError, RapidRuntimeError
from ..values import MAX_STRING, PREDEFINED
from . import builtin
from .system import seconds

_DEFAULT_TIME_S = 60.0
_STATUS = {name: PREDEFINED[f"socket_{name}"][1] for name in ("created", "connected", "bound", "listening", "closed")}


def _net(task):
    return task.bindings.need("sockets", "sockets")


def _handle(device, what: str):
    if device.state is None:
        raise RapidRuntimeError("ERR_SOCK_CLOSED", f"{what}: the socket was not created (SocketCreate first)")
    return device.state


@builtin("SocketCreate", "Socket:socketdev, \\UDP")
def _create(task, a):
    device, udp = a
    if udp:
        raise RapidFatalError("SocketCreate \\UDP is not supported by the interpreter")
    if device.state is not None:
        _net(task).close(device.state)
    device.state = _net(task).create(task)


@builtin("SocketBind", "Socket:socketdev, LocalAddress:string, LocalPort:num")
def _bind(task, a):
    _net(task).bind(_handle(a[0], "SocketBind"), a[1], int(a[2]))


@builtin("SocketListen", "Socket:socketdev")
def _listen(task, a):
    _net(task).listen(_handle(a[0], "SocketListen"))


@builtin("SocketAccept", "Socket:socketdev, ClientSocket:socketdev, \\ref ClientAddress:string, \\Time:num")
def _accept(task, a):
    server, client, address, timeout = a
    net = _net(task)
    if client.state is not None and net.status(client.state) != "closed":
        raise RapidFatalError("SocketAccept: the client socketdev is still in use (SocketClose it first)")
    handle, peer = net.accept(task, _handle(server, "SocketAccept"), seconds(timeout, "SocketAccept \\Time",
                                                                             _DEFAULT_TIME_S))
    client.state = handle
    if address is not None:
        address.set(peer)


@builtin("SocketConnect", "Socket:socketdev, Address:string, Port:num, \\Time:num")
def _connect(task, a):
    device, address, port, timeout = a
    _net(task).connect(task, _handle(device, "SocketConnect"), address, int(port),
                       seconds(timeout, "SocketConnect \\Time", _DEFAULT_TIME_S))


@builtin("SocketSend", "Socket:socketdev, \\Str:string, \\NoOfBytes:num")
def _send(task, a):
    device, text, count = a
    if text is None:
        raise RapidFatalError("SocketSend: only \\Str is supported by the interpreter")
    data = text.encode("latin-1")
    if count is not None:
        data = data[:int(count)]
    _net(task).send(task, _handle(device, "SocketSend"), data)


@builtin("SocketReceive", "Socket:socketdev, \\ref Str:string, \\ReadNoOfBytes:num, \\ref NoRecBytes:num, "
                          "\\Time:num")
def _receive(task, a):
    device, text, wanted, received, timeout = a
    if text is None:
        raise RapidFatalError("SocketReceive: only \\Str is supported by the interpreter")
    size = MAX_STRING if wanted is None else int(wanted)
    if not 1 <= size <= MAX_STRING:
        raise RapidFatalError(f"SocketReceive \\ReadNoOfBytes must be 1..{MAX_STRING}; got {wanted:g}")
    data = _net(task).receive(task, _handle(device, "SocketReceive"), size,
                              seconds(timeout, "SocketReceive \\Time", _DEFAULT_TIME_S), exact=wanted is not None)
    text.set(data.decode("latin-1"))
    if received is not None:
        received.set(float(len(data)))


@builtin("SocketClose", "Socket:socketdev")
def _close(task, a):
    device = a[0]
    if device.state is not None:
        _net(task).close(device.state)


@builtin("SocketGetStatus", "Socket:socketdev", returns="socketstatus")
def _status(task, a):
    device = a[0]
    if device.state is None:
        return _STATUS["closed"]
    return _STATUS[_net(task).status(device.state)]
