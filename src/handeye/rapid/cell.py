"""``HeCell``: the cell's guards on the controller, a speed override and (World Zones option) keep-out zones.

Generated only when the station asks for it (``motion.speed_override_pct`` below 100, or
``cell.world_zones: true`` in the station config), so a station without them gets the program it
always got. ``HeMain`` then calls ``HeCellSetup`` once, first thing in ``main``:

- ``VelSet HE_SPEED_OVERRIDE, HE_MAX_TCP``: every posture move runs at the override (percent of
  ``vHeMove``), the TCP never faster than the station's TCP speed;
- with world zones (ABB option 608-1 World Zones): one temporary zone per keep-out volume,
  ``WZBoxDef \\Inside`` (boxes axis-aligned in base, a floor as a box reaching far below it) or
  ``WZCylDef \\Inside`` (vertical cylinders), each made active with ``WZLimSup \\Temp``: the
  controller stops the arm before the supervised TCP enters one. The supervised TCP is the one of
  the tool the moves use: with world zones the posture moves use ``tHeCamZone``, a tool whose frame is
  the camera's nominal mount (the camera's optical centre, as planned), not ``tool0``.
  Temporary zones are erased when the program pointer is moved to main; main defines them again.

The zones come from :mod:`handeye.robot.cell` (``world_zone()`` of each volume); the planner
keeps that TCP clear of the zones as the controller sees them, so a plan never trips them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import math
import string
from pathlib import Path

import numpy as np

from ..geometry import transform_from_pose
from .errors import ConfigError
from .literals import POSITION_DECIMALS, format_num, tooldata_literal

if TYPE_CHECKING:
    from .station import RapidStation

__all__ = ["CELL_MODULE", "MAX_WORLD_ZONES", "ZONE_TOOL", "check_world_zones", "needs_cell_module", "render_cell_text"]

#: The module's name.
CELL_MODULE = "HeCell"
#: The tool the posture moves use when world zones are declared (its TCP is what the zones watch).
ZONE_TOOL = "tHeCamZone"
#: World zones a controller supervises at most (temporary and stationary together).
MAX_WORLD_ZONES = 20
#: Largest coordinate of a zone, mm.
_ZONE_REACH_MM = 100000.0

_TEMPLATE = Path(__file__).with_name("templates") / "HeCell.mod.tmpl"


def _numbers(value, name: str, count: int, source: str) -> tuple:
    try:
        values = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(f"{source}: {name} must be {count} numbers") from None
    if len(values) != count or not all(math.isfinite(v) and abs(v) <= _ZONE_REACH_MM for v in values):
        raise ConfigError(f"{source}: {name} must be {count} finite numbers (mm); got {value!r}")
    return values


def _zone(zone, i: int, source: str) -> dict:
    name = f"world_zones.zones[{i}]"
    if not isinstance(zone, dict) or zone.get("type") not in ("box", "cylinder"):
        raise ConfigError(f"{source}: {name} must be a mapping with type box or cylinder")
    label = "".join(ch if " " <= ch <= "~" and ch != '"' else "?" for ch in str(zone.get("name", f"zone {i + 1}")))
    if zone["type"] == "box":
        low = _numbers(zone.get("min_mm"), f"{name}.min_mm", 3, source)
        high = _numbers(zone.get("max_mm"), f"{name}.max_mm", 3, source)
        if not all(a < b for a, b in zip(low, high)):
            raise ConfigError(f"{source}: {name}: min_mm must be below max_mm on every axis")
        return {"type": "box", "name": label, "min_mm": low, "max_mm": high}
    base = _numbers(zone.get("base_mm"), f"{name}.base_mm", 3, source)
    radius, height = _numbers([zone.get("radius_mm"), zone.get("height_mm")], f"{name} radius_mm, height_mm", 2, source)
    if not (radius > 0 and height > 0):
        raise ConfigError(f"{source}: {name}: radius_mm and height_mm must be > 0")
    return {"type": "cylinder", "name": label, "base_mm": base, "radius_mm": radius, "height_mm": height}


def check_world_zones(data, source: str) -> tuple[tuple, tuple | None]:
    """The ``world_zones`` mapping of a station dict (``{tcp: {position_mm, quaternion_wxyz}, zones: [...]}``)
    checked: ``(zones, tcp)``; ``((), None)`` for None.

    Raises
    ------
    ConfigError
    """
    if data is None:
        return (), None
    if not isinstance(data, dict) or set(data) - {"tcp", "zones"} or "tcp" not in data:
        raise ConfigError(f"{source}: world_zones must be a mapping of tcp (position_mm, quaternion_wxyz) and zones")
    tcp = data["tcp"]
    if not isinstance(tcp, dict):
        raise ConfigError(f"{source}: world_zones.tcp needs position_mm and quaternion_wxyz")
    position = _numbers(tcp.get("position_mm"), "world_zones.tcp.position_mm", 3, source)
    quaternion = _numbers(tcp.get("quaternion_wxyz"), "world_zones.tcp.quaternion_wxyz", 4, source)
    if abs(np.linalg.norm(quaternion) - 1) > 1e-3 or np.linalg.norm(position) > 1000:
        raise ConfigError(f"{source}: world_zones.tcp must be a unit quaternion within 1000 mm of the flange")
    zones = data.get("zones") or []
    if not isinstance(zones, list) or len(zones) > MAX_WORLD_ZONES:
        raise ConfigError(f"{source}: world_zones.zones must be a list of at most {MAX_WORLD_ZONES} zones "
                          "(what a controller supervises)")
    return tuple(_zone(z, i, source) for i, z in enumerate(zones)), (position, quaternion)


def needs_cell_module(station: RapidStation) -> bool:
    """True when the station's program needs ``HeCell`` (a speed override, or world zones)."""
    return station.speed_override_pct < 100 or station.zone_tcp is not None


