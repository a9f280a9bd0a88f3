"""The live view's HTTP server: the page and its server-sent events, behind a per-run token.

A stdlib ``ThreadingHTTPServer`` (one thread per request, daemon threads). Every request must carry
the run's random token (``?token=...``): without it, or with another, the answer is 403 and
nothing else. Paths:

- ``/`` the page (``page.html``, package data; nothing loaded from elsewhere);
- ``/events`` ``text/event-stream``: ``state`` events (the page's JSON) and ``frame`` events (the
  latest images as JPEG data URLs), each sent when newer than what this client has, and a comment
  line every 10 s to keep the stream open;
- ``/preview.png`` the planned capture's preview (``SESSION/preview.png``), 404 when there is none.
"""

from __future__ import annotations

import hmac
import secrets
import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

__all__ = ["ViewServer"]

_KEEPALIVE_S = 10.0


def _handler(server: "ViewServer"):
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, format, *args):  # noqa: A002 (the base class's name): quiet
            pass

        def _send(self, code: int, body: bytes, kind: str) -> None:
            self.send_response(code)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def do_GET(self):  # noqa: N802 (http.server's name)
            url = urlsplit(self.path)
            token = parse_qs(url.query).get("token", [""])[0]
            if not hmac.compare_digest(token.encode(), server.token.encode()):
                self._send(403, b"forbidden: the live view's URL carries a token; use the one capture printed\n",
                           "text/plain; charset=utf-8")
                return
            if url.path in ("/", "/index.html"):
                self._send(200, server.page(), "text/html; charset=utf-8")
            elif url.path == "/events":
                self._events()
            elif url.path == "/preview.png" and (preview := server.preview_path()) is not None:
                self._send(200, preview.read_bytes(), "image/png")
            else:
                self._send(404, b"not found\n", "text/plain; charset=utf-8")

        def _events(self) -> None:
            hub = server.hub
            self.send_response(200)
            self.send_header("Content-Type", "text/event-stream")
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            hub.client(+1)
            seen_state = seen_frame = -1
            try:
                while not server.stopping.is_set():
                    finished, state_v, state, frame_v, frame = hub.wait(seen_state, seen_frame, _KEEPALIVE_S)
                    out = []
                    if state_v != seen_state:
                        out.append(f"event: state\ndata: {state}\n\n")
                    if frame_v != seen_frame and frame:
                        out.append(f"event: frame\ndata: {frame}\n\n")
                    seen_state, seen_frame = state_v, frame_v
                    self.wfile.write(("".join(out) or ": keep-alive\n\n").encode("utf-8"))
                    self.wfile.flush()
                    if finished:  # what the hub published last has been sent
                        break
            except (BrokenPipeError, ConnectionResetError, OSError):
                pass
            finally:
                hub.client(-1)

    return Handler


def _server_class(host: str) -> type:
    """``ThreadingHTTPServer`` with the address family of ``host``: IPv6 for an IPv6 address (``::1``, ``::``)
    or a name that resolves only to one, IPv4 otherwise (OSError: a name that does not resolve)."""
    try:
        families = {info[0] for info in socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)}
    except socket.gaierror as exc:
        raise OSError(f"no address for {host!r} ({exc.strerror})") from None
    if socket.AF_INET in families or socket.AF_INET6 not in families:
        return ThreadingHTTPServer
    return type("ThreadingHTTPServerV6", (ThreadingHTTPServer,), {"address_family": socket.AF_INET6})


class ViewServer:
    """The page of ``hub`` served on ``host:port`` (0: a free port), behind a random token.

    Attributes
    ----------
    url : str
        ``http://HOST:PORT/?token=...`` (the one to open).
    """

    def __init__(self, hub, host: str = "127.0.0.1", port: int = 0, session_dir=None):
        self.hub, self.session_dir = hub, None if session_dir is None else Path(session_dir)
        self.token = secrets.token_urlsafe(18)
        self.stopping = threading.Event()
        self._page = None
        self.httpd = _server_class(host)((host, port), _handler(self))
        self.httpd.daemon_threads = True
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="view-server", daemon=True)

    @property
    def port(self) -> int:
        return int(self.httpd.server_address[1])

    @property
    def url(self) -> str:
        host = self.httpd.server_address[0]
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{self.port}/?token={self.token}"

    def page(self) -> bytes:
        if self._page is None:
            self._page = resources.files(__name__.rpartition(".")[0]).joinpath("page.html").read_bytes()
        return self._page

    def preview_path(self) -> Path | None:
        path = None if self.session_dir is None else self.session_dir / "preview.png"
        return path if path is not None and path.is_file() else None

    def start(self) -> ViewServer:
        self._thread.start()
        return self

    def close(self, linger_s: float = 0.5) -> None:
        """Stop serving, after ``linger_s`` for the open pages to receive the last state (the hub closed first)."""
        deadline = time.monotonic() + linger_s
        while self.hub.clients > 0 and time.monotonic() < deadline:
            time.sleep(0.02)
        self.stopping.set()
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join(timeout=5.0)
