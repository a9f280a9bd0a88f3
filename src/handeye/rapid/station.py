"""The station settings the RAPID modules are rendered from, read from a YAML file or built in.

Station YAML (the keys ``handeye rapid generate`` reads; other top-level sections are left for the
rest of the station and ignored here)::

    robot: IRB1400                     # robot model (joint limits for the checks)
    controller:
      protocol: socket                 # a protocol with a RAPID link module: which one to generate
      pc_address: 192.168.125.10       # the only client the socket server accepts
      controller_address: auto         # address the socket server binds: auto = GetSysInfo(\\LanIp)
      port: 1025                       # TCP port of the socket server
      serial_channel: "sio1:"          # serial channel of the serial variant
      ack_timeout_s: 30                # warn (state LATE) when the PC has not acknowledged a posture
      idle_timeout_s: 5                # drop a silent PC (socket) / forget its session (serial), 0.1..10 s
      write_key: null                  # 8-32 letters/digits/_/-: tool writes need it (HeKey.sys; secret)
    motion:
      speed_tcp_mm_s: 200              # speeddata of the posture moves: TCP speed
      speed_ori_deg_s: 100             #   and reorientation speed
      speed_override_pct: 100          # below 100: HeCell sets VelSet to it
    tool:
      name: tHeCamera                  # PERS tooldata holding the camera frame
      mass_kg: 1.0
      cog_mm: [0, 0, 60]
    postures:                          # approved postures, controller axis angles in degrees
      - [25.13, -38.52, -10.33, -11.31, 89.6, -102.64]
      - ...
    world_zones:                       # optional (World Zones option): HeCell declares them (rapid.cell)
      tcp: {position_mm: [x, y, z], quaternion_wxyz: [w, x, y, z]}    # the supervised TCP in tool0
      zones:
        - {type: box, name: fixture, min_mm: [x, y, z], max_mm: [x, y, z]}
        - {type: cylinder, name: column, base_mm: [x, y, z], radius_mm: r, height_mm: h}

(``handeye capture`` and ``rapid generate --config`` build ``world_zones`` from the station config's
``cell`` section when ``cell.world_zones`` is true.)

Every key is optional; a missing key takes the built-in station's value (``default_station.yaml``:
the mock controller on 127.0.0.1).
"""

from __future__ import annotations

import ipaddress
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..base import parse_yaml, read_text_file
from ..robot import load_robot
from ..base import WRITE_KEY_PATTERN
from .cell import check_world_zones
from .errors import ConfigError
from .links import BUILT_IN_LINKS, PROTOCOLS, RapidLink

__all__ = ["PROTOCOLS", "RapidStation", "default_station", "load_station", "station_from_dict", "check_postures",
           "DEFAULT_STATION_FILE", "RAPID_IDENTIFIER", "WRITE_KEY_PATTERN", "IDLE_TIMEOUT_RANGE"]

DEFAULT_STATION_FILE = Path(__file__).with_name("default_station.yaml")
RAPID_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
#: Allowed range of controller.idle_timeout_s (seconds).
IDLE_TIMEOUT_RANGE = (0.1, 10.0)

_SECTIONS = {
    "controller": {"protocol", "pc_address", "controller_address", "port", "serial_channel", "ack_timeout_s",
                   "idle_timeout_s", "write_key"},
    "motion": {"speed_tcp_mm_s", "speed_ori_deg_s", "speed_override_pct"},
    "tool": {"name", "mass_kg", "cog_mm"},
}


@dataclass(frozen=True)
class RapidStation:
    """Settings of the generated RAPID program (see the module docstring for the YAML keys)."""

    robot: str = "IRB1400"
    protocol: str = PROTOCOLS[0]  # the package's first link (default_station.yaml names it)
    pc_address: str = "127.0.0.1"
    controller_address: str = "127.0.0.1"
    port: int = 1025
    serial_channel: str = "sio1:"
    ack_timeout_s: float = 30.0
    idle_timeout_s: float = 5.0
    write_key: str | None = field(default=None, repr=False)  # a secret: rendered into HeKey.sys only
    speed_tcp_mm_s: float = 200.0
    speed_ori_deg_s: float = 100.0
    tool_name: str = "tHeCamera"
    tool_mass_kg: float = 1.0
    tool_cog_mm: tuple = (0.0, 0.0, 0.0)
    postures: tuple = field(default_factory=tuple)
    source: str = "built-in"
    speed_override_pct: float = 100.0
    world_zones: tuple = ()
    zone_tcp: tuple | None = None
    #: Protocol -> its RAPID link module (``rapid.links.RapidLink``): the package's own, or what the
    #: caller hands over from the controller registry (plug-ins included).
    links: Mapping[str, RapidLink] = field(default_factory=lambda: BUILT_IN_LINKS, compare=False, repr=False)

    @property
    def postures_array(self) -> np.ndarray:
        return np.array(self.postures, dtype=float).reshape(-1, load_robot(self.robot).dof)

    def with_(self, **changes) -> "RapidStation":
        """A copy with some settings changed, checked again."""
        return _checked(replace(self, **changes))


