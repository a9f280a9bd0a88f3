"""The station configuration: one YAML file, validated on load, with the mock station built in.

A file must name its hardware: ``controller.protocol`` and ``camera.backend`` are required, so a
config never runs on the built-in mock station by accident; ``mock`` for both (or ``--mock`` on the
command line) selects the embedded mock station, and every output then says MOCK. Every other key is
optional and keeps the built-in value.

Every key is declared once, below, on the settings dataclasses (:func:`~handeye.station.config.schema.setting`):
its default, its rule (type, range or choices), its unit and what it is for. The choices of
``controller.protocol``, ``camera.backend`` and ``mock.protocol`` are the registered back ends
(:mod:`handeye.drivers.controller.backends`, :mod:`handeye.drivers.camera.backends`), plug-ins
included. ``src/handeye/station/config/example_station.yaml`` documents every key (a test holds it to the schema);
:func:`describe_keys` lists them.

Sections: ``robot``, ``controller`` (the link and the generated RAPID program), ``camera``,
``target``, ``plan`` (posture planning), ``motion``, ``tool`` (the PERS tooldata written back),
``capture`` (per-posture quality), ``cell`` and ``guided`` (the cell's keep-out volumes and
carried geometry, the operator-guided capture: ``station.config.cell``), ``quality`` (the
verdict's thresholds, see ``station.report.quality``), ``verify`` (the change a check acts on), ``output``, ``mock`` (the embedded mock station) and ``postures`` (fixed approved postures for
``handeye rapid generate``; capture plans its own).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import TYPE_CHECKING, ClassVar
from pathlib import Path

import numpy as np

from ...geometry import STATION_BOARD, BoardGeometry
from ...base import ConfigError, HandEyeError, brief
from ...base import read_text_file
from ...robot import load_robot
from ...base import parse_yaml
from ...geometry import pose_from_transform, transform_from_pose
from ...base import WRITE_KEY_PATTERN
from ...drivers import DEFAULT_PROTOCOL
from ..cell.plan import base_problem
from .cell import CellSettings, GuidedSettings
from ..plant.settings import PlantSettings, plant_rule
if TYPE_CHECKING:
    from ...mocks import Occlusion

from .schema import (
    Custom,
    Flag,
    Number,
    Numbers,
    Optional,
    Range,
    Text,
    check_section,
    chosen_of,
    declared_fields,
    numbers,
    key_rule,
    rule_of,
    schema_keys,
    secret_fields,
    section,
    setting,
    text,
)

__all__ = ["EXAMPLE_FILE", "MOCK", "ConfigError", "StationConfig", "config_from_dict", "default_config", "load_config",
           "describe_keys", "controller_protocols", "camera_backends", "mock_protocols", "protocol_choices", "camera_choices"]

EXAMPLE_FILE = Path(__file__).with_name("example_station.yaml")
REHEARSAL_FILE = Path(__file__).with_name("rehearsal_station.yaml")

#: The back-end name that selects the embedded mock station (controller and camera alike).
MOCK = "mock"
#: Bounds of every ``seed``.
SEED_MAX = 2**31


def controller_protocols() -> tuple[str, ...]:
    """Controller link protocols of a real station: every registered controller back end (plug-ins
    listed from their metadata, none imported)."""
    from ...drivers import CONTROLLERS

    return CONTROLLERS.names()


def camera_backends() -> tuple[str, ...]:
    """Camera back ends of a real station: every registered camera back end that is not simulated
    (which loads every camera plug-in, under the time bound: for listing them)."""
    from ...drivers import CAMERAS

    return CAMERAS.names(lambda backend: not backend.simulated)


def mock_protocols() -> tuple[str, ...]:
    """Controller links the embedded mock station can speak: the back ends a mock serves."""
    from ...mocks import mock_protocols

    return mock_protocols()


def protocol_choices():
    """What ``controller.protocol`` may be: a controller back end, or mock (checking one imports that
    plug-in only: :class:`~handeye.base.registry.Choices`)."""
    from ...drivers import CONTROLLERS

    return CONTROLLERS.choices(extra=(MOCK,))


def camera_choices():
    """What ``camera.backend`` may be: a camera back end that is not simulated, or mock."""
    from ...drivers import CAMERAS

    return CAMERAS.choices(lambda backend: not backend.simulated, extra=(MOCK,),
                           lacking="is simulated (a real station needs a real camera)")


def _mock_protocol_choices():
    """What ``mock.protocol`` may be: a controller back end a mock serves."""
    from ...mocks import mock_protocol_choices

    return mock_protocol_choices()


# ---------------------------------------------------------------------------------- checks of their own
def _write_key(value, key: str, context) -> str | None:
    """The write key, checked without ever echoing it (one protocol word, one RAPID string)."""
    if value is None:
        return None
    if not isinstance(value, str):
        raise ConfigError(f"{key} must be a text of 8 to 32 letters, digits, '_' or '-' (quote it in YAML); "
                          f"got a {type(value).__name__}")
    if not WRITE_KEY_PATTERN.fullmatch(value):
        raise ConfigError(f"{key} must be 8 to 32 letters, digits, '_' or '-'; got another value of {len(value)} "
                          "characters (the key itself is never printed)")
    return value


def _link_settings(chosen=None) -> dict:
    """``key -> (LinkSetting, back-end names)`` of the controller back ends a section on ``chosen`` may set
    (:func:`_section_backends`)."""
    from ...drivers import CONTROLLERS, link_settings  # noqa: PLC0415

    return link_settings(_section_backends(CONTROLLERS, chosen))


def _camera_settings(chosen=None) -> dict:
    """``key -> (Setting, back-end names)`` of the camera back ends a section on ``chosen`` may set."""
    from ...drivers import CAMERAS, camera_settings  # noqa: PLC0415

    return camera_settings(_section_backends(CAMERAS, chosen))


def _section_backends(registry, chosen) -> tuple[str, ...]:
    """The back ends whose settings a section naming ``chosen`` takes: handeye's own and ``chosen``
    (no other plug-in is imported to check or read a file); ``None`` (the schema, documenting every key):
    every back end, plug-ins loaded under the time bound."""
    from ...drivers import chosen_with_own  # noqa: PLC0415

    return registry.names() if chosen is None else chosen_with_own(registry, chosen)


def _checked_by(check: Callable, rule) -> Callable:
    """A rule that runs ``rule`` and then a back end's own ``check(value, name)`` (its ValueError, the
    controllers' InvalidRequest included, becomes a ConfigError)."""

    def checked(value, key: str, context):
        value = rule(value, key, context)
        try:
            return check(value, key)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None

    return checked


