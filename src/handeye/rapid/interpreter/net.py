"""Real TCP sockets for a RAPID program: the socket binding of a controller on this machine.

:class:`TcpSockets` runs ``SocketCreate`` ... ``SocketClose`` on the operating system's sockets,
non-blocking, waiting through ``task.idle`` (interrupts run, a stop request ends the wait). The
address and port a program binds may be mapped (a program written for the controller's LAN address
and port 1025 listens where the test wants it). Subclasses watch the traffic through four hooks
(:meth:`accepted`, :meth:`arrived`, :meth:`sending`, :meth:`closing`); the mock controller injects its
faults and counts there.
"""

from __future__ import annotations

from typing import Any, TYPE_CHECKING
import errno
import socket

from .bindings import SocketBinding
from .errors import RapidFatalError, RapidRuntimeError

if TYPE_CHECKING:
    from .runtime import Task

__all__ = ["TcpSockets", "TcpHandle"]


class TcpHandle:
    """One RAPID socket: the OS socket, what was received and not yet taken, its state."""

    __slots__ = ("sock", "state", "rx", "peer", "owner", "info")

    def __init__(self, owner):
        self.sock: socket.socket | None = None
        self.state = "created"
        self.rx = bytearray()
        self.peer = ""
        self.owner = owner
        self.info: dict = {}

    def close(self) -> None:
        if self.state != "closed":
            self.owner._close(self)

    def os_socket(self) -> socket.socket:
        """The OS socket, set from SocketBind (or accept) until the handle is closed."""
        if self.sock is None:
            raise RapidRuntimeError("ERR_SOCK_CLOSED", f"the socket is {self.state}")
        return self.sock

    def fileno(self) -> int:
        return self.os_socket().fileno()


