"""The station configuration: one YAML file, validated on load, with the mock station built in.

Sections (``station/example_station.yaml`` documents each one). A file must name its hardware:
``controller.protocol`` and ``camera.backend`` are required, so a config never runs on the built-in
mock station by accident; ``mock`` for both (or ``--mock`` on the command line) selects the embedded
mock station, and every output then says MOCK. Every other key is optional and keeps the built-in value.

``robot``       model name or robot YAML path (joint limits, kinematics)
``controller``  protocol (socket | serial | modbus | mock), host, port, serial_url, modbus_map, timeout_s,
                motion_timeout_s, and for the generated RAPID: pc_address, controller_address,
                serial_channel, ack_timeout_s; for both: idle_timeout_s, write_key (a secret: never
                printed, never stored in a session)
``camera``      backend (xb3 | mock), stereo_model (OpenCV FileStorage; none = nominal XB3 pair),
                nominal_mount (camera in tool0 from the drawing, for planning only), grab_timeout_s
``target``      corners [nx, ny], square_mm
``plan``        postures, start_joints_deg (none = where the robot stands), distance_mm [min, max],
                cone_deg, roll_deg, aim_mm, joint_margin_deg, seed
``motion``      speed_tcp_mm_s, speed_ori_deg_s
``tool``        name, mass_kg, cog_mm
``capture``     per-posture quality: max_row_disagreement_px, max_plane_rms_mm, distance_mm [min, max],
                max_pose_mismatch_mm, retries, save_images
``quality``     thresholds of the calibration verdict (see ``station.quality``)
``output``      folder (where new sessions go)
``mock``        the embedded mock station: protocol (its controller link), seed, kinematic_error_mm,
                kinematic_error_deg, time_scale (used by --mock, a config whose back ends are mock, and the demo)
``postures``    optional fixed approved postures for ``handeye rapid generate`` (capture plans its own)
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from ..calibration.compact_points import BoardGeometry
from ..calibration.errors import HandEyeError, brief
from ..calibration.files import read_text_file
from ..calibration.kinematics import load_robot
from ..calibration.session import parse_yaml
from ..calibration.transforms import pose_from_transform, transform_from_pose

__all__ = ["EXAMPLE_FILE", "ConfigError", "StationConfig", "config_from_dict", "default_config", "load_config"]

EXAMPLE_FILE = Path(__file__).with_name("example_station.yaml")


class ConfigError(HandEyeError):
    """The station configuration file is missing, malformed, or holds a bad value (named by key)."""


#: The back-end name that selects the embedded mock station (controller and camera alike).
MOCK = "mock"
#: Controller link protocols of a real station.
CONTROLLER_PROTOCOLS = ("socket", "serial", "modbus")
#: Camera back ends of a real station.
CAMERA_BACKENDS = ("xb3",)
#: Keys a station file must name: without them a config would silently run on the built-in mock.
REQUIRED_KEYS = (("controller", "protocol", CONTROLLER_PROTOCOLS), ("camera", "backend", CAMERA_BACKENDS))


@dataclass(frozen=True)
class ControllerSettings:
    protocol: str = MOCK
    host: str = "127.0.0.1"
    port: int = 1025
    serial_url: str = "socket://127.0.0.1:1026"
    modbus_map: str | None = None
    timeout_s: float = 2.0
    motion_timeout_s: float = 120.0
    pc_address: str = "127.0.0.1"
    controller_address: str = "127.0.0.1"
    serial_channel: str = "sio1:"
    ack_timeout_s: float = 30.0
    idle_timeout_s: float = 5.0
    write_key: str | None = field(default=None, repr=False)  # a secret: masked in to_dict, never printed


@dataclass(frozen=True)
class CameraSettings:
    backend: str = MOCK
    stereo_model: str | None = None
    nominal_mount: tuple = ((-115.0, 30.0, 95.0), (0.7071068, 0.0, 0.0, 0.7071068))
    grab_timeout_s: float = 2.0

    def nominal_mount_transform(self) -> np.ndarray:
        return transform_from_pose(self.nominal_mount[0], self.nominal_mount[1])


@dataclass(frozen=True)
class PlanSettings:
    postures: int = 30
    start_joints_deg: tuple | None = None
    distance_mm: tuple = (700.0, 1200.0)
    cone_deg: float = 35.0
    roll_deg: float = 40.0
    aim_mm: float = 80.0
    joint_margin_deg: float = 5.0
    seed: int = 0


@dataclass(frozen=True)
class MotionSettings:
    speed_tcp_mm_s: float = 200.0
    speed_ori_deg_s: float = 100.0


@dataclass(frozen=True)
class ToolSettings:
    name: str = "tHeCamera"
    mass_kg: float = 1.8
    cog_mm: tuple = (-60.0, 20.0, 60.0)


@dataclass(frozen=True)
class CaptureSettings:
    max_row_disagreement_px: float = 0.5
    max_plane_rms_mm: float = 1.0
    distance_mm: tuple = (500.0, 1500.0)
    max_pose_mismatch_mm: float = 0.5
    retries: int = 2
    save_images: bool = False


@dataclass(frozen=True)
class MockSettings:
    protocol: str = "socket"
    seed: int = 7
    kinematic_error_mm: float = 0.05
    kinematic_error_deg: float = 0.002
    time_scale: float = 0.02


@dataclass(frozen=True)
class StationConfig:
    """The whole station (see the module docstring for the YAML)."""

    robot: str = "IRB1400"
    controller: ControllerSettings = ControllerSettings()
    camera: CameraSettings = CameraSettings()
    target: BoardGeometry = BoardGeometry((13, 8), 30.0)
    plan: PlanSettings = PlanSettings()
    motion: MotionSettings = MotionSettings()
    tool: ToolSettings = ToolSettings()
    capture: CaptureSettings = CaptureSettings()
    quality: dict = field(default_factory=dict)
    output: str = "sessions"
    mock: MockSettings = MockSettings()
    postures: tuple | None = None
    source: str = "built-in mock station"

    @property
    def is_mock(self) -> bool:
        """True when this configuration runs the embedded mock station (both back ends are ``mock``)."""
        return self.controller.protocol == MOCK

    def as_mock(self) -> "StationConfig":
        """The same settings on the embedded mock station (what ``--mock`` does to a config)."""
        return replace(self, controller=replace(self.controller, protocol=MOCK), camera=replace(self.camera, backend=MOCK))

    @property
    def link_protocol(self) -> str:
        """The controller link actually spoken: the mock station's own protocol when mocked."""
        return self.mock.protocol if self.is_mock else self.controller.protocol

    def rapid_dict(self, postures) -> dict:
        """The mapping ``rapid.station.station_from_dict`` reads, with the given approved postures."""
        c = self.controller
        return {
            "robot": self.robot,
            "controller": {"protocol": self.link_protocol, "pc_address": c.pc_address, "controller_address": c.controller_address,
                           "port": c.port, "serial_channel": c.serial_channel, "ack_timeout_s": c.ack_timeout_s,
                           "idle_timeout_s": c.idle_timeout_s, "write_key": c.write_key},
            "motion": {"speed_tcp_mm_s": self.motion.speed_tcp_mm_s, "speed_ori_deg_s": self.motion.speed_ori_deg_s},
            "tool": {"name": self.tool.name, "mass_kg": self.tool.mass_kg, "cog_mm": list(self.tool.cog_mm)},
            "postures": [[round(float(v), 4) for v in row] for row in np.asarray(postures, float)],
        }

    def to_dict(self) -> dict:
        """A YAML-ready mapping of the whole configuration (for the session record)."""
        out = {"robot": self.robot, "output": self.output, "quality": dict(self.quality),
               "target": {"corners": list(self.target.corners), "square_mm": self.target.square_mm}}
        for name in ("controller", "camera", "plan", "motion", "tool", "capture", "mock"):
            section = {f.name: getattr(getattr(self, name), f.name) for f in fields(getattr(self, name))}
            out[name] = _plain(section)
        out["controller"]["write_key"] = None if self.controller.write_key is None else "<set>"  # never the secret
        out["camera"]["nominal_mount"] = pose_from_transform(self.camera.nominal_mount_transform())
        return out


