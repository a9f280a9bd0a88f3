"""Sending the outbox to the broker: in order, QoS 1, within a time budget, then the retained state.

:func:`deliver` connects (TLS and credentials of ``plant.mqtt``), publishes every waiting event of the
outbox in sequence order on ``<topic_prefix>/handeye/event`` (QoS 1, not retained), removes each file
once the broker acknowledged it, and publishes the last one on ``<topic_prefix>/handeye/state``
(QoS 1, retained: what a subscriber sees first about the cell). It stops at the budget: what was not
acknowledged stays in the outbox and leaves, first, with the next command's events.
"""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass

__all__ = ["EVENT_TOPIC", "STATE_TOPIC", "Delivery", "Link", "deliver", "event_topic", "state_topic"]

EVENT_TOPIC, STATE_TOPIC = "handeye/event", "handeye/state"


def event_topic(prefix: str) -> str:
    return f"{prefix}/{EVENT_TOPIC}"


def state_topic(prefix: str) -> str:
    return f"{prefix}/{STATE_TOPIC}"


@dataclass
class Delivery:
    """What :func:`deliver` did: events acknowledged, events still waiting, the fault (one line) or None."""

    sent: int
    waiting: int
    fault: str | None = None


class Link:
    """The connection to the broker of ``plant``, opened in a thread of its own (importing paho, TLS and the
    broker's answer take longer than writing the event: the command does both at once); :meth:`client`
    waits for it."""

    def __init__(self, plant, budget_s: float):
        self.plant, self.deadline = plant, time.monotonic() + budget_s
        self._client, self.fault = None, None
        self._thread = threading.Thread(target=self._open, name="plant-link", daemon=True)

    def start(self) -> Link:
        self._thread.start()
        return self

    def _open(self) -> None:
        from .client import PlantLinkError, connect, make_client

        try:
            client = make_client(self.plant.mqtt, self.plant.mqtt.client_id or f"handeye-{self.plant.cell}-{os.getpid()}")
            connect(client, self.plant.mqtt, max(self.deadline - time.monotonic(), 0.05))
            self._client = client
        except PlantLinkError as exc:
            self.fault = str(exc)
        except Exception as exc:  # noqa: BLE001 (publishing never fails a command)
            self.fault = f"{type(exc).__name__}: {exc}"

    def client(self):
        """The connected client, or None (``fault`` says why) once the budget is spent."""
        self._thread.join(max(self.deadline - time.monotonic(), 0.0))
        if self._thread.is_alive():
            self.fault = f"broker {self.plant.mqtt.host}:{self.plant.mqtt.effective_port} did not answer in time"
            return None
        return self._client

    def close(self) -> None:
        self._thread.join(max(self.deadline - time.monotonic(), 0.0))
        if self._client is not None:
            self._client.disconnect()
            self._client.loop_stop()
            self._client = None


def deliver(plant, outbox, budget_s: float | None = None, link: Link | None = None) -> Delivery:
    """Send ``outbox`` (``Outbox``) to the broker of ``plant`` (``PlantSettings``) within ``budget_s``
    (default ``plant.publish_timeout_s``), on ``link`` when one was opened already; never raises for a
    broker fault (``Delivery.fault``)."""
    budget = plant.publish_timeout_s if budget_s is None else budget_s
    link = link or Link(plant, budget).start()
    try:
        with outbox.draining(max(link.deadline - time.monotonic(), 0.0)) as ours:
            if not ours:
                return Delivery(0, len(outbox.pending()), "another handeye command of this cell is sending; the events wait")
            pending = outbox.pending()
            if not pending:
                return Delivery(0, 0)
            client = link.client()
            if client is None:
                return Delivery(0, len(pending), link.fault)
            return _send(client, plant, outbox, pending, link.deadline)
    finally:
        link.close()


def _send(client, plant, outbox, pending, deadline: float) -> Delivery:
    """Publish ``pending`` in order (up to paho's in-flight window at once), removing each acknowledged file."""
    sent, last = 0, None
    infos = []
    for seq, path in pending:
        payload = outbox.read(path)
        infos.append((path, payload, client.publish(event_topic(plant.mqtt.topic_prefix), payload, qos=1)))
    for path, payload, info in infos:
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not _acked(info, remaining):
            break
        outbox.done(path)
        sent, last = sent + 1, payload
    waiting = len(pending) - sent
    if last is not None:
        state = client.publish(state_topic(plant.mqtt.topic_prefix), last, qos=1, retain=True)
        _acked(state, max(deadline - time.monotonic(), 0.05))
    fault = None if waiting == 0 else (f"broker {plant.mqtt.host}:{plant.mqtt.effective_port} acknowledged "
                                       f"{sent} of {len(pending)} events in time")
    return Delivery(sent, waiting, fault)


def _acked(info, timeout_s: float) -> bool:
    try:
        info.wait_for_publish(timeout_s)
    except (RuntimeError, ValueError):  # the link dropped, or the message was refused by paho's queue
        return False
    return info.is_published()