def check_postures(postures: ArrayLike, robot: str = "IRB1400", source: str = "postures") -> np.ndarray:
    """Approved postures as an (n, dof) array (dof: the robot's axes); refused if empty, NaN, or outside
    the joint limits.

    Raises
    ------
    ConfigError
        Naming every bad posture (1-based) and axis.
    """
    model = load_robot(robot)
    try:
        arr = np.array(postures, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{source}: postures must be lists of {model.dof} numbers") from None
    if arr.ndim != 2 or arr.shape[1] != model.dof or len(arr) == 0:
        raise ConfigError(f"{source}: postures must be a non-empty list of {model.dof} joint angles each; "
                                 f"got shape {arr.shape}")
    if len(arr) > 255:
        raise ConfigError(f"{source}: at most 255 postures fit the protocol; got {len(arr)}")
    problems = []
    for i, row in enumerate(arr, start=1):
        violations = model.limit_violations(row)
        if violations:
            problems.append(f"posture {i}: {', '.join(violations)}")
    if problems:
        raise ConfigError(f"{source}: postures outside the {model.name} joint limits (nothing written): "
                                 + "; ".join(problems))
    return arr


def _number(value, name: str, source: str, low: float, high: float) -> float:
    if isinstance(value, bool):
        raise ConfigError(f"{source}: {name} must be a number; got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{source}: {name} must be a number; got {value!r}") from None
    if not math.isfinite(v) or not low < v <= high:
        raise ConfigError(f"{source}: {name} must be in ({low:g}, {high:g}]; got {value!r}")
    return v


def _ipv4(value, name: str, source: str, allow_auto: bool = False) -> str:
    text = str(value)
    if allow_auto and text == "auto":
        return text
    try:
        return str(ipaddress.IPv4Address(text))
    except ValueError:
        extra = " or 'auto'" if allow_auto else ""
        raise ConfigError(f"{source}: {name} must be an IPv4 address{extra}; got {value!r}") from None


def _checked(station: RapidStation) -> RapidStation:
    src = station.source
    try:
        load_robot(station.robot)
    except ValueError as exc:
        raise ConfigError(f"{src}: {exc}") from None
    if station.protocol not in station.links:
        raise ConfigError(f"{src}: controller.protocol must be one of {', '.join(station.links)} (a protocol with a "
                          f"RAPID link module); got {station.protocol!r}")
    pc = _ipv4(station.pc_address, "controller.pc_address", src)
    ctrl = _ipv4(station.controller_address, "controller.controller_address", src, allow_auto=True)
    port = station.port
    if isinstance(port, bool) or not isinstance(port, int) or not 0 < port < 65536:
        raise ConfigError(f"{src}: controller.port must be an integer 1..65535; got {port!r}")
    if not re.fullmatch(r"[A-Za-z0-9_]{1,15}:", str(station.serial_channel)):
        raise ConfigError(f"{src}: controller.serial_channel must look like 'sio1:' or 'com1:'; "
                                 f"got {station.serial_channel!r}")
    ack = _number(station.ack_timeout_s, "controller.ack_timeout_s", src, 0.0, 3600.0)
    idle = _number(station.idle_timeout_s, "controller.idle_timeout_s", src, 0.0, IDLE_TIMEOUT_RANGE[1])
    if idle < IDLE_TIMEOUT_RANGE[0]:
        raise ConfigError(f"{src}: controller.idle_timeout_s must be {IDLE_TIMEOUT_RANGE[0]:g} to "
                                 f"{IDLE_TIMEOUT_RANGE[1]:g} s; got {station.idle_timeout_s!r}")
    key = station.write_key
    if key is not None and not (isinstance(key, str) and WRITE_KEY_PATTERN.fullmatch(key)):
        size = f"another value of {len(key)} characters" if isinstance(key, str) else f"a {type(key).__name__} (quote it in YAML)"
        raise ConfigError(f"{src}: controller.write_key must be 8 to 32 letters, digits, '_' or '-'; got {size} "
                                 "(the key itself is never printed)")
    tcp = _number(station.speed_tcp_mm_s, "motion.speed_tcp_mm_s", src, 0.0, 7000.0)
    ori = _number(station.speed_ori_deg_s, "motion.speed_ori_deg_s", src, 0.0, 1000.0)
    override = _number(station.speed_override_pct, "motion.speed_override_pct", src, 0.0, 100.0)
    if override < 1:
        raise ConfigError(f"{src}: motion.speed_override_pct must be 1 to 100 %; got {station.speed_override_pct!r}")
    name = str(station.tool_name)
    if not RAPID_IDENTIFIER.fullmatch(name) or name.lower() in ("tool0", "tooldata"):
        raise ConfigError(f"{src}: tool.name must be a RAPID identifier (letter first, letters/digits/_, "
                                 f"at most 32) other than tool0; got {name!r}")
    mass = _number(station.tool_mass_kg, "tool.mass_kg", src, 0.0, 100.0)
    try:
        cog = tuple(float(v) for v in station.tool_cog_mm)
    except (TypeError, ValueError):
        raise ConfigError(f"{src}: tool.cog_mm must be three numbers (mm)") from None
    if len(cog) != 3 or not all(math.isfinite(v) and abs(v) <= 1000 for v in cog):
        raise ConfigError(f"{src}: tool.cog_mm must be three finite numbers within 1000 mm; got {station.tool_cog_mm!r}")
    postures = check_postures(station.postures, station.robot, src)
    return replace(station, pc_address=pc, controller_address=ctrl, ack_timeout_s=ack, idle_timeout_s=idle, speed_tcp_mm_s=tcp,
                   speed_ori_deg_s=ori, speed_override_pct=override, tool_name=name, tool_mass_kg=mass, tool_cog_mm=cog,
                   postures=tuple(tuple(float(v) for v in row) for row in postures))


def station_from_dict(data: dict, source: str = "station config", base: RapidStation | None = None,
                      links: Mapping[str, RapidLink] | None = None) -> RapidStation:
    """A checked station from the YAML structure; missing keys come from ``base`` (default: built-in).

    ``links``: protocol -> ``RapidLink`` of every protocol the station may name (default: ``base``'s,
    the package's own); the station config passes the controller registry's.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping of sections (controller, motion, tool, postures)")
    station = base or default_station()
    changes = {"source": source, **({"links": links} if links is not None else {})}
    for section, keys in _SECTIONS.items():
        values = data.get(section, {}) or {}
        if not isinstance(values, dict):
            raise ConfigError(f"{source}: '{section}' must be a mapping")
        unknown = set(values) - keys
        if unknown:
            raise ConfigError(f"{source}: unknown key(s) in '{section}': {', '.join(sorted(unknown))}; "
                                     f"known: {', '.join(sorted(keys))}")
        prefix = {"tool": "tool_"}.get(section, "")
        for key, value in values.items():
            target = "tool_name" if (section == "tool" and key == "name") else prefix + key
            changes[target] = value
    if "robot" in data:
        changes["robot"] = data["robot"]
    if "postures" in data:
        changes["postures"] = data["postures"]
    if "world_zones" in data:
        changes["world_zones"], changes["zone_tcp"] = check_world_zones(data["world_zones"], source)
    return _checked(replace(station, **changes))


def load_station(path: str | Path, links: Mapping[str, RapidLink] | None = None) -> RapidStation:
    """Read a station YAML file (see the module docstring); ``links`` as in :func:`station_from_dict`."""
    file = Path(path)
    text = read_text_file(file, "station config", ConfigError,
                          missing=f"station config {file} not found; write one (see `handeye rapid generate --help`) "
                                  "or leave --config out to use the built-in mock station")
    data = parse_yaml(text, file, ConfigError)
    return station_from_dict(data or {}, str(file), links=links)


_DEFAULT: RapidStation | None = None


def default_station() -> RapidStation:
    """The built-in station: the mock controller on 127.0.0.1 with 12 approved postures."""
    global _DEFAULT
    if _DEFAULT is None:
        data = parse_yaml(read_text_file(DEFAULT_STATION_FILE, "built-in station", ConfigError), DEFAULT_STATION_FILE, ConfigError)
        _DEFAULT = station_from_dict(data, "built-in station", base=RapidStation())
    return _DEFAULT