def _plain(value):
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


#: Largest finite float: ``abs(v) <= _FLOAT_MAX`` is false for NaN, inf and integers too large for a
#: float (where ``math.isfinite`` would raise OverflowError).
_FLOAT_MAX = sys.float_info.max


def _number(value, key: str, low: float = -math.inf, high: float = math.inf, integer: bool = False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) <= _FLOAT_MAX:
        raise ConfigError(f"{key} must be a {'whole ' if integer else ''}number; got {brief(value)}")
    if integer and int(value) != value:
        raise ConfigError(f"{key} must be a whole number; got {brief(value)}")
    if not low <= value <= high:
        raise ConfigError(f"{key} must be between {low:g} and {high:g}; got {brief(value)}")
    return int(value) if integer else float(value)


def _numbers(value, key: str, count: int, low=-math.inf, high=math.inf) -> tuple:
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise ConfigError(f"{key} must be a list of {count} numbers; got {brief(value)}")
    return tuple(_number(v, f"{key}[{i}]", low, high) for i, v in enumerate(value))


def _range(value, key: str, low=0.0, high=math.inf) -> tuple:
    pair = _numbers(value, key, 2, low, high)
    if pair[0] >= pair[1]:
        raise ConfigError(f"{key} must be [min, max] with min < max; got {list(value)!r}")
    return pair


