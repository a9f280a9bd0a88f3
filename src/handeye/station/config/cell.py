"""The ``cell`` and ``guided`` sections of the station config: the cell's geometry and the guided capture.

``cell`` describes what the arm must keep out of (keep-out volumes in base: boxes, vertical cylinders,
the floor), what the flange carries (boxes and spheres in tool0), the board's stand (derived from the
measured board pose), the margin and path sampling of the checks, and whether the controller also
guards the volumes with ABB world zones. ``guided`` sets the operator-guided capture (``capture
--guided``): when the arm counts as still, when a posture counts as new, and the targets beyond the
verdict's thresholds. Each key is a :func:`~handeye.station.config.schema.setting` with its rule; the
geometry itself is ``robot.cell``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...robot import DEFAULT_CARRIED, Box, CellModel, Cylinder, Floor, Sphere
from ...base import ConfigError, brief
from ...rapid import PROMPTS
from .schema import Custom, Flag, Number, Optional, Text, number, numbers, setting, text

__all__ = ["CellSettings", "GuidedSettings", "DEFAULT_CARRIED", "DEFAULT_KEEP_OUT"]

#: Longest length of a cell coordinate, mm (a cell is a few metres; 10 m is a typing error).
_CELL_REACH_MM = 10000.0
#: Longest length of a carried body's coordinate in tool0, mm.
_CARRIED_REACH_MM = 1000.0
#: A keep-out volume whose every coordinate is within this (the robot reaches ~1400 mm) is in metres.
_METRES_CELL = 5.0
#: A carried body whose every coordinate is within this (a camera sits ~100 mm from the flange) is in metres.
_METRES_CARRIED = 1.0

_VOLUME_KEYS = {
    "box": {"type", "name", "min_mm", "max_mm"},
    "floor": {"type", "name", "z_mm"},
    "cylinder": {"type", "name", "centre_mm", "radius_mm", "z_mm"},
}
_CARRIED_KEYS = {
    "box": {"type", "name", "min_mm", "max_mm"},
    "sphere": {"type", "name", "centre_mm", "radius_mm"},
}


def _entry(value, key: str, allowed: dict) -> tuple[str, dict]:
    """The type of one list entry and the entry, its keys checked against ``allowed[type]``."""
    if not isinstance(value, dict):
        raise ConfigError(f"{key} must be a mapping with a type ({' | '.join(allowed)}); got {brief(value)}")
    kind = text(value.get("type"), f"{key}.type", tuple(allowed))
    unknown = sorted(set(value) - allowed[kind], key=brief)
    if unknown:
        raise ConfigError(f"unknown key {key}.{unknown[0]}; a {kind} has {', '.join(sorted(allowed[kind]))}")
    missing = sorted(allowed[kind] - set(value) - {"name"})
    if missing:
        raise ConfigError(f"{key} ({kind}) needs {missing[0]}")
    return kind, value


def _corners(value: dict, key: str, reach: float) -> tuple[tuple, tuple]:
    low = numbers(value["min_mm"], f"{key}.min_mm", 3, -reach, reach)
    high = numbers(value["max_mm"], f"{key}.max_mm", 3, -reach, reach)
    for axis, (a, b) in enumerate(zip(low, high)):
        if not a < b:
            raise ConfigError(f"{key}: min_mm[{axis}] ({a:g}) must be below max_mm[{axis}] ({b:g})")
    return low, high


def _name(value: dict, key: str, default: str, taken: set) -> str:
    name = text(value["name"], f"{key}.name") if "name" in value else default
    if name in taken:
        raise ConfigError(f"{key}.name {name!r} is used twice: give each volume its own name")
    taken.add(name)
    return name


def _not_metres(key: str, name: str, values, largest_m: float) -> None:
    """Refuse a volume whose every coordinate is within ``largest_m``: lengths in metres, not mm."""
    if max(abs(float(v)) for v in values) < largest_m:
        raise ConfigError(f"{key} ({name!r}): every coordinate is within +-{largest_m:g}, which looks like metres; "
                          f"the cell is given in mm (e.g. 1.15 m -> 1150)")


def _floor(entry: dict, key: str, name: str) -> Floor:
    """A floor at or below the robot's foot (base z = 0): higher, the robot would stand inside it."""
    z = number(entry["z_mm"], f"{key}.z_mm", -_CELL_REACH_MM, _CELL_REACH_MM)
    if z > 0:
        raise ConfigError(f"{key}.z_mm is {z:g}: a floor is everything below that height, so the robot's foot (base z 0) "
                          f"would stand inside {name!r}; give 0 or below (a robot on a pedestal: minus its height), and a "
                          "table beside the robot as a box")
    return Floor(name, z)


def _volume(value, key: str, taken: set):
    kind, entry = _entry(value, key, _VOLUME_KEYS)
    name = _name(entry, key, kind if kind == "floor" else f"{kind} {key.rsplit('[', 1)[-1].rstrip(']')}", taken)
    if kind == "box":
        low, high = _corners(entry, key, _CELL_REACH_MM)
        _not_metres(key, name, low + high, _METRES_CELL)
        return Box(name, low, high)
    if kind == "floor":
        return _floor(entry, key, name)
    centre = numbers(entry["centre_mm"], f"{key}.centre_mm", 2, -_CELL_REACH_MM, _CELL_REACH_MM)
    z = numbers(entry["z_mm"], f"{key}.z_mm", 2, -_CELL_REACH_MM, _CELL_REACH_MM)
    radius = number(entry["radius_mm"], f"{key}.radius_mm", -_CELL_REACH_MM, _CELL_REACH_MM)
    _not_metres(key, name, centre + z + (radius,), _METRES_CELL)
    radius = number(radius, f"{key}.radius_mm", 1.0, _CELL_REACH_MM)
    if not z[0] < z[1]:
        raise ConfigError(f"{key}.z_mm must be [bottom, top] with bottom < top; got {list(z)}")
    return Cylinder(name, centre, radius, z)