def declared_setting_fields(declared: dict, own=()) -> tuple:
    """The keys back ends declare (``{key: (Setting, back-end names)}``: ``ControllerBackend.link_settings``,
    ``CameraBackend.settings``) as :func:`~handeye.station.config.schema.setting` fields: rule from the type and
    range, the back ends' names in front of the doc, secret as declared. A key that is one of the
    section's ``own`` fields is left out: the back end reads the section's own value."""
    out = []
    for key, (declared_setting, names) in declared.items():
        if key in own:
            continue
        kinds = {int: Number(declared_setting.low, declared_setting.high, integer=True),
                 float: Number(declared_setting.low, declared_setting.high)}
        rule = kinds.get(declared_setting.type, Text())
        if declared_setting.check is not None:
            rule = Custom(_checked_by(declared_setting.check, rule))
        if declared_setting.default is None:
            rule = Optional(rule)
        made = setting(declared_setting.default, rule, f"{', '.join(names)}: {declared_setting.help}",
                       secret=declared_setting.secret)
        made.name = key
        out.append(made)
    return tuple(out)


def _own_keys(cls) -> set:
    return {f.name for f in fields(cls)}


class _DeclaredByBackEnds:
    """A section that also takes the keys its back ends declare (``_declared()``: ``{key: (Setting,
    names)}``): kept by key in ``backend_settings``, read as attributes (``section.serial_url``, the
    declared default when the file names none); a key no back end declares is refused."""

    EXTRA_FIELD: ClassVar[str] = "backend_settings"
    #: The key naming the section's back end: the keys a file may set are its settings and those of
    #: handeye's own back ends (no other plug-in is imported to check a file).
    CHOSEN_BY: ClassVar[str] = ""
    _WHAT: ClassVar[str] = ""
    #: ``_declared(chosen) -> {key: (Setting, back-end names)}`` (each section's own: a staticmethod).
    _declared: ClassVar[Callable[[str | None], dict]]

    @classmethod
    def extra_settings(cls, chosen: str | None = None) -> tuple:
        """The keys the back ends declare (:func:`declared_setting_fields`): handeye's own and ``chosen``'s."""
        return declared_setting_fields(cls._declared(chosen), _own_keys(cls))

    def __getattr__(self, name: str):
        if name.startswith("_") or name == "backend_settings":
            raise AttributeError(name)
        declared = type(self)._declared(self.__dict__.get(self.CHOSEN_BY, "")).get(name)
        if declared is None:
            raise AttributeError(f"no {self._WHAT} key {name!r}")
        return self.__dict__.get("backend_settings", {}).get(name, declared[0].default)


def _mount(value, key: str, context) -> tuple:
    if not isinstance(value, dict) or "position_mm" not in value or "quaternion_wxyz" not in value:
        raise ConfigError(f"{key} needs position_mm and quaternion_wxyz")
    position = numbers(value["position_mm"], f"{key}.position_mm", 3, -1000, 1000)
    quaternion = numbers(value["quaternion_wxyz"], f"{key}.quaternion_wxyz", 4, -1, 1)
    if abs(math.sqrt(sum(q * q for q in quaternion)) - 1) > 1e-3:
        raise ConfigError(f"{key}.quaternion_wxyz must have norm 1; got {list(quaternion)}")
    return position, quaternion