def _text(value, key: str, choices=None) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{key} must be a text; got {brief(value)}")
    if choices and value not in choices:
        raise ConfigError(f"{key} must be one of {', '.join(choices)}; got {brief(value)}")
    return value


def _write_key(value, key: str) -> str | None:
    """The write key, checked without ever echoing it (one protocol word, one RAPID string)."""
    if value is None:
        return None
    if not isinstance(value, str):
        raise ConfigError(f"{key} must be a text of 8 to 32 letters, digits, '_' or '-' (quote it in YAML); "
                          f"got a {type(value).__name__}")
    if not re.fullmatch(r"[A-Za-z0-9_-]{8,32}", value):
        raise ConfigError(f"{key} must be 8 to 32 letters, digits, '_' or '-'; got another value of {len(value)} "
                          "characters (the key itself is never printed)")
    return value


def _section(data: dict, name: str, allowed) -> dict:
    section = data.get(name) or {}
    if not isinstance(section, dict):
        raise ConfigError(f"{name} must be a mapping of keys; got {brief(section)}")
    unknown = sorted(set(section) - set(allowed), key=brief)
    if unknown:
        key = unknown[0] if isinstance(unknown[0], str) and unknown[0].isprintable() else brief(unknown[0])
        raise ConfigError(f"unknown key {name}.{key}; known keys of {name}: {', '.join(sorted(allowed))}")
    return section


def _mount(value, key: str) -> tuple:
    if not isinstance(value, dict) or "position_mm" not in value or "quaternion_wxyz" not in value:
        raise ConfigError(f"{key} needs position_mm and quaternion_wxyz")
    position = _numbers(value["position_mm"], f"{key}.position_mm", 3, -1000, 1000)
    quaternion = _numbers(value["quaternion_wxyz"], f"{key}.quaternion_wxyz", 4, -1, 1)
    if abs(math.sqrt(sum(q * q for q in quaternion)) - 1) > 1e-3:
        raise ConfigError(f"{key}.quaternion_wxyz must have norm 1; got {list(quaternion)}")
    return position, quaternion


