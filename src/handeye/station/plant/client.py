"""A paho-mqtt client for the plant's broker, from :class:`~handeye.station.plant.settings.BrokerSettings`.

paho-mqtt (the Eclipse Foundation's client, the reference MQTT 3.1.1/5 implementation for Python) is
the one dependency of the plant: it speaks TLS with client certificates and QoS 1/2 with its own
network thread, and needs no event loop of ours. The alternatives build on it (asyncio-mqtt/aiomqtt
wrap paho in asyncio, which no command of handeye runs) or are thinner and less kept (gmqtt, hbmqtt's
successor amqtt is a broker first). Imported only here, and only when a station file has ``plant:``.
"""

from __future__ import annotations

import os
import ssl
import threading

from ...base import HandEyeError

__all__ = ["make_client", "connect", "PlantLinkError"]


class PlantLinkError(HandEyeError):
    """The broker cannot be reached, or refused us: one line saying which."""


def make_client(broker, client_id: str, clean_session: bool = True):
    """A paho client (MQTT 3.1.1) with the TLS and credentials of ``broker`` (``BrokerSettings``), not connected."""
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    from .settings import broker_password

    client = mqtt.Client(CallbackAPIVersion.VERSION2, client_id=client_id, protocol=mqtt.MQTTv311,
                         clean_session=clean_session)
    if broker.username is not None:
        client.username_pw_set(broker.username, broker_password(broker))
    tls = broker.tls
    if tls.enabled:
        for name in ("ca", "cert", "key"):
            path = getattr(tls, name)
            if path not in (None, "system") and not os.path.isfile(path):
                raise PlantLinkError(f"plant.mqtt.tls.{name}: no file {path}")
        ca = None if tls.ca in (None, "system") else tls.ca
        client.tls_set(ca_certs=ca, certfile=tls.cert, keyfile=tls.key, cert_reqs=ssl.CERT_REQUIRED,
                       tls_version=ssl.PROTOCOL_TLS_CLIENT)
    return client


def connect(client, broker, timeout_s: float) -> None:
    """Connect ``client`` to ``broker`` and start its network thread, within ``timeout_s``.

    Raises
    ------
    PlantLinkError
        Not reachable, TLS refused, or the broker refused the credentials (its reason).
    """
    import paho.mqtt.client as mqtt

    done, answer = threading.Event(), {}

    def on_connect(client, userdata, flags, reason_code, properties=None):
        answer["rc"] = reason_code
        done.set()

    client.on_connect = on_connect
    client.connect_timeout = max(timeout_s, 0.05)
    where = f"{broker.host}:{broker.effective_port}"
    try:
        client.connect(broker.host, broker.effective_port, keepalive=int(broker.keepalive_s))
    except (OSError, ssl.SSLError, ValueError) as exc:
        raise PlantLinkError(f"broker {where} not reachable ({_reason(exc)})") from None
    client.loop_start()
    if not done.wait(timeout_s):
        _stop(client)
        raise PlantLinkError(f"broker {where} did not answer within {timeout_s:g} s")
    rc = answer["rc"]
    if getattr(rc, "is_failure", False) or (isinstance(rc, int) and rc != mqtt.CONNACK_ACCEPTED):
        _stop(client)
        raise PlantLinkError(f"broker {where} refused the connection ({rc}): check plant.mqtt.username and the password")


def _stop(client) -> None:
    try:
        client.disconnect()
    finally:
        client.loop_stop()


def _reason(exc: Exception) -> str:
    text = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
    return text.lower() if isinstance(text, str) else type(exc).__name__