def _joints(value, key: str, context) -> tuple:
    """One posture: as many angles as the config's robot has axes, within its joint limits."""
    robot = load_robot(context["robot"])
    joints = numbers(value, key, robot.dof, -360, 360)
    problems = robot.limit_violations(joints)
    if problems:
        raise ConfigError(f"{key}: {problems[0]}")
    return joints


def _mock_arm(value, key: str, context) -> str:
    """``HOST:PORT`` of a standalone mock controller's camera port."""
    address = text(value, key)
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"{key} must be HOST:PORT (where `handeye mock controller --camera-port PORT` serves its "
                          f"camera); got {brief(value)}")
    return address


def _rapid_name(value, key: str, context) -> str:
    name = text(value, key)
    if not (name[0].isalpha() and name.replace("_", "a").isalnum() and len(name) <= 32):
        raise ConfigError(f"{key} must be a RAPID identifier (letter first, letters/digits/_, <= 32); got {brief(name)}")
    return name


def _robot(value, key: str, context) -> str:
    name = text(value, key)
    try:
        load_robot(name)
    except ValueError as exc:
        raise ConfigError(f"robot: {exc}") from None
    context["robot"] = name  # the keys checked after it (postures, start joints) use its model
    return name


def _corners(value, key: str, context) -> tuple:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 2 for c in value)):
        raise ConfigError(f"{key} must be two whole numbers >= 2; got {brief(value)}")
    return max(value), min(value)


def _quality(value, key: str, context) -> dict:
    quality = value or {}
    if not isinstance(quality, dict):
        raise ConfigError(f"quality must be a mapping of thresholds; got {brief(quality)}")
    return dict(quality)


def _postures(value, key: str, context) -> tuple:
    robot = load_robot(context["robot"])
    if not isinstance(value, list) or not value:
        axes = ", ..., ".join(f"a{i}" for i in (1, robot.dof))
        raise ConfigError(f"postures must be a list of joint-angle rows [{axes}]")
    checked = []
    for i, row in enumerate(value):
        joints = numbers(row, f"postures[{i}]", robot.dof, -360, 360)
        problems = robot.limit_violations(joints)
        if problems:
            raise ConfigError(f"posture {i + 1}: {problems[0]} (postures are numbered from 1)")
        checked.append(joints)
    return tuple(checked)


def _as_is(value, key: str, context):
    return value


# ---------------------------------------------------------------------------------- the sections
@dataclass(frozen=True)
class ControllerSettings(_DeclaredByBackEnds):
    """``controller``: the robot controller's link, and the settings of the generated RAPID program."""

    protocol: str = setting(MOCK, Text(protocol_choices),
                            "link protocol: a registered controller back end, or mock", required=True)
    host: str = setting("127.0.0.1", Text(what="the controller's IP address or host name"),
                        "address of the controller (or of its gateway)")
    port: int | None = setting(None, Optional(Number(1, 65535, integer=True)),
                               "TCP port (null: the back end's own default port)")
    timeout_s: float = setting(2.0, Number(0.001, 3600), "budget of one request", "s")
    motion_timeout_s: float = setting(120.0, Number(0.001, 3600), "budget for a move to a posture", "s")
    pc_address: str = setting("127.0.0.1", Text(), "RAPID: the only client the socket server accepts (this PC)")
    controller_address: str = setting("127.0.0.1", Text(), "RAPID: address the server binds (auto: GetSysInfo)")
    serial_channel: str = setting("sio1:", Text(), "RAPID: the serial variant's channel")
    ack_timeout_s: float = setting(30.0, Number(0.001, 3600), "RAPID: warn (LATE) when a posture is not acknowledged",
                                   "s")
    idle_timeout_s: float = setting(5.0, Number(0.1, 10), "RAPID and PC: a link silent this long is dropped", "s")
    write_key: str | None = setting(None, Custom(_write_key), "the secret tool-data writes need (8-32 letters, "
                                    "digits, _ or -; HeKey.sys)", secret=True)
    #: The back ends' own settings a file sets (``serial_url``, ``modbus_map`` ...), by key: declared
    #: by each back end (``ControllerBackend.link_settings``), read as attributes (``c.serial_url``).
    backend_settings: dict = field(default_factory=dict, hash=False, repr=False)  # may hold secrets

    _WHAT: ClassVar[str] = "controller"
    CHOSEN_BY: ClassVar[str] = "protocol"
    _declared = staticmethod(_link_settings)