def _pos(values) -> str:
    return "[" + ",".join(format_num(float(v), POSITION_DECIMALS) for v in values) + "]"


def _zone_lines(zones) -> tuple[list, list]:
    """Module data and setup lines of the zones."""
    data, setup = [], []
    for k, zone in enumerate(zones, start=1):
        data.append(f"  ! zone {k}: {zone['name']}")
        data.append(f"  VAR wztemporary wzHeZone{k};")
        if zone["type"] == "box":
            data.append(f"  CONST pos pHeZone{k}Lo := {_pos(zone['min_mm'])};")
            data.append(f"  CONST pos pHeZone{k}Hi := {_pos(zone['max_mm'])};")
            setup.append(f"    WZBoxDef \\Inside, heShape, pHeZone{k}Lo, pHeZone{k}Hi;")
        else:
            data.append(f"  CONST pos pHeZone{k}Base := {_pos(zone['base_mm'])};")
            setup.append(f"    WZCylDef \\Inside, heShape, pHeZone{k}Base, {format_num(zone['radius_mm'], 3)}, "
                         f"{format_num(zone['height_mm'], 3)};")
        setup.append(f"    WZLimSup \\Temp, wzHeZone{k}, heShape;")
    return data, setup


def render_cell_text(station: RapidStation, header: str) -> str:
    """The text of ``HeCell`` for a station that :func:`needs_cell_module`."""
    data, setup = [], ["    VAR shapedata heShape;", "", "    VelSet HE_SPEED_OVERRIDE, HE_MAX_TCP;"]
    if station.zone_tcp is not None:
        position, quaternion = station.zone_tcp
        tool = tooldata_literal(transform_from_pose(position, quaternion), station.tool_mass_kg, station.tool_cog_mm)
        data.append("  ! The camera at its nominal mount as a tool: the posture moves use it, so the world zones")
        data.append("  ! watch the camera's optical centre, not the flange.")
        data.append(f"  PERS tooldata {ZONE_TOOL} := {tool};")
        zone_data, zone_setup = _zone_lines(station.world_zones)
        data += zone_data
        setup += zone_setup
    else:
        setup[0:2] = []  # no zones: no shape
    text = string.Template(_TEMPLATE.read_text()).substitute(
        header=header, override=format_num(station.speed_override_pct, 1),
        max_tcp=format_num(station.speed_tcp_mm_s, 1), zone_data="\n".join(data), setup="\n".join(setup))
    return text.replace("\n\n\n", "\n\n")
