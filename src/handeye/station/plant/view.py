"""The fleet page: the live view's server (``station.view.server``: stdlib HTTP, a per-run token,
server-sent events) with a hub of its own that publishes the fleet table.

:class:`FleetHub` answers the server's ``wait`` / ``client`` like the capture's hub: its ``state`` is
the fleet table's JSON (``station.plant.fleet``), recomputed at once when the subscriber keeps an
event (``poke``) and every ``refresh_s`` otherwise (a cell that stops reporting is flagged without an
event). The page (``fleet_page.html``) is plain JavaScript and inline SVG: nothing loaded from elsewhere.
"""

from __future__ import annotations

import json
import threading
from importlib import resources

from ..view.server import ViewServer
from .fleet import fleet_table

__all__ = ["FleetHub", "FleetServer"]


class FleetHub:
    """See the module docstring; ``history`` a ``store.History``, ``fleet`` the ``FleetSettings``."""

    def __init__(self, history, fleet, refresh_s: float = 5.0):
        self.history, self.fleet, self.refresh_s = history, fleet, refresh_s
        self._changed = threading.Condition()
        self._poked = threading.Event()
        self.state_json, self.state_version = "{}", 0
        self.clients = 0
        self.finished = self.closed = False
        self._thread = threading.Thread(target=self._run, name="fleet-hub", daemon=True)

    def start(self) -> FleetHub:
        self._publish()
        self._thread.start()
        return self

    def poke(self) -> None:
        """The history changed (the subscriber's ``on_change``)."""
        self._poked.set()

    def _publish(self) -> None:
        text = json.dumps(fleet_table(self.history, self.fleet))
        with self._changed:
            self.state_json, self.state_version = text, self.state_version + 1
            self._changed.notify_all()

    def _run(self) -> None:
        while not self.closed:
            self._poked.wait(self.refresh_s)
            self._poked.clear()
            if not self.closed:
                self._publish()

    def wait(self, state_version: int, frame_version: int, timeout_s: float) -> tuple:
        """As ``ViewHub.wait``: ``(finished, state_version, state_json, frame_version, frame_json)``; no frames."""
        with self._changed:
            self._changed.wait_for(lambda: self.finished or self.state_version != state_version, timeout_s)
            return self.finished, self.state_version, self.state_json, frame_version, ""

    def client(self, delta: int) -> None:
        with self._changed:
            self.clients += delta

    def close(self) -> None:
        self.closed = self.finished = True
        self._poked.set()
        with self._changed:
            self._changed.notify_all()


class FleetServer(ViewServer):
    """The live view's server, serving the fleet page."""

    def __init__(self, hub: FleetHub, host: str = "127.0.0.1", port: int = 0):
        super().__init__(hub, host, port, None)

    def page(self) -> bytes:
        if self._page is None:
            self._page = resources.files(__name__.rpartition(".")[0]).joinpath("fleet_page.html").read_bytes()
        return self._page
