"""The fleet's subscription: every cell's events and retained states, into the history.

A persistent session (``clean_session`` false, a fixed client id, QoS 1): while the fleet view is
away, or the broker restarts (with its persistence on), the broker keeps the events for it and
delivers them, in each cell's order, when it is back. paho reconnects by itself (0.2 to 2 s).
Each message's cell is its topic (``<cell>/handeye/event``); a payload naming another cell, without
a sequence number, or not JSON is counted in ``rejected`` and not kept.
"""

from __future__ import annotations

import json
import os
import threading

from .publisher import EVENT_TOPIC, STATE_TOPIC

__all__ = ["FleetSubscriber"]


class FleetSubscriber:
    """Subscribe to ``fleet.cells`` on ``fleet.mqtt`` and keep what arrives in ``history`` (``store.History``);
    ``on_change()`` is called after each kept event or state."""

    def __init__(self, fleet, history, on_change=lambda: None, persistent: bool = True):
        self.fleet, self.history, self.on_change, self.persistent = fleet, history, on_change, persistent
        self.rejected = self.duplicates = 0
        self.connected = threading.Event()
        self.client = None

    def start(self, timeout_s: float = 10.0) -> FleetSubscriber:
        """Connect (PlantLinkError when the broker cannot be reached within ``timeout_s``) and subscribe."""
        from .client import connect, make_client

        mqtt = self.fleet.mqtt
        if self.persistent:  # the one fleet view the broker keeps events for
            client_id, clean = mqtt.client_id or "handeye-fleet", False
        else:  # a look (--json) beside it: what the history holds, and what comes meanwhile
            client_id, clean = f"{mqtt.client_id or 'handeye-fleet'}-look-{os.getpid()}", True
        self.client = make_client(mqtt, client_id, clean_session=clean)
        self.client.reconnect_delay_set(0.2, 2.0)  # pyright: ignore[reportArgumentType] (paho's hint says int; the back-off takes float seconds)
        self.client.on_message = self._message
        self.client.on_disconnect = lambda *a, **k: self.connected.clear()
        connect(self.client, mqtt, timeout_s)
        self.client.on_connect = self._subscribe  # after connect's own answer: again at every reconnection
        self._subscribe(self.client, None, None, 0)
        return self

    def _subscribe(self, client, userdata, flags, reason_code, properties=None) -> None:
        cells = self.fleet.cells
        client.subscribe([(f"{cells}/{EVENT_TOPIC}", 1), (f"{cells}/{STATE_TOPIC}", 1)])
        self.connected.set()

    def _message(self, client, userdata, message) -> None:
        topic = message.topic
        for suffix, kind in ((f"/{EVENT_TOPIC}", "event"), (f"/{STATE_TOPIC}", "state")):
            if topic.endswith(suffix):
                cell = topic[: -len(suffix)]
                break
        else:
            self.rejected += 1
            return
        try:
            event = json.loads(message.payload)
            ok = isinstance(event, dict) and event.get("topic_prefix") == cell and isinstance(event.get("seq"), int)
        except ValueError:
            ok = False
        if not ok:
            self.rejected += 1
            return
        if kind == "state":
            self.history.set_state(cell, event)
        elif not self.history.add(cell, event):
            self.duplicates += 1
            return
        self.on_change()

    def stop(self) -> None:
        if self.client is not None:
            self.client.disconnect()
            self.client.loop_stop()
