"""Mock controllers of the line protocol: the generated HeSocket / HeSerial program, executed.

- :class:`SocketControllerServer`: the RAPID program's own socket server (``SocketCreate`` ...
  ``SocketAccept``) on real TCP sockets at the mock's address. Which PC it accepts, the idle timeout,
  the takeover, the write key: all of that is the program's (``HE_PC_ADDRESS``, ``HE_IDLE_TIMEOUT``
  ... as rendered), nothing of it is Python.
- :class:`SerialControllerServer`: the program's serial channel on a line that a TCP endpoint stands
  for (pyserial's ``socket://HOST:PORT``); the newest connection owns the wire.

Faults (:class:`~handeye.mocks.controller.faults.Faults`) act on the link, under the program: the
program never knows.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from ...rapid import RapidError
from ...rapid import Bindings
from .faults import Faults
from .network import MockSockets
from .serial_line import SerialLine
from .server import DEFAULT_IDLE_TIMEOUT_S, RapidControllerServer
from .sources import ControllerProgram

if TYPE_CHECKING:
    from ..robot import SimulatedRobot

__all__ = ["SocketControllerServer", "SerialControllerServer", "DEFAULT_IDLE_TIMEOUT_S"]

#: How long a started socket program may take to listen.
_LISTEN_TIMEOUT_S = 15.0


class SocketControllerServer(RapidControllerServer):
    """HeSocket on real TCP sockets (see the module docstring).

    Counters (from the traffic): ``requests``, ``connections``, ``refused_clients``, ``takeovers``,
    ``idle_closes``. ``allowed_client`` is the program's ``HE_PC_ADDRESS`` (information only: the
    program decides).
    """

    kind = "socket"

    def __init__(self, program: ControllerProgram, robot: SimulatedRobot, host: str = "127.0.0.1", port: int = 0,
                 faults: Faults | None = None, *, idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S,
                 write_key: str | None = None):
        super().__init__(program, robot, host, port, faults, idle_timeout_s=idle_timeout_s, write_key=write_key)
        self.net: MockSockets | None = None

    def _open_endpoint(self) -> Bindings:
        self.net = MockSockets(self.faults, self.host, self._requested_port)
        return Bindings(sockets=self.net, sysinfo={**Bindings().sysinfo, "LanIp": self.host})

    def _close_endpoint(self) -> None:
        pass  # the program's sockets close with its task

    def _sockets(self) -> MockSockets:
        if self.net is None:
            raise RapidError("mock socket controller: its endpoint is not open; call start() first")
        return self.net

    def _arming(self) -> None:
        self._sockets().listening_event.clear()

    def _wait_ready(self) -> None:
        """Return once the program listens; else say at once how it ended (or that main ran to its end
        without listening), or after ``_LISTEN_TIMEOUT_S`` that it does not listen."""
        end = time.monotonic() + _LISTEN_TIMEOUT_S
        net, runner = self._sockets(), self._live_runner()
        while not net.listening_event.wait(0.05):
            if runner.end_reason:
                why = f"{runner.end_reason} before it listened"
            elif runner.main_returns:
                why = "ran main to its end without listening (SocketCreate, SocketBind, SocketListen)"
            elif time.monotonic() > end:
                why = f"did not listen within {_LISTEN_TIMEOUT_S:g} s"
            else:
                continue
            raise RapidError(f"mock socket controller: the RAPID program {why}: "
                             f"{self.fix_hint(error=bool(runner.error))}")

    @property
    def link_open(self) -> bool | None:
        return self.net is not None and self.net.listening_event.is_set()

    @property
    def allowed_client(self) -> str | None:
        program = self.runner.program if self.runner else None
        datum = program.datum("HE_PC_ADDRESS", "HeSocket") if program is not None else None
        return None if datum is None else datum.box[0]

    @property
    def port(self) -> int:
        return self.net.actual_port if self.net is not None else self._requested_port

    def __getattr__(self, name: str):
        if name in ("requests", "connections", "refused_clients", "takeovers", "idle_closes"):
            net = self.__dict__.get("net")
            return 0 if net is None else getattr(net, name)
        raise AttributeError(name)

    def client_options(self) -> dict:
        return self._client_key({"host": self.host, "port": self.port, "idle_timeout": self.idle_timeout_s})


class SerialControllerServer(RapidControllerServer):
    """HeSerial on a line behind ``socket://host:port`` (see the module docstring).

    Counters: ``requests``, ``connections``, ``takeovers``, ``idle_resets``.
    """

    kind = "serial"

    def __init__(self, program: ControllerProgram, robot: SimulatedRobot, host: str = "127.0.0.1", port: int = 0,
                 faults: Faults | None = None, *, idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S,
                 write_key: str | None = None):
        super().__init__(program, robot, host, port, faults, idle_timeout_s=idle_timeout_s, write_key=write_key)
        self.line: SerialLine | None = None
        self._port = port

    def _open_endpoint(self) -> Bindings:
        self.line = SerialLine(self.faults, self.host, self._port)
        self._port = self.line.port  # a reload keeps the line
        return Bindings(serial=self.line)

    def _close_endpoint(self) -> None:
        if self.line is not None:
            self.line.close_all()

    @property
    def link_open(self) -> bool | None:
        return self.line is not None and self.line.channel is not None and self.line.channel.open

    @property
    def port(self) -> int:
        return self._port

    @property
    def url(self) -> str:
        return f"socket://{self.host}:{self.port}"

    def __getattr__(self, name: str):
        if name in ("requests", "connections", "takeovers", "idle_resets"):
            line = self.__dict__.get("line")
            return 0 if line is None else getattr(line, name)
        raise AttributeError(name)

    def client_options(self) -> dict:
        return self._client_key({"url": self.url, "idle_timeout": self.idle_timeout_s})

    def listening(self) -> str:
        return f": serial line on pyserial URL {self.url}"

    def client_flags(self) -> str:
        return f"--url {self.url}"
