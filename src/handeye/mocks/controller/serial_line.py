"""A serial line behind a TCP endpoint, for the RAPID program's serial channel (``Open "sio1:"``).

The PC reaches the line with pyserial's ``socket://HOST:PORT`` URL. A line has no connections: the
newest TCP connection owns the wire at once (the older one is closed) and the bytes already in the
controller's receive buffer stay there, as on a wire. The program's ``ReadStr``, ``WriteStrBin``,
``ClearIOBuff`` work on that buffer and on the current owner. Faults and counters as the socket
mock's (:mod:`~handeye.mocks.controller.network`): ``requests``, ``connections``, ``takeovers``, and
``idle_resets`` (``ClearIOBuff`` of a line that had received something since the last one: the
program's idle reset).
"""

from __future__ import annotations

import socket
from typing import TYPE_CHECKING

from ...rapid import RapidRuntimeError, SerialBinding
from ...rapid import MAX_STRING
from .faults import Faults

if TYPE_CHECKING:
    from ...rapid import Task

__all__ = ["SerialLine"]


class _Channel:
    """The program's open channel (an ``iodev``)."""

    def __init__(self, line: SerialLine, name: str):
        self.line, self.name, self.open = line, name, True

    def close(self) -> None:
        self.open = False


class SerialLine(SerialBinding):
    """The wire and the program's channel on it (see the module docstring).

    Parameters
    ----------
    faults : Faults
    host, port : str, int
        Where the TCP endpoint listens (port 0: a free one).
    """

    def __init__(self, faults: Faults, host: str = "127.0.0.1", port: int = 0):
        self.faults, self.host = faults, host
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.listener.bind((host, port))
            self.listener.listen(4)
        except OSError:
            self.listener.close()
            raise
        self.listener.setblocking(False)
        self.port = self.listener.getsockname()[1]
        self.owner: socket.socket | None = None
        self.rx = bytearray()
        self.heard = False  # bytes arrived since the last ClearIOBuff
        self.channel: _Channel | None = None  # the program's channel, once it opened one
        self.requests = self.connections = self.takeovers = self.idle_resets = 0

    def close_all(self) -> None:
        self._drop_owner()
        self.listener.close()

    # ------------------------------------------------------------------ the wire
    def _drop_owner(self) -> None:
        if self.owner is not None:
            self.owner.close()
            self.owner = None

    def _pump(self) -> None:
        """Take a new connection over the wire, and move what the owner sent into the buffer."""
        while True:
            try:
                conn, _ = self.listener.accept()
            except (BlockingIOError, InterruptedError, OSError):
                break
            conn.setblocking(False)
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if self.owner is not None:
                self.takeovers += 1
                self._drop_owner()
            self.owner = conn
            self.connections += 1
        while self.owner is not None:
            try:
                chunk = self.owner.recv(4096)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                chunk = b""
            if not chunk:
                self._drop_owner()
                return
            self._arrived(chunk)

    def _arrived(self, chunk: bytes) -> None:
        faults, lines = self.faults, chunk.count(b"\n")
        if faults.silent:
            self.requests += lines
            faults.note("silent")
            return
        for _ in range(lines):
            self.requests += 1
            if faults.should_drop():
                self._drop_owner()
                return
        self.rx += chunk
        self.heard = True

    def _readable(self) -> list:
        return [self.listener] + ([self.owner] if self.owner is not None else [])

    # ------------------------------------------------------------------ the binding
    def open(self, task: Task, name: str, binary: bool) -> _Channel:
        channel = _Channel(self, name)
        task.resources.append(channel)
        self.channel = channel
        return channel

    def read_line(self, task: Task, handle: _Channel, timeout: float | None) -> bytes:
        end = None if timeout is None else task.clock() + timeout
        while True:
            self._pump()
            newline = self.rx.find(b"\n")
            if 0 <= newline <= MAX_STRING or len(self.rx) >= MAX_STRING:
                size = newline if 0 <= newline <= MAX_STRING else MAX_STRING
                data = bytes(self.rx[:size])
                del self.rx[:size + (1 if size == newline else 0)]
                return data
            left = None if end is None else end - task.clock()
            if left is not None and left <= 0:
                raise RapidRuntimeError("ERR_DEV_MAXTIME", "ReadStr: no line end in time")
            task.idle(left, self._readable())

    def write(self, task: Task, handle: _Channel, data: bytes) -> None:
        faults = self.faults
        if faults.delay_s > 0:
            task.idle(faults.delay_s)
        if faults.take("garbage_next"):
            faults.note("garbage")
            data = faults.garbage
        self._pump()
        if self.owner is None:
            return  # nobody on the line: the bytes go nowhere
        try:
            self.owner.setblocking(True)
            self.owner.settimeout(5.0)
            self.owner.sendall(data)
        except OSError:
            self._drop_owner()
        finally:
            if self.owner is not None:
                self.owner.setblocking(False)

    def clear(self, handle: _Channel) -> None:
        self._pump()
        if self.heard:
            self.idle_resets += 1
        self.rx.clear()
        self.heard = False

    def close(self, handle: _Channel) -> None:
        handle.close()