TOP_LEVEL = {"robot", "controller", "camera", "target", "plan", "motion", "tool", "capture", "quality", "output", "mock",
             "postures"}


def config_from_dict(data: dict, source: str = "configuration") -> StationConfig:
    """Validate a mapping (as read from YAML) into a :class:`StationConfig`.

    Raises
    ------
    ConfigError
        Naming the key at fault (``camera.nominal_mount.position_mm[2]``) and what it must be.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: the file must hold a mapping of sections")
    unknown = sorted(set(data) - TOP_LEVEL, key=brief)
    if unknown:
        raise ConfigError(f"unknown section {brief(unknown[0])}; known: {', '.join(sorted(TOP_LEVEL))}")
    base = StationConfig(source=source)
    changes: dict = {}
    if "robot" in data:
        name = _text(data["robot"], "robot")
        try:
            load_robot(name)
        except ValueError as exc:
            raise ConfigError(f"robot: {exc}") from None
        changes["robot"] = name

    def settings(name, cls, convert):
        section = _section(data, name, {f.name for f in fields(cls)})
        values = {key: convert(key, value, f"{name}.{key}") for key, value in section.items()}
        return replace(getattr(base, name), **values)

    def controller_value(key, value, path):
        if key == "protocol":
            return _text(value, path, CONTROLLER_PROTOCOLS + (MOCK,))
        if key == "port":
            return _number(value, path, 1, 65535, integer=True)
        if key in ("timeout_s", "motion_timeout_s", "ack_timeout_s"):
            return _number(value, path, 0.001, 3600)
        if key == "idle_timeout_s":
            return _number(value, path, 0.1, 10)
        if key == "write_key":
            return _write_key(value, path)
        if key == "modbus_map":
            return None if value is None else _text(value, path)
        return _text(value, path)

    def camera_value(key, value, path):
        if key == "backend":
            return _text(value, path, CAMERA_BACKENDS + (MOCK,))
        if key == "stereo_model":
            return None if value is None else _text(value, path)
        if key == "nominal_mount":
            return _mount(value, path)
        return _number(value, path, 0.001, 60)

    def plan_value(key, value, path):
        if key == "postures":
            return _number(value, path, 3, 255, integer=True)
        if key == "seed":
            return _number(value, path, 0, 2**31, integer=True)
        if key == "start_joints_deg":
            if value is None:
                return None
            joints = _numbers(value, path, 6, -360, 360)
            problems = load_robot(changes.get("robot", base.robot)).limit_violations(joints)
            if problems:
                raise ConfigError(f"{path}: {problems[0]}")
            return joints
        if key == "distance_mm":
            return _range(value, path, 100, 5000)
        if key in ("cone_deg", "roll_deg"):
            return _number(value, path, 0, 90)
        if key == "aim_mm":
            return _number(value, path, 0, 500)
        return _number(value, path, 0, 45)

    def motion_value(key, value, path):
        return _number(value, path, 1, 7000 if key == "speed_tcp_mm_s" else 1000)

    def tool_value(key, value, path):
        if key == "name":
            name = _text(value, path)
            if not (name[0].isalpha() and name.replace("_", "a").isalnum() and len(name) <= 32):
                raise ConfigError(f"{path} must be a RAPID identifier (letter first, letters/digits/_, <= 32); got {name!r}")
            return name
        if key == "mass_kg":
            return _number(value, path, 1e-3, 100)
        return _numbers(value, path, 3, -1000, 1000)

    def capture_value(key, value, path):
        if key == "distance_mm":
            return _range(value, path, 100, 5000)
        if key == "retries":
            return _number(value, path, 0, 10, integer=True)
        if key == "save_images":
            if not isinstance(value, bool):
                raise ConfigError(f"{path} must be true or false; got {brief(value)}")
            return value
        return _number(value, path, 0, 1000)

    def mock_value(key, value, path):
        if key == "protocol":
            return _text(value, path, CONTROLLER_PROTOCOLS)
        if key == "seed":
            return _number(value, path, 0, 2**31, integer=True)
        if key == "time_scale":
            return _number(value, path, 1e-4, 10)
        return _number(value, path, 0, 10)

    changes["controller"] = settings("controller", ControllerSettings, controller_value)
    changes["camera"] = settings("camera", CameraSettings, camera_value)
    changes["plan"] = settings("plan", PlanSettings, plan_value)
    changes["motion"] = settings("motion", MotionSettings, motion_value)
    changes["tool"] = settings("tool", ToolSettings, tool_value)
    changes["capture"] = settings("capture", CaptureSettings, capture_value)
    changes["mock"] = settings("mock", MockSettings, mock_value)
    if "target" in data:
        target = _section(data, "target", {"corners", "square_mm", "type"})
        corners = target.get("corners", list(base.target.corners))
        if (not isinstance(corners, list) or len(corners) != 2
                or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 2 for c in corners)):
            raise ConfigError(f"target.corners must be two whole numbers >= 2; got {brief(corners)}")
        square = _number(target.get("square_mm", base.target.square_mm), "target.square_mm", 1, 500)
        changes["target"] = BoardGeometry((max(corners), min(corners)), square)
    if "quality" in data:
        quality = data["quality"] or {}
        if not isinstance(quality, dict):
            raise ConfigError(f"quality must be a mapping of thresholds; got {brief(quality)}")
        changes["quality"] = dict(quality)
    if "output" in data:
        changes["output"] = _text(data["output"], "output")
    if data.get("postures") is not None:
        rows = data["postures"]
        if not isinstance(rows, list) or not rows:
            raise ConfigError("postures must be a list of joint-angle rows [a1, ..., a6]")
        robot = load_robot(changes.get("robot", base.robot))
        checked = []
        for i, row in enumerate(rows):
            joints = _numbers(row, f"postures[{i}]", robot.dof, -360, 360)
            problems = robot.limit_violations(joints)
            if problems:
                raise ConfigError(f"posture {i + 1}: {problems[0]} (postures are numbered from 1)")
            checked.append(joints)
        changes["postures"] = tuple(checked)
    config = replace(base, **changes)
    _check_quality(config.quality)
    _check_hardware_named(data, config)
    return config


def _check_hardware_named(data: dict, config: StationConfig) -> None:
    """Refuse a config that names no controller or camera, or mixes the mock with real hardware."""
    for section, key, real in REQUIRED_KEYS:
        if not isinstance(data.get(section), dict) or key not in data[section]:
            raise ConfigError(f"{section}.{key} is missing: name the station's {section} ({' | '.join(real)}), "
                              f"or {MOCK} for the embedded mock station")
    if (config.controller.protocol == MOCK) != (config.camera.backend == MOCK):
        raise ConfigError(f"controller.protocol is {config.controller.protocol} but camera.backend is {config.camera.backend}: "
                          f"the mock camera only sees the mock robot; set both to {MOCK}, or neither")


def _check_quality(quality: dict) -> None:
    """Validate the verdict thresholds with the report's own checker when it is available."""
    try:
        from .quality import QualityThresholds
    except ImportError:  # pragma: no cover - the verdict module ships with the station
        return
    try:
        QualityThresholds.from_dict(quality)
    except HandEyeError as exc:
        raise ConfigError(f"quality: {exc}") from None


def load_config(path) -> StationConfig:
    """Read and validate a station YAML file.

    Raises
    ------
    ConfigError
    """
    path = Path(path)
    text = read_text_file(path, "station configuration", ConfigError,
                          missing=f"no station configuration at {path}; start from {EXAMPLE_FILE}")
    data = parse_yaml(text, path, ConfigError)
    return config_from_dict(data or {}, str(path))


def default_config() -> StationConfig:
    """The built-in station: the embedded mock controller and camera on 127.0.0.1."""
    return StationConfig()
