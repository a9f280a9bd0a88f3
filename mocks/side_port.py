"""A side port of the standalone mock controller: a small TCP service beside the controller's own link
(the rehearsal camera, :mod:`~handeye.mocks.cell`; the FlexPendant, :mod:`~handeye.mocks.controller.pendant`).

A threading TCP server whose handler reaches the service as ``self.server.service``, served in a
daemon thread of its own from :meth:`SidePort.start` until :meth:`SidePort.stop`.
"""

from __future__ import annotations

import socketserver
import threading

__all__ = ["SidePort"]


class _Server(socketserver.ThreadingTCPServer):
    daemon_threads = True
    allow_reuse_address = True
    block_on_close = True


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

    def __init__(self, handler, host: str, port: int, name: str):
        self._server = _Server((host, port), handler, bind_and_activate=True)
        self._server.service = self
        self.host, self.port = self._server.server_address[:2]
        self._name = name
        self._thread: threading.Thread | None = None

    def start(self):
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
