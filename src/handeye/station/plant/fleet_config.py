"""``plant.yaml``: the fleet view's configuration (``handeye plant --config plant.yaml``)::

    mqtt:                                  # the plant's broker, as a cell's plant.mqtt (no topic_prefix)
      host: broker.plant.local
      username: fleet                      # the ACL lets it read every cell's topics
      password_env: HANDEYE_FLEET_PASSWORD
      tls: {ca: /etc/handeye/plant-ca.pem}
    cells: acme/+/+/+/+                    # which cells (an MQTT filter of 5 levels); default +/+/+/+/+
    verify_interval_h: 168                 # a cell's verify is due this long after its last one
    stale_after_h: 48                      # a cell silent this long is flagged: stopped reporting
    history: plant_history.sqlite          # beside plant.yaml unless absolute
    view: {host: 127.0.0.1, port: 8765}
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from ...base import ConfigError, brief
from ...base import read_text_file
from ...base import parse_yaml
from ..config.schema import Custom, Number, Text, check_section, section, setting, text
from .settings import BrokerSettings

__all__ = ["FleetSettings", "ViewSettings", "load_fleet_config", "fleet_from_dict"]


def _cells_filter(value, key: str, context) -> str:
    levels = text(value, key).strip("/").split("/")
    if len(levels) != 5 or not all(level == "+" or re.fullmatch(r"[A-Za-z0-9_.\-]+", level) for level in levels):
        raise ConfigError(f"{key} must be 5 topic levels enterprise/site/area/line/cell, each a name or +; got "
                          f"{brief(value)}")
    return "/".join(levels)


@dataclass(frozen=True)
class ViewSettings:
    """``view``: where the fleet page is served (behind the live view's token)."""

    host: str = setting("127.0.0.1", Text(), "address the page listens on (127.0.0.1: this PC only)")
    port: int = setting(0, Number(0, 65535, integer=True), "TCP port (0: a free one, printed)")


@dataclass(frozen=True)
class FleetSettings:
    """The whole of ``plant.yaml``."""

    mqtt: BrokerSettings = section(BrokerSettings, "the plant's MQTT broker")
    cells: str = setting("+/+/+/+/+", Custom(_cells_filter), "the cells shown: an MQTT filter of 5 levels")
    verify_interval_h: float = setting(168.0, Number(0.001, 100000), "a cell's verify is due this long after its last "
                                       "check (or calibration)", "h")
    stale_after_h: float = setting(48.0, Number(0.0001, 100000), "a cell silent this long is flagged as stopped "
                                   "reporting", "h")
    drift_alarm_mm: float = setting(0.5, Number(0, 1000), "a verify change this large is flagged even when OK", "mm")
    history: str = setting("plant_history.sqlite", Text(), "the SQLite history (beside plant.yaml unless absolute)")
    view: ViewSettings = section(ViewSettings, "the page")
    source: Path | None = field(default=None, compare=False)

    def history_path(self) -> Path:
        path = Path(self.history).expanduser()
        return path if path.is_absolute() or self.source is None else self.source.parent / path


def fleet_from_dict(data, source: str = "plant.yaml") -> FleetSettings:
    """Validate ``data`` (as read from YAML) into :class:`FleetSettings` (ConfigError naming the key)."""
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: the file must hold a mapping (mqtt, cells, verify_interval_h, ...)")
    try:
        changes = check_section(FleetSettings, data, "plant", {})
    except ConfigError as exc:  # the keys as plant.yaml spells them (mqtt.port, not plant.mqtt.port)
        raise ConfigError(f"{source}: {str(exc).replace('plant.', '')}") from None
    tls = changes.get("mqtt", BrokerSettings()).tls
    if (tls.cert is None) != (tls.key is None):
        raise ConfigError("mqtt.tls needs both cert and key for a client certificate, or neither")
    return replace(FleetSettings(), **changes)


def load_fleet_config(path) -> FleetSettings:
    path = Path(path)
    raw = read_text_file(path, "plant configuration", ConfigError, missing=f"no plant configuration at {path}; "
                         "see docs/plant.md (A plant of cells)")
    return replace(fleet_from_dict(parse_yaml(raw, path, ConfigError) or {}, str(path)), source=path)