@dataclass(frozen=True)
class CameraSettings(_DeclaredByBackEnds):
    """``camera``: the stereo head, and the settings its back end declares (``CameraBackend.settings``)."""

    backend: str = setting(MOCK, Text(camera_choices),
                           "camera back end: a registered one (xb3), or mock", required=True)
    stereo_model: str | None = setting(None, Optional(Text()), "OpenCV FileStorage of the stereo pair "
                                       "(null: the nominal XB3 model)")
    nominal_mount: tuple = setting(((-115.0, 30.0, 95.0), (0.7071068, 0.0, 0.0, 0.7071068)), Custom(_mount),
                                   "camera in tool0 from the drawing, for planning only (position_mm, "
                                   "quaternion_wxyz)", "mm")
    grab_timeout_s: float = setting(2.0, Number(0.001, 60), "budget of one grab", "s")
    mock_arm: str | None = setting(None, Optional(Custom(_mock_arm)), "rehearsal only (backend mock with a real "
                                   "controller protocol): HOST:PORT where `handeye mock controller --camera-port` "
                                   "serves the simulated XB3 on its arm")
    #: The back ends' own settings a file sets (``guid`` ...), by key: declared by each camera back end
    #: (``CameraBackend.settings``), read as attributes (``camera.guid``).
    backend_settings: dict = field(default_factory=dict, hash=False, repr=False)

    _WHAT: ClassVar[str] = "camera"
    CHOSEN_BY: ClassVar[str] = "backend"
    _declared = staticmethod(_camera_settings)

    def nominal_mount_transform(self) -> np.ndarray:
        return transform_from_pose(self.nominal_mount[0], self.nominal_mount[1])


def _target_kinds() -> tuple:
    from ...geometry import TARGETS

    return TARGETS.names()


def _squares(value, key: str, context) -> tuple:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 3 for c in value)):
        raise ConfigError(f"{key} must be two whole numbers >= 3; got {brief(value)}")
    return tuple(value)


def _occlude(value: object, key: str, context) -> Occlusion:
    """``mock.occlude``: ``{postures: share 0..1, band: [min, max] fraction of the board}`` (``mocks.printed_targets``)."""
    from ...mocks import Occlusion

    if not isinstance(value, dict):
        raise ConfigError(f"{key} must be a mapping like {{postures: 0.3, band: [0.2, 0.4]}}; got {brief(value)}")
    unknown = sorted(set(value) - {"postures", "band"}, key=brief)
    if unknown:
        raise ConfigError(f"unknown key {key}.{unknown[0]}; known keys of {key}: band, postures")
    share = Number(0, 1)(value.get("postures", 0.3), f"{key}.postures", context)
    band = Range(0.01, 1)(value.get("band", [0.2, 0.4]), f"{key}.band", context)
    return Occlusion(float(share), tuple(float(b) for b in band))


@dataclass(frozen=True)
class TargetSettings:
    """``target``: the checkerboard (kept as a :class:`BoardGeometry`)."""

    type: str = setting("checkerboard", Text(_target_kinds), "checkerboard, charuco or circles (the target registry; "
                        "`board:` is the same section)")
    corners: tuple = setting(STATION_BOARD.corners, Custom(_corners), "inner corners along x (the long side), along y "
                             "(circles: circles per row, rows)")
    square_mm: float = setting(STATION_BOARD.square_mm, Number(1, 500), "square size (circles: spacing in a row)", "mm")
    squares: tuple | None = setting(None, Optional(Custom(_squares)), "charuco: squares along x, along y (corners = "
                                    "squares - 1; give one of the two)")
    marker_mm: float | None = setting(None, Optional(Number(0.1, 500)), "charuco: marker side (default 22)", "mm")
    dictionary: str | None = setting(None, Optional(Text()), "charuco: OpenCV ArUco dictionary (default DICT_5X5_100)")
    legacy: bool = setting(False, Flag(), "charuco: OpenCV's layout before 4.6 (even square rows start white)")
    diameter_mm: float | None = setting(None, Optional(Number(0.1, 500)), "circles: circle diameter (informative)", "mm")


@dataclass(frozen=True)
class PlanSettings:
    """``plan``: how capture plans its postures."""

    postures: int = setting(30, Number(3, 255, integer=True), "postures to plan")
    start_joints_deg: tuple | None = setting(None, Optional(Custom(_joints)), "where planning starts (null: where "
                                             "the robot stands)", "deg")
    distance_mm: tuple = setting((700.0, 1200.0), Range(100, 5000), "camera to board centre [min, max]", "mm")
    cone_deg: float = setting(35.0, Number(0, 90), "largest view angle from the board normal", "deg")
    roll_deg: float = setting(40.0, Number(0, 90), "largest roll about the optical axis", "deg")
    aim_mm: float = setting(80.0, Number(0, 500), "spread of the aim point over the board", "mm")
    joint_margin_deg: float = setting(5.0, Number(0, 45), "distance kept from every joint limit", "deg")
    seed: int = setting(0, Number(0, SEED_MAX, integer=True), "seed of the planner")
    partial_views: bool = setting(True, Flag(), "ChArUco: plan postures with part of the board out of view where "
                                  "they widen the rotation spread (never a checkerboard)")


@dataclass(frozen=True)
class MotionSettings:
    """``motion``: the speed of the posture moves (RAPID speeddata)."""

    speed_tcp_mm_s: float = setting(200.0, Number(1, 7000), "TCP speed", "mm/s")
    speed_ori_deg_s: float = setting(100.0, Number(1, 1000), "reorientation speed", "deg/s")
    speed_override_pct: float = setting(100.0, Number(1, 100), "RAPID VelSet override of the posture moves "
                                        "(100: as programmed)", "%")


