"""The live view of a capture (``handeye capture --view``): a page the operator watches while capturing.

:func:`live_view` opens it for a connected station: the hub (``hub``: takes the capture's events,
``station.capture.events``, and keeps the page's state, ``state``; encodes the images, ``frames``),
the live frames while the robot moves (``feed``) and the HTTP server with its token (``server``).
The page (``page.html``) is plain JavaScript: one ``EventSource``, inline SVG drawings; nothing is
loaded from anywhere but the server, so it works offline at the station.
"""

from __future__ import annotations

import ipaddress
from contextlib import contextmanager

__all__ = ["LiveView", "live_view", "loopback"]


def loopback(host: str) -> bool:
    """True for an address only this machine reaches (127.0.0.0/8, ::1, ``localhost``)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class LiveView:
    """A running live view: ``observer`` (give it to the capture), ``url``, ``hub``, ``server``, ``feed``."""

    def __init__(self, hub, server, feed):
        self.hub, self.server, self.feed = hub, server, feed

    @property
    def url(self) -> str:
        return self.server.url

    @property
    def observer(self):
        return self.hub.observe

    def finish(self, text: str, ok: bool = True) -> None:
        """The run is over: the page says ``text`` (what the command said last) in place of the next step."""
        from ..capture.events import CaptureEnded

        self.hub.observe(CaptureEnded(text, ok))

    def close(self) -> None:
        self.feed.close()
        self.hub.close()
        self.server.close()


@contextmanager
def live_view(config, link, session_dir, host: str = "127.0.0.1", port: int = 0, progress=lambda message: None):
    """Serve the live view of a capture on ``link`` (its camera is shared with the page's live feed:
    ``link.camera`` becomes a ``feed.SharedCamera``) and yield the :class:`LiveView`; stopped on exit.

    Raises
    ------
    OSError
        The address cannot be bound (the port taken, a host not of this machine).
    """
    from .feed import LiveFeed, SharedCamera
    from .hub import ViewHub
    from .server import ViewServer

    hub = ViewHub(config, link.stereo_model)
    server = ViewServer(hub, host, port, session_dir)
    if not isinstance(link.camera, SharedCamera):
        link.camera = SharedCamera(link.camera)
    link.camera.on_grab, link.camera.on_frame = hub.capture_grabs, hub.capture_frame
    view = LiveView(hub.start(), server.start(), LiveFeed(hub, link.camera).start())
    if not loopback(host):
        progress(f"warning: the live view listens on {host}, not only on this machine: anyone who can reach it and "
                 "has the URL (its token) sees the camera and the session"
                 + ("; open it with this machine's address in place of the wildcard" if host in ("0.0.0.0", "::") else ""))
    progress(f"live view: {view.url}")
    try:
        yield view
    finally:
        link.camera.on_grab = link.camera.on_frame = None
        view.close()
