"""Sending the outbox to the broker: in order, QoS 1, within a time budget, then the retained state.

:func:`deliver` connects (TLS and credentials of ``plant.mqtt``), publishes every waiting event of the
outbox in sequence order on ``<topic_prefix>/handeye/event`` (QoS 1, not retained), removes each file
once the broker acknowledged it, and publishes the last one on ``<topic_prefix>/handeye/state``
(QoS 1, retained: what a subscriber sees first about the cell). It stops at the budget: what was not
acknowledged stays in the outbox and leaves, first, with the next command's events.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

__all__ = ["EVENT_TOPIC", "STATE_TOPIC", "Delivery", "deliver", "event_topic", "state_topic"]

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


def deliver(plant, outbox, budget_s: float | None = None) -> Delivery:
    """Send ``outbox`` (``Outbox``) to the broker of ``plant`` (``PlantSettings``) within ``budget_s``
    (default ``plant.publish_timeout_s``); never raises for a broker fault (``Delivery.fault``)."""
    from .client import PlantLinkError, connect, make_client

    budget = plant.publish_timeout_s if budget_s is None else budget_s
    deadline = time.monotonic() + budget
    with outbox.draining(budget) as ours:
        if not ours:
            return Delivery(0, len(outbox.pending()), "another handeye command of this cell is sending; the events wait")
        pending = outbox.pending()
        if not pending:
            return Delivery(0, 0)
        client_id = plant.mqtt.client_id or f"handeye-{plant.cell}-{os.getpid()}"
        try:
            client = make_client(plant.mqtt, client_id)
            connect(client, plant.mqtt, max(deadline - time.monotonic(), 0.05))
        except PlantLinkError as exc:
            return Delivery(0, len(pending), str(exc))
        try:
            return _send(client, plant, outbox, pending, deadline)
        finally:
            client.disconnect()
            client.loop_stop()


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