@dataclass(frozen=True)
class ToolSettings:
    """``tool``: the PERS tooldata of the camera, written back after calibration."""

    name: str = setting("tHeCamera", Custom(_rapid_name), "the PERS tooldata's name (a RAPID identifier)")
    mass_kg: float = setting(1.8, Number(1e-3, 100), "camera and bracket", "kg")
    cog_mm: tuple = setting((-60.0, 20.0, 60.0), Numbers(3, -1000, 1000), "centre of gravity in tool0", "mm")


@dataclass(frozen=True)
class CaptureSettings:
    """``capture``: when a posture's measurement is good enough (else retried, then skipped)."""

    max_row_disagreement_px: float = setting(0.5, Number(0, 1000), "left/right corner rows after rectification", "px")
    max_plane_rms_mm: float = setting(1.0, Number(0, 1000), "corners off their fitted plane", "mm")
    distance_mm: tuple = setting((500.0, 1500.0), Range(100, 5000), "board distance [min, max]", "mm")
    max_pose_mismatch_mm: float = setting(0.5, Number(0, 1000), "controller flange pose vs our kinematics", "mm")
    retries: int = setting(2, Number(0, 10, integer=True), "grabs again before a posture is skipped")
    save_images: bool = setting(False, Flag(), "keep the left/right PNGs in SESSION/images")


@dataclass(frozen=True)
class VerifySettings:
    """``verify``: the change ``handeye verify`` acts on (``station.verify.tolerance``). A drift must be
    beyond the noise (the test at ``--level``) and larger than these; null: the station's quality
    thresholds ``max_sigma_translation_mm`` / ``max_sigma_rotation_deg`` (a change smaller than the
    uncertainty a passing calibration may have does not matter)."""

    tolerance_mm: float | None = setting(None, Optional(Number(0, 100)), "smallest change that is acted on (camera "
                                         "or board shift; null: quality max_sigma_translation_mm)", "mm")
    tolerance_deg: float | None = setting(None, Optional(Number(0, 10)), "smallest turn that is acted on (camera, "
                                          "board or a joint's zero; null: quality max_sigma_rotation_deg)", "deg")


@dataclass(frozen=True)
class KinematicsSettings:
    """``kinematics``: identify the arm's joint zeros and link lengths with the camera after a capture (the
    demo and ``calibrate --kinematics``), and the stand-off where the predicted error is stated."""

    identify: bool = setting(False, Flag(), "identify the arm's kinematic deviations with the camera")
    standoff_mm: float = setting(750.0, Number(1, 5000), "the inspection stand-off along the camera axis", "mm")


@dataclass(frozen=True)
class FaultSettings:
    """``mock.faults``: what changed at the mock station since its calibration (``handeye verify``
    finds it); all zero: nothing."""

    camera_shift_mm: tuple = setting((0.0, 0.0, 0.0), Numbers(3, -100, 100), "the camera moved on the flange "
                                     "(tool0 axes)", "mm")
    camera_turn_deg: tuple = setting((0.0, 0.0, 0.0), Numbers(3, -30, 30), "the camera turned about its origin "
                                     "(rotation vector, tool0 axes)", "deg")
    board_shift_mm: tuple = setting((0.0, 0.0, 0.0), Numbers(3, -100, 100), "the board moved (base axes)", "mm")
    board_turn_deg: tuple = setting((0.0, 0.0, 0.0), Numbers(3, -30, 30), "the board turned about its first inner "
                                    "corner (rotation vector, base axes)", "deg")
    joint_zero_deg: tuple = setting((0.0,) * 6, Numbers(6, -10, 10), "each axis stands this much further than "
                                    "its controller angle (a zero moved)", "deg")

    def model(self):
        """The mock's :class:`~handeye.mocks.drift.StationFaults`."""
        from ...mocks import StationFaults

        return StationFaults(**{f.name: tuple(float(v) for v in getattr(self, f.name)) for f in fields(self)})


def _link_mm(value, key: str, context) -> dict:
    from ...mocks import LINK_NAMES
    from .schema import number as schema_number

    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ConfigError(f"{key} must be a mapping of DH lengths to mm, e.g. {{a2: 0.2, d4: -0.1}}; got {brief(value)}")
    out = {}
    for name, length in value.items():
        if name not in LINK_NAMES:
            raise ConfigError(f"{key}.{name} is not a DH length: use d1..d6 or a1..a6")
        out[name] = schema_number(length, f"{key}.{name}", -10, 10)
    return out


