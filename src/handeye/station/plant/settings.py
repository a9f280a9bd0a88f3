"""The station file's ``plant:`` section: where a cell publishes its calibration health (MQTT).

Declared like every other section (:func:`~handeye.station.config.schema.setting`: default, rule, doc), and
checked key by key; nothing here imports an MQTT client. Without a ``plant:`` section the config's
``plant`` is None and nothing is published (``station.plant.hooks``)::

    plant:
      station_id: cell07-pc          # null: the cell (the last level of topic_prefix)
      mqtt:
        host: broker.plant.local
        port: 8883                   # null: 8883 with TLS, 1883 without
        topic_prefix: acme/berlin/body/line2/cell07   # ISA-95: enterprise/site/area/line/cell
        username: cell07
        password_env: HANDEYE_MQTT_PASSWORD           # or password: ... (a secret, never printed)
        tls: {ca: /etc/handeye/plant-ca.pem, cert: null, key: null}
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

from ...base import ConfigError, brief
from ..config.schema import Custom, Number, Optional, Text, check_section, section, setting, text

__all__ = ["TlsSettings", "BrokerSettings", "MqttSettings", "PlantSettings", "plant_rule", "topic_levels",
           "broker_password"]

#: One level of an MQTT topic as the prefix allows it: no wildcard, no separator, no spaces.
_LEVEL = re.compile(r"[A-Za-z0-9_.\-]+")


def _file(value, key: str, context) -> str:
    """A path to a PEM file (existence is checked when connecting: the file may be mounted later)."""
    return text(value, key, what="the path of a PEM file")


def topic_levels(value: str, key: str, count: int | None = 5) -> tuple[str, ...]:
    """The levels of a topic prefix ``enterprise/site/area/line/cell`` (``count`` of them when given).

    Raises
    ------
    ConfigError
        Not ``count`` levels of letters, digits, ``_ . -`` (MQTT wildcards ``+ #`` are refused).
    """
    levels = tuple(text(value, key).strip("/").split("/"))
    if (count is not None and len(levels) != count) or not all(_LEVEL.fullmatch(level) for level in levels):
        raise ConfigError(f"{key} must be enterprise/site/area/line/cell: {count} levels of letters, digits, '_', "
                          f"'.' or '-' separated by '/' (no + or #); got {brief(value)}")
    return levels


def _prefix(value, key: str, context) -> str:
    return "/".join(topic_levels(value, key))


def _env_name(value, key: str, context) -> str:
    name = text(value, key)
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise ConfigError(f"{key} must be the name of an environment variable; got {brief(value)}")
    return name


@dataclass(frozen=True)
class TlsSettings:
    """``plant.mqtt.tls``: TLS to the broker; on when ``ca`` or ``cert`` is set."""

    ca: str | None = setting(None, Optional(Custom(_file)), "CA certificate (PEM) the broker's certificate is checked "
                             "against ('system': the system's trust store)")
    cert: str | None = setting(None, Optional(Custom(_file)), "client certificate (PEM) when the broker "
                               "authenticates cells by certificate")
    key: str | None = setting(None, Optional(Custom(_file)), "the client certificate's private key (PEM)")

    @property
    def enabled(self) -> bool:
        return self.ca is not None or self.cert is not None


@dataclass(frozen=True)
class BrokerSettings:
    """How to reach the plant's MQTT broker (a cell and the fleet view alike)."""

    host: str = setting("127.0.0.1", Text(what="the broker's address"), "the broker's address or host name")
    port: int | None = setting(None, Optional(Number(1, 65535, integer=True)), "TCP port (null: 8883 with TLS, 1883 "
                               "without)")
    username: str | None = setting(None, Optional(Text()), "user name at the broker (its ACL names it)")
    password: str | None = setting(None, Optional(Text()), "the password (prefer password_env)", secret=True)
    password_env: str | None = setting(None, Optional(Custom(_env_name)), "environment variable holding the "
                                       "password (read when connecting)")
    client_id: str | None = setting(None, Optional(Text()), "MQTT client id (null: handeye-<cell> / handeye-fleet)")
    keepalive_s: float = setting(30.0, Number(5, 3600), "MQTT keep-alive", "s")
    tls: TlsSettings = section(TlsSettings, "TLS to the broker")

    @property
    def effective_port(self) -> int:
        return self.port if self.port is not None else (8883 if self.tls.enabled else 1883)


@dataclass(frozen=True)
class MqttSettings(BrokerSettings):
    """``plant.mqtt``: the broker, and the cell's place in the plant's namespace."""

    topic_prefix: str = setting("enterprise/site/area/line/cell", Custom(_prefix), "the cell's topic: "
                                "enterprise/site/area/line/cell (ISA-95); events go below it")


def broker_password(broker: BrokerSettings) -> str | None:
    """The password to connect with: ``password_env``'s variable when set (None when it is unset), else ``password``."""
    if broker.password_env is not None:
        return os.environ.get(broker.password_env)
    return None if broker.password == "<set>" else broker.password  # "<set>": a session's record, never the secret


@dataclass(frozen=True)
class PlantSettings:
    """``plant``: publishing this cell's calibration health to the plant's broker (``station.plant``)."""

    station_id: str | None = setting(None, Optional(Text()), "this station's name in the plant (null: the cell, "
                                     "the last level of mqtt.topic_prefix)")
    operator: str | None = setting(None, Optional(Text()), "who runs the commands (null: the login name)")
    outbox: str | None = setting(None, Optional(Text()), "folder of the events not yet delivered (null: "
                                 "~/.handeye/plant-outbox/<cell>)")
    publish_timeout_s: float = setting(2.0, Number(0.05, 30), "longest time publishing may add to a command (then "
                                       "the events wait in the outbox)", "s")
    standoff_mm: float = setting(800.0, Number(10, 10000), "the stand-off at which the predicted error of a "
                                 "calibration is given (camera to part)", "mm")
    mqtt: MqttSettings = section(MqttSettings, "the plant's MQTT broker")

    @property
    def cell(self) -> str:
        return self.mqtt.topic_prefix.rsplit("/", 1)[-1]

    @property
    def station(self) -> str:
        return self.station_id or self.cell

    def outbox_dir(self) -> Path:
        if self.outbox is not None:
            return Path(self.outbox).expanduser()
        return Path.home() / ".handeye" / "plant-outbox" / self.cell

    def to_dict(self) -> dict:
        """The section as the session record keeps it: the password is ``"<set>"`` or None, never its value."""
        from dataclasses import asdict

        data = asdict(self)
        data["mqtt"]["password"] = None if self.mqtt.password is None else "<set>"
        return data


def plant_rule(value, key: str, context) -> PlantSettings:
    """The rule of ``plant``: a mapping of :class:`PlantSettings` keys; ``mqtt.topic_prefix`` is required."""
    if not isinstance(value, dict) or not isinstance(value.get("mqtt"), dict) or "topic_prefix" not in value["mqtt"]:
        raise ConfigError(f"{key}.mqtt.topic_prefix is missing: name the cell's topic, enterprise/site/area/line/cell "
                          "(and plant.mqtt.host, the broker)")
    changes = check_section(PlantSettings, value, key, context)
    mqtt = changes.get("mqtt")
    if mqtt is not None:
        tls = mqtt.tls
        if (tls.cert is None) != (tls.key is None):
            raise ConfigError(f"{key}.mqtt.tls needs both cert and key for a client certificate, or neither")
        if mqtt.password is not None and mqtt.password_env is not None:
            raise ConfigError(f"{key}.mqtt: give password or password_env, not both")
    return replace(PlantSettings(), **changes)