class TcpSockets(SocketBinding):
    """Sockets of the operating system.

    Parameters
    ----------
    addresses : dict, optional
        Address a program binds -> address to bind instead (``{"192.168.125.1": "127.0.0.1"}``).
    ports : dict, optional
        Port a program binds -> port to bind instead (0: any free port; see :attr:`bound`).
    """

    def __init__(self, addresses: dict | None = None, ports: dict | None = None):
        self.addresses = dict(addresses or {})
        self.ports = dict(ports or {})
        #: ``(address, port)`` of every listener bound, as the operating system reports it.
        self.bound: list[tuple] = []
        self.listening = None  # callable(handle) when a listener starts (the mock waits for it)

    # ------------------------------------------------------------------ hooks
    def where(self, address: str, port: int) -> tuple[str, int]:
        """The OS address and port a ``SocketBind address, port`` binds (the maps above)."""
        return self.addresses.get(address, address), self.ports.get(port, port)

    def accepted(self, handle: TcpHandle) -> None:
        """A connection was accepted into ``handle``."""

    def arrived(self, handle: TcpHandle, data: bytes) -> bytes | None:
        """Bytes read from the peer; returns what the program gets (None: the connection is dropped)."""
        return data

    def sending(self, task: Task, handle: TcpHandle, data: bytes) -> bytes | None:
        """Bytes the program sends; returns what goes out (None: the connection is dropped instead)."""
        return data

    def closing(self, handle: TcpHandle) -> None:
        """The program closes ``handle``."""

    # ------------------------------------------------------------------ the binding
    def create(self, task: Task) -> TcpHandle:
        handle = TcpHandle(self)
        task.resources.append(handle)
        return handle

    def bind(self, handle: TcpHandle, address: str, port: int) -> None:
        if handle.state != "created":
            raise RapidFatalError(f"SocketBind: the socket is {handle.state}")
        host, actual = self.where(address, port)
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, actual))
        except OSError as exc:
            sock.close()
            if exc.errno == errno.EADDRINUSE:
                raise RapidRuntimeError("ERR_SOCK_ADDR_INUSE", f"{host}:{actual} is in use") from None
            raise RapidFatalError(f"SocketBind {address}:{port}: {exc.strerror or exc}") from None
        handle.sock, handle.state = sock, "bound"
        self.bound.append(sock.getsockname()[:2])

    def listen(self, handle: TcpHandle) -> None:
        if handle.state != "bound":
            raise RapidFatalError(f"SocketListen: the socket is {handle.state} (SocketBind first)")
        handle.os_socket().listen(8)
        handle.os_socket().setblocking(False)
        handle.state = "listening"
        if self.listening is not None:
            self.listening(handle)

    def accept(self, task: Task, handle: TcpHandle, timeout: float | None) -> tuple[TcpHandle, str]:
        if handle.state != "listening":
            raise RapidFatalError(f"SocketAccept: the socket is {handle.state} (SocketListen first)")
        end = None if timeout is None else task.clock() + timeout
        while True:
            try:
                conn, addr = handle.os_socket().accept()
            except (BlockingIOError, InterruptedError):
                left = None if end is None else end - task.clock()
                if left is not None and left <= 0:
                    raise RapidRuntimeError("ERR_SOCK_TIMEOUT", "SocketAccept: no connection") from None
                task.idle(left, [handle.sock])
                continue
            client = TcpHandle(self)
            task.resources.append(client)
            conn.setblocking(False)
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            client.sock, client.state, client.peer = conn, "connected", addr[0]
            self.accepted(client)
            return client, addr[0]

    def connect(self, task: Task, handle: Any, address: str, port: int, timeout: float | None) -> None:
        raise RapidFatalError("SocketConnect is not supported by this controller's socket binding")

    def receive(self, task: Task, handle: TcpHandle, max_bytes: int, timeout: float | None, exact: bool = False) -> bytes:
        if handle.state != "connected" and not handle.rx:
            raise RapidRuntimeError("ERR_SOCK_CLOSED", "SocketReceive: the socket is not connected")
        end = None if timeout is None else task.clock() + timeout
        while len(handle.rx) < (max_bytes if exact else 1):
            if handle.state != "connected":
                raise RapidRuntimeError("ERR_SOCK_CLOSED", "SocketReceive: the connection was closed")
            if not self._read(handle):
                left = None if end is None else end - task.clock()
                if left is not None and left <= 0:
                    raise RapidRuntimeError("ERR_SOCK_TIMEOUT", "SocketReceive: no data")
                task.idle(left, [handle.sock])
        data = bytes(handle.rx[:max_bytes])
        del handle.rx[:max_bytes]
        return data

    def _read(self, handle: TcpHandle) -> bool:
        """Move what the OS holds into ``handle.rx``; True if anything came (or the peer closed)."""
        try:
            chunk = handle.os_socket().recv(4096)
        except (BlockingIOError, InterruptedError):
            return False
        except OSError:
            chunk = b""
        if not chunk:
            self._close(handle, by_peer=True)
            return True
        data = self.arrived(handle, chunk)
        if data is None:
            self._close(handle, by_peer=True)
            handle.rx.clear()
            return True
        handle.rx += data
        return True

    def send(self, task: Task, handle: TcpHandle, data: bytes) -> None:
        if handle.state != "connected":
            raise RapidRuntimeError("ERR_SOCK_CLOSED", "SocketSend: the socket is not connected")
        out = self.sending(task, handle, data)
        if out is None:
            self._close(handle, by_peer=True)
            raise RapidRuntimeError("ERR_SOCK_CLOSED", "SocketSend: the connection was closed")
        try:
            sock = handle.os_socket()
            sock.setblocking(True)
            sock.settimeout(5.0)
            sock.sendall(out)
        except OSError:
            self._close(handle, by_peer=True)
            raise RapidRuntimeError("ERR_SOCK_CLOSED", "SocketSend: the connection was closed") from None
        finally:
            if handle.sock is not None:
                handle.sock.setblocking(False)

    def close(self, handle: TcpHandle) -> None:
        if handle.state != "closed":
            self.closing(handle)
            self._close(handle)

    def _close(self, handle: TcpHandle, by_peer: bool = False) -> None:
        if handle.sock is not None:
            try:
                handle.sock.close()
            except OSError:  # pragma: no cover
                pass
        handle.sock = None
        handle.state = "closed"
        handle.info["closed_by_peer"] = by_peer

    def status(self, handle: TcpHandle) -> str:
        return handle.state