@dataclass(frozen=True)
class ArmSettings:
    """``mock.arm``: the mock arm's true deviations from its DH table, given explicitly (a truth to compare
    ``calibrate --kinematics`` with); both left out: random ones (``mock.kinematic_error_mm`` / ``_deg``).
    Given, they replace the random ones. Not ``mock.faults``: this is the arm as it is, not what changed."""

    joint_zero_deg: tuple | None = setting(None, Optional(Numbers(6, -10, 10)), "each axis stands this much further "
                                           "than its controller angle (zero offsets of axes 1-6; null: random)", "deg")
    link_mm: dict = setting(None, Custom(_link_mm), "DH length deviations by name (d1..d6, a1..a6)", "mm",
                            factory=dict)

    def model(self):
        """The mock's :class:`~handeye.mocks.arm_truth.ArmDeviations`, or None when nothing is given."""
        if self.joint_zero_deg is None and not self.link_mm:
            return None
        from ...mocks import ArmDeviations

        zero = (0.0,) * 6 if self.joint_zero_deg is None else tuple(float(v) for v in self.joint_zero_deg)
        return ArmDeviations(zero, dict(self.link_mm))


@dataclass(frozen=True)
class MockSettings:
    """``mock``: the embedded mock station (``--mock``, mock back ends, the demo)."""

    protocol: str = setting(DEFAULT_PROTOCOL, Text(_mock_protocol_choices), "its controller link: a back end a mock serves")
    seed: int = setting(7, Number(0, SEED_MAX, integer=True), "seeds the arm's errors and the sensor noise")
    kinematic_error_mm: float = setting(0.05, Number(0, 10), "the simulated arm's DH length errors", "mm")
    kinematic_error_deg: float = setting(0.002, Number(0, 10), "the simulated arm's DH angle errors", "deg")
    time_scale: float = setting(0.02, Number(1e-4, 10), "wall-clock seconds per simulated second of motion")
    faults: FaultSettings = section(FaultSettings, "what changed since the calibration (handeye verify)")
    arm: ArmSettings = section(ArmSettings, "the arm's true kinematic deviations (null: random)")
    occlude: Occlusion | None = setting(None, Optional(Custom(_occlude)), "a band over the board at a share of the postures "
                              "({postures: 0.3, band: [0.2, 0.4]}; null: none)")


def _target(value, key: str, context) -> BoardGeometry:
    checked = check_section(TargetSettings, value or {}, key, context)
    default = TargetSettings()
    kind = checked.get("type", "checkerboard").lower()
    if kind == "checkerboard":
        extra = sorted(k for k, v in checked.items() if k not in ("type", "corners", "square_mm") and v not in (None, False))
        if extra:
            raise ConfigError(f"{key}.{extra[0]} is a key of a charuco or circles target, not of a checkerboard")
        return BoardGeometry(checked.get("corners", default.corners), checked.get("square_mm", default.square_mm))
    from ...geometry import target_from_dict

    raw = {k: (list(v) if isinstance(v, tuple) else v) for k, v in (value or {}).items() if v is not None}
    raw["type"] = kind
    try:
        return target_from_dict(raw)
    except ValueError as exc:
        raise ConfigError(f"{key}: {exc}") from None


