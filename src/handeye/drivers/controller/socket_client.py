"""The ``socket`` back end: the line protocol over TCP to the RAPID socket server (PC Interface option)."""

from __future__ import annotations

import socket
from typing import Any

from .interface import Deadline, LinkDown
from .line_client import LineBuffer, LineController, LineTransport

__all__ = [
    "SocketController",
    "DEFAULT_PORT",
]

#: Default TCP port of the RAPID server module (any port above 1024 works on a controller).
DEFAULT_PORT = 1025


class _TcpTransport(LineTransport):
    def __init__(self, host: str, port: int, timeout_error, protocol_error):
        self.host, self.port = host, port
        self.sock: socket.socket | None = None
        self.buffer = LineBuffer(protocol_error)
        self.timeout_error = timeout_error

    def open(self, deadline: Deadline) -> None:
        try:
            sock = socket.create_connection((self.host, self.port), timeout=max(deadline.remaining(), 1e-3))
        except socket.timeout:
            raise LinkDown(f"connecting to {self.host}:{self.port} timed out") from None
        except OSError as exc:
            raise LinkDown(f"cannot connect to {self.host}:{self.port}: {exc.strerror or exc}") from None
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock = sock
        self.buffer.clear()

    @property
    def is_open(self) -> bool:
        return self.sock is not None

    def close(self) -> None:
        if self.sock is not None:
            sock, self.sock = self.sock, None
            try:
                sock.close()
            except OSError:
                pass

    def write(self, data: bytes, deadline: Deadline) -> None:
        if self.sock is None:
            raise LinkDown("not connected")
        try:
            self.sock.settimeout(max(deadline.remaining(), 1e-3))
            self.sock.sendall(data)
        except socket.timeout:
            raise self.timeout_error(f"sending to {self.host}:{self.port} timed out") from None
        except OSError as exc:
            raise LinkDown(f"sending failed: {exc.strerror or exc}") from None

    def read_line(self, deadline: Deadline) -> bytes:
        while True:
            line = self.buffer.take_line()
            if line is not None:
                return line
            left = deadline.remaining()
            if left <= 0 or self.sock is None:
                if self.sock is None:
                    raise LinkDown("not connected")
                raise self.timeout_error(self.buffer.timeout_text())
            try:
                self.sock.settimeout(left)
                chunk = self.sock.recv(4096)
            except socket.timeout:
                raise self.timeout_error(self.buffer.timeout_text()) from None
            except OSError as exc:
                raise LinkDown(f"receiving failed: {exc.strerror or exc}") from None
            if not chunk:
                raise LinkDown("the controller closed the connection")
            self.buffer.feed(chunk)


class SocketController(LineController):
    """The RAPID socket server over TCP.

    Parameters
    ----------
    host : str
        The controller's address (the RAPID module binds to it and accepts only this PC's address).
    port : int
        TCP port of the RAPID server module (default 1025).
    **options
        See :class:`~handeye.drivers.controller.interface.Controller` (timeout, retries, ...).
    """

    protocol = "socket"

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, **options: Any):
        from .errors import InvalidRequest

        if isinstance(port, bool) or not isinstance(port, int) or not 0 < port < 65536:
            raise InvalidRequest(f"TCP port must be an integer 1..65535; got {port!r}")
        self.host, self.port = str(host), int(port)
        super().__init__(**options)

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    def _make_transport(self) -> LineTransport:
        return _TcpTransport(self.host, self.port, self.timeout_error, self.protocol_error)
