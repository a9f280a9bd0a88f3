"""The mock controller's network: real TCP sockets for the RAPID program, with faults and counters.

:class:`MockSockets` is the interpreter's :class:`~handeye.rapid.interpreter.net.TcpSockets` with
the mock's address (the program binds ``GetSysInfo(\\LanIp)`` or any address; it listens on the
mock's host and port) and the fault switches of :class:`~handeye.mocks.controller.faults.Faults`:

- ``silent``: what the PC sends is read and thrown away (a hung controller);
- ``drop_next`` / ``drop_after``: the connection is closed when a request line arrives, before the
  program sees it;
- ``delay_s``: every reply leaves that late; ``garbage_next``: a reply is replaced by garbage.

It counts what a test may ask: ``requests`` (request lines received), ``connections`` (accepted
connections the program served), ``refused_clients`` (accepted and closed unread: another
address), ``takeovers`` (a served connection closed by the program for one accepted after its last
quiet receive slice),
``idle_closes`` (the program closed a connection after a receive slice without data, nobody new
having come).
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

from ...rapid import RapidRuntimeError
from ...rapid import TcpSockets
from .faults import Faults

if TYPE_CHECKING:
    from ...rapid import Task

__all__ = ["MockSockets"]


class MockSockets(TcpSockets):
    """Sockets of the mock controller (see the module docstring).

    Parameters
    ----------
    faults : Faults
    host : str
        Where every listener binds (the mock's address).
    port : int
        Where the listener binds (0: a free port, kept for the program's later binds).
    """

    def __init__(self, faults: Faults, host: str, port: int):
        super().__init__()
        self.faults, self.host, self.port = faults, host, port
        self.listening_event = threading.Event()
        self.listening = lambda handle: self.listening_event.set()
        self.requests = self.connections = self.refused_clients = self.takeovers = self.idle_closes = 0
        self._accepts = 0

    @property
    def actual_port(self) -> int:
        return self.bound[-1][1] if self.bound else self.port

    def where(self, address: str, port: int) -> tuple[str, int]:
        return self.host, (self.bound[-1][1] if self.bound and self.port == 0 else self.port)

    # ------------------------------------------------------------------ hooks
    def accepted(self, handle) -> None:
        self._accepts += 1

    def receive(self, task: Task, handle, max_bytes: int, timeout: float | None, exact: bool = False) -> bytes:
        if not handle.info.get("served"):
            handle.info["served"] = True
            self.connections += 1
        handle.info["quiet"] = None
        try:
            return super().receive(task, handle, max_bytes, timeout, exact)
        except RapidRuntimeError as err:
            if err.name == "ERR_SOCK_TIMEOUT":
                handle.info["quiet"] = self._accepts
            raise

    def arrived(self, handle, data: bytes) -> bytes | None:
        faults = self.faults
        lines = data.count(b"\n")
        if faults.silent:
            self.requests += lines
            faults.note("silent")
            return b""
        for _ in range(lines):
            self.requests += 1
            if faults.should_drop():
                return None
        return data

    def sending(self, task: Task, handle, data: bytes) -> bytes | None:
        faults = self.faults
        if faults.delay_s > 0:
            task.idle(faults.delay_s)
        if faults.take("garbage_next"):
            faults.note("garbage")
            return faults.garbage
        return data

    def closing(self, handle) -> None:
        quiet = handle.info.get("quiet")
        if handle.peer and not handle.info.get("served"):
            self.refused_clients += 1
        elif quiet is not None and quiet == self._accepts:
            self.idle_closes += 1
        elif quiet is not None:  # a connection accepted since its last quiet slice replaces it
            self.takeovers += 1