@dataclass(frozen=True)
class StationConfig:
    """The whole station; each field is a top-level key of the YAML (``source``: where it was read)."""

    robot: str = setting("IRB1400", Custom(_robot), "robot model (robot/robots/*.yaml) or a robot YAML path")
    controller: ControllerSettings = section(ControllerSettings, "the controller")
    camera: CameraSettings = section(CameraSettings, "the camera")
    target: BoardGeometry = setting(STATION_BOARD, Custom(_target), "the checkerboard",
                                    keys=TargetSettings)
    plan: PlanSettings = section(PlanSettings, "posture planning")
    motion: MotionSettings = section(MotionSettings, "posture moves")
    tool: ToolSettings = section(ToolSettings, "the camera's tooldata")
    capture: CaptureSettings = section(CaptureSettings, "per-posture quality")
    cell: CellSettings = section(CellSettings, "keep-out volumes, carried geometry, path checks")
    guided: GuidedSettings = section(GuidedSettings, "operator-guided capture")
    verify: VerifySettings = section(VerifySettings, "the change handeye verify acts on")
    kinematics: KinematicsSettings = section(KinematicsSettings, "the arm's kinematics identified with the camera")
    quality: dict = setting(None, Custom(_quality), "verdict thresholds (src/handeye/station/quality_thresholds.yaml)",
                            factory=dict)
    output: str | None = setting(None, Optional(Text()), "folder of new sessions: a relative capture --session goes "
                                 "inside it (null: the current folder)")
    mock: MockSettings = section(MockSettings, "the embedded mock station")
    postures: tuple | None = setting(None, Optional(Custom(_postures)), "fixed approved postures for rapid generate "
                                     "(null: the built-in station's)", "deg")
    plant: PlantSettings | None = setting(None, Optional(Custom(plant_rule)), "publishing calibration health to the "
                                          "plant's MQTT broker (station/plant/settings.py; null: nothing is published)")
    source: str = "built-in mock station"

    @property
    def is_mock(self) -> bool:
        """True when this configuration runs the embedded mock station (both back ends are ``mock``)."""
        return self.controller.protocol == MOCK

    @property
    def is_rehearsal(self) -> bool:
        """True for a rehearsal station: a real controller link to ``handeye mock controller`` and the
        mock camera on its arm (``camera.backend: mock`` with ``camera.mock_arm``)."""
        return self.controller.protocol != MOCK and self.camera.backend == MOCK and self.camera.mock_arm is not None

    def as_mock(self) -> "StationConfig":
        """The same settings on the embedded mock station (what ``--mock`` does to a config)."""
        return replace(self, controller=replace(self.controller, protocol=MOCK),
                       camera=replace(self.camera, backend=MOCK, mock_arm=None))

    def session_folder(self, session: str | Path) -> Path:
        """Where ``handeye capture --session SESSION`` works: a relative ``SESSION`` inside ``output`` (unless it
        already starts with that folder), an absolute one, or any with ``output`` null, as given."""
        path = Path(session)
        if self.output is None or path.is_absolute():
            return path
        output = Path(self.output)
        return path if path.parts[:len(output.parts)] == output.parts else output / path

    @property
    def link_protocol(self) -> str:
        """The controller link actually spoken: the mock station's own protocol when mocked."""
        return self.mock.protocol if self.is_mock else self.controller.protocol

    def rapid_dict(self, postures: np.ndarray | Sequence, board2base: np.ndarray | None = None) -> dict:
        """The mapping ``rapid.station.station_from_dict`` reads, with the given approved postures; with
        ``cell.world_zones`` the keep-out volumes (and the board's stand when ``board2base`` is given)
        as world zones on the camera's nominal TCP."""
        c = self.controller
        out = {
            "robot": self.robot,
            "controller": {"protocol": self.link_protocol, "pc_address": c.pc_address, "controller_address": c.controller_address,
                           **({"port": c.port} if c.port is not None else {}), "serial_channel": c.serial_channel, "ack_timeout_s": c.ack_timeout_s,
                           "idle_timeout_s": c.idle_timeout_s, "write_key": c.write_key},
            "motion": {"speed_tcp_mm_s": self.motion.speed_tcp_mm_s, "speed_ori_deg_s": self.motion.speed_ori_deg_s,
                       "speed_override_pct": self.motion.speed_override_pct},
            "tool": {"name": self.tool.name, "mass_kg": self.tool.mass_kg, "cog_mm": list(self.tool.cog_mm)},
            "postures": [[round(float(v), 4) for v in row] for row in np.asarray(postures, float)],
        }
        if self.cell.world_zones:
            volumes = self.cell.model().world_zone_volumes(board2base, self.target)
            position, quaternion = self.camera.nominal_mount
            out["world_zones"] = {"tcp": {"position_mm": list(position), "quaternion_wxyz": list(quaternion)},
                                  "zones": [_plain(v.world_zone()) for v in volumes]}
        return out

    def to_dict(self) -> dict:
        """A YAML-ready mapping of the whole configuration (for the session record); secrets are
        ``"<set>"`` or None, never their value."""
        out = {"robot": self.robot, "output": self.output, "quality": dict(self.quality),
               "target": {"corners": list(self.target.corners), "square_mm": self.target.square_mm}}
        if getattr(self.target, "kind", "checkerboard") != "checkerboard":
            from ...geometry import target_to_dict

            out["target"] = target_to_dict(self.target)
        for name in ("controller", "camera", "plan", "motion", "tool", "capture", "guided", "verify", "mock"):
            settings = getattr(self, name)
            chosen = chosen_of(settings)
            section = {f.name: getattr(settings, f.name) for f in declared_fields(type(settings), chosen)}
            for secret in secret_fields(type(settings), chosen):
                section[secret] = None if section[secret] is None else "<set>"  # never the secret
            out[name] = _plain(section)
        out["camera"]["nominal_mount"] = pose_from_transform(self.camera.nominal_mount_transform())
        out["cell"] = _plain(self.cell.to_dict())
        if self.plant is not None:
            out["plant"] = self.plant.to_dict()
        return out


