"""A side port of the standalone mock controller: a small TCP service beside the controller's own link
(the rehearsal camera, :mod:`~handeye.mocks.cell`; the FlexPendant, :mod:`~handeye.mocks.controller.pendant`).

A threading TCP server whose handler reaches the service as ``self.server.service``, served in a
daemon thread of its own from :meth:`SidePort.start` until :meth:`SidePort.stop`. Requests are lines:
:func:`read_line` reads one to its newline and refuses a line longer than the port takes as a whole (its
tail is never read as a request of its own); a client that hangs up mid-request ends its connection
quietly, never with a traceback on the mock's stderr.
"""

from __future__ import annotations

import enum
import logging
import socket
import socketserver
import sys
import threading
from typing import TYPE_CHECKING, Final, Literal, Protocol

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = ["SidePort", "TOO_LONG", "read_line"]

log = logging.getLogger(__name__)

class _TooLong(enum.Enum):
    """The type of :data:`TOO_LONG`: a single value, so that ``line is TOO_LONG`` tells a type checker which it is."""

    TOO_LONG = "too long"


#: What :func:`read_line` returns for a line longer than its limit (the whole line read and dropped).
TOO_LONG: Final = _TooLong.TOO_LONG


class LineStream(Protocol):
    """A binary stream read by lines (a connection's ``rfile``)."""

    def readline(self, size: int = -1, /) -> bytes: ...

#: A client's hang-up, seen by the server as one of these (nothing to report).
_HANG_UPS = (ConnectionError, TimeoutError)


def read_line(stream: LineStream, limit: int) -> bytes | Literal[_TooLong.TOO_LONG]:
    """The next request line of ``stream`` (bytes with its newline; ``b""`` at the end of the stream), or
    :data:`TOO_LONG` when it has more than ``limit`` bytes before its newline: the rest of that line is
    read and dropped (at most ``limit`` bytes held at a time), so its tail is never taken as a request.

    Parameters
    ----------
    stream : binary file
        The connection's ``rfile``.
    limit : int
        Longest line taken, in bytes, its newline not counted.
    """
    line = stream.readline(limit + 1)
    if len(line) <= limit or line.endswith(b"\n"):
        return line
    while True:  # over long: drop up to the newline (or the end of the stream)
        rest = stream.readline(limit + 1)
        if not rest or rest.endswith(b"\n"):
            return TOO_LONG


class _Server(socketserver.ThreadingTCPServer):
    daemon_threads = True
    allow_reuse_address = True
    block_on_close = True
    service: SidePort  # set by SidePort.__init__: what the handlers serve

    def handle_error(self, request: socket.socket, client_address: tuple[str, int]) -> None:
        """A client that hung up early ends its connection without a word; anything else is the mock's
        fault, logged with its traceback."""
        if isinstance(sys.exc_info()[1], _HANG_UPS):
            log.debug("side port: %s hung up", client_address)
            return
        super().handle_error(request, client_address)


class SidePort:
    """The server and its thread (see the module docstring).

    Parameters
    ----------
    handler : type of socketserver.BaseRequestHandler
        Serves one connection; ``self.server.service`` is this object.
    host, port : str, int
        Where it listens (port 0: a free one); ``host`` and ``port`` hold the address it got.
    name : str
        The thread's name, followed by the port.
    """

    def __init__(self, handler: type[socketserver.BaseRequestHandler], host: str, port: int, name: str):
        self._server = _Server((host, port), handler, bind_and_activate=True)
        self._server.service = self
        self.host, self.port = self._server.server_address[:2]
        self._name = name
        self._thread: threading.Thread | None = None

    def start(self) -> Self:
        """Serve in a daemon thread; returns self."""
        self._thread = threading.Thread(target=self._server.serve_forever, kwargs={"poll_interval": 0.1},
                                        name=f"{self._name}-{self.port}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close the listening socket."""
        if self._thread is not None:
            self._server.shutdown()
            self._thread.join(10)
            self._thread = None
        self._server.server_close()