def _keep_out(value, key: str, context) -> tuple:
    """Keep-out volumes in base: a list of boxes, vertical cylinders and floors."""
    if not isinstance(value, list):
        raise ConfigError(f"{key} must be a list of volumes ({{type: box | floor | cylinder, ...}}); got {brief(value)}")
    taken: set = set()
    return tuple(_volume(v, f"{key}[{i}]", taken) for i, v in enumerate(value))


def _carried_body(value, key: str, taken: set):
    kind, entry = _entry(value, key, _CARRIED_KEYS)
    name = _name(entry, key, f"{kind} {key.rsplit('[', 1)[-1].rstrip(']')}", taken)
    if kind == "box":
        low, high = _corners(entry, key, _CARRIED_REACH_MM)
        _not_metres(key, name, low + high, _METRES_CARRIED)
        return Box(name, low, high)
    centre = numbers(entry["centre_mm"], f"{key}.centre_mm", 3, -_CARRIED_REACH_MM, _CARRIED_REACH_MM)
    radius = number(entry["radius_mm"], f"{key}.radius_mm", -_CARRIED_REACH_MM, _CARRIED_REACH_MM)
    _not_metres(key, name, centre + (radius,), _METRES_CARRIED)
    return Sphere(name, centre, number(radius, f"{key}.radius_mm", 1.0, _CARRIED_REACH_MM))


def _carried(value, key: str, context) -> tuple:
    """What the flange carries, in tool0: a list of boxes and spheres."""
    if not isinstance(value, list):
        raise ConfigError(f"{key} must be a list of bodies in tool0 ({{type: box | sphere, ...}}); got {brief(value)}")
    taken: set = set()
    return tuple(_carried_body(v, f"{key}[{i}]", taken) for i, v in enumerate(value))


#: The robot stands on the floor: nothing of the wrist or the camera may go below its foot.
DEFAULT_KEEP_OUT = (Floor("floor", 0.0),)


@dataclass(frozen=True)
class CellSettings:
    """``cell``: what the arm must keep out of, what it carries, and how plans are checked."""

    keep_out: tuple = setting(DEFAULT_KEEP_OUT, Custom(_keep_out), "keep-out volumes in base: [{type: box, min_mm, "
                              "max_mm} | {type: floor, z_mm} | {type: cylinder, centre_mm, radius_mm, z_mm}]", "mm")
    carried: tuple = setting(DEFAULT_CARRIED, Custom(_carried), "what the flange carries, in tool0: [{type: box, "
                             "min_mm, max_mm} | {type: sphere, centre_mm, radius_mm}]", "mm")
    stand_margin_mm: float | None = setting(50.0, Optional(Number(0, 1000)), "the board's stand: the board grown by "
                                            "this on every side (null: no stand)", "mm")
    stand_depth_mm: float = setting(100.0, Number(0, 3000), "the board's stand: how far it reaches behind the "
                                    "printed face (then down to the floor)", "mm")
    margin_mm: float = setting(30.0, Number(5, 500), "clearance every posture and every move keeps", "mm")
    path_step_mm: float = setting(10.0, Number(1, 100), "moves are sampled so nothing moves farther between two "
                                  "samples (at most margin_mm)", "mm")
    world_zones: bool = setting(False, Flag(), "the controller has World Zones (608-1): the program declares the "
                                "keep-out volumes as world zones on the camera's TCP")

    def model(self) -> CellModel:
        """The cell's geometry (``robot.cell``)."""
        return CellModel(self.keep_out, self.carried, self.stand_margin_mm, self.stand_depth_mm)

    def to_dict(self) -> dict:
        return {"keep_out": [v.to_dict() for v in self.keep_out], "carried": [b.to_dict() for b in self.carried],
                "stand_margin_mm": self.stand_margin_mm, "stand_depth_mm": self.stand_depth_mm,
                "margin_mm": self.margin_mm, "path_step_mm": self.path_step_mm, "world_zones": self.world_zones}


@dataclass(frozen=True)
class GuidedSettings:
    """``guided``: operator-guided capture (``capture --guided``)."""

    still_s: float = setting(1.0, Number(0.05, 30), "the arm counts as still after this long without motion", "s")
    still_tolerance_deg: float = setting(0.01, Number(0, 5), "a joint change that counts as motion", "deg")
    poll_s: float = setting(0.1, Number(0.01, 5), "how often the joints are read", "s")
    min_step_deg: float = setting(5.0, Number(0, 90), "a new posture turns at least this much from every captured "
                                  "one ...", "deg")
    min_step_mm: float = setting(50.0, Number(0, 2000), "... or moves at least this far", "mm")
    min_distance_spread_mm: float = setting(200.0, Number(0, 5000), "board distances should span at least this",
                                            "mm")
    min_image_cells: int = setting(7, Number(1, 9, integer=True), "of the 3x3 cells of the image, the board's "
                                   "corners should be seen in at least this many")
    max_postures: int = setting(60, Number(3, 255, integer=True), "stop after this many postures")
    prompt: str = setting("fk", Text(lambda: PROMPTS), "how the guided RAPID program asks the operator: fk "
                          "(TPReadFK, every RobotWare) or messagebox (UIMessageBox, RobotWare 6/7)")
    operator_timeout_s: float = setting(1800.0, Number(10, 86400), "the guided program: how long the PC waits "
                                        "for the operator's key or Start before it gives up", "s")