def _plain(value):
    if is_dataclass(value):
        return {f.name: _plain(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


#: The top-level keys, in the order they are checked (``robot`` first: other keys use its model).
TOP_LEVEL = tuple(f.name for f in fields(StationConfig) if rule_of(f) is not None)


def config_from_dict(data: dict, source: str = "configuration") -> StationConfig:
    """Validate a mapping (as read from YAML) into a :class:`StationConfig`.

    Raises
    ------
    ConfigError
        Naming the key at fault (``camera.nominal_mount.position_mm[2]``) and what it must be.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: the file must hold a mapping of sections")
    if "board" in data:  # `board:` names the target section too (issue 37)
        if "target" in data:
            raise ConfigError("give the board in one section: board or target (the same keys), not both")
        data = {("target" if k == "board" else k): v for k, v in data.items()}
    unknown = sorted(set(data) - set(TOP_LEVEL), key=brief)
    if unknown:
        raise ConfigError(f"unknown section {brief(unknown[0])}; known: {', '.join(sorted(TOP_LEVEL))}")
    context = {"robot": StationConfig.robot}
    rules = {f.name: key_rule(f) for f in fields(StationConfig) if rule_of(f) is not None}
    changes = {name: rules[name](data[name], name, context) for name in TOP_LEVEL if name in data}
    config = replace(StationConfig(source=source), **changes)
    _check_quality(config.quality)
    _check_hardware_named(data, config)
    _check_cell(config)
    return config


def _required_keys():
    """``(section, key, real choices)`` of every key a file must name (its choices without ``mock``)."""
    for path, f in schema_keys(StationConfig):
        if f.metadata.get("required"):
            name, key = path.split(".")
            rule = key_rule(f)
            if not isinstance(rule, Text) or rule.choices is None:  # required keys name a registered back end
                raise TypeError(f"required key {path} has no choices to name")
            yield name, key, tuple(c for c in rule.choices() if c != MOCK)


def _check_hardware_named(data: dict, config: StationConfig) -> None:
    """Refuse a config that names no controller or camera, or mixes the mock with real hardware."""
    for name, key, real in _required_keys():
        if not isinstance(data.get(name), dict) or key not in data[name]:
            raise ConfigError(f"{name}.{key} is missing: name the station's {name} ({' | '.join(real)}), "
                              f"or {MOCK} for the embedded mock station")
    controller_mock, camera_mock = config.controller.protocol == MOCK, config.camera.backend == MOCK
    if config.camera.mock_arm is not None and not (camera_mock and not controller_mock):
        raise ConfigError(f"camera.mock_arm is for a rehearsal: camera.backend {MOCK} with a real controller protocol "
                          f"({', '.join(controller_protocols())}) pointing at `handeye mock controller`; here "
                          "controller.protocol is "
                          f"{config.controller.protocol} and camera.backend {config.camera.backend}")
    if controller_mock and not camera_mock:
        raise ConfigError(f"controller.protocol is {MOCK} but camera.backend is {config.camera.backend}: the embedded mock "
                          f"station has its own camera; set both to {MOCK}, or neither")
    if camera_mock and not controller_mock and config.camera.mock_arm is None:
        raise ConfigError(f"camera.backend is {MOCK} but controller.protocol is {config.controller.protocol}: the mock camera "
                          f"only sees the mock robot: set both to {MOCK} (the embedded mock station), or rehearse against "
                          "`handeye mock controller --camera-port PORT` with camera.mock_arm: HOST:PORT")


def _check_cell(config: StationConfig) -> None:
    """The cell's keys that depend on each other: the path step within the margin, the keep-out volumes
    clear of the robot's base (it never moves: ``station.cell.plan.base_problem``), and the carried
    geometry where the camera is mounted."""
    cell = config.cell
    if cell.path_step_mm > cell.margin_mm:
        raise ConfigError(f"cell.path_step_mm ({cell.path_step_mm:g}) must not exceed cell.margin_mm ({cell.margin_mm:g}): "
                          "between two samples of a move the clearance may drop by half the step")
    problem = base_problem(load_robot(config.robot), cell.keep_out, cell.margin_mm)
    if problem is not None:
        raise ConfigError(problem)
    if not cell.carried:
        return
    camera = np.asarray(config.camera.nominal_mount[0], float)
    gaps = [float(body.signed_distance(camera)) if hasattr(body, "signed_distance")
            else float(np.linalg.norm(camera - np.asarray(body.centre_mm)) - body.radius_mm) for body in cell.carried]
    if min(gaps) > cell.margin_mm:
        raise ConfigError(f"camera.nominal_mount puts the camera {min(gaps):.0f} mm from every body of cell.carried: "
                          "describe the camera and its bracket in tool0 where they are mounted")


def _check_quality(quality: dict) -> None:
    """Validate the verdict thresholds with the report's own checker when it is available."""
    try:
        from ..report.quality import QualityThresholds
    except ImportError:  # pragma: no cover - the verdict module ships with the station
        return
    try:
        QualityThresholds.from_dict(quality)
    except HandEyeError as exc:
        raise ConfigError(f"quality: {exc}") from None


def describe_keys() -> list[str]:
    """One line per key of the station YAML: ``controller.port: ... [unit]``, from the schema."""
    lines = []
    for path, f in schema_keys(StationConfig):
        unit = f" [{f.metadata['unit']}]" if f.metadata.get("unit") else ""
        lines.append(f"{path}: {f.metadata['doc']}{unit}{' (REQUIRED)' if f.metadata.get('required') else ''}")
    return lines


def load_config(path: str | Path) -> StationConfig:
    """Read and validate a station YAML file.

    Raises
    ------
    ConfigError
    """
    path = Path(path)
    text_ = read_text_file(path, "station configuration", ConfigError,
                           missing=f"no station configuration at {path}; start from {EXAMPLE_FILE}")
    data = parse_yaml(text_, path, ConfigError)
    return config_from_dict(data or {}, str(path))


def default_config() -> StationConfig:
    """The built-in station: the embedded mock controller and camera on 127.0.0.1."""
    return StationConfig()
