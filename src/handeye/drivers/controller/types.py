"""Values that travel over the controller link, and their checks.

Units and conventions as everywhere in handeye: millimetres, degrees, quaternions ``(w, x, y, z)``
(= ABB ``q1..q4``) with ``w >= 0``. Every check here runs on the PC *before* anything is sent, and
raises :class:`InvalidRequest` naming the offending value.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, SupportsInt, cast

import numpy as np

from ...base import WRITE_KEY_PATTERN, write_key_code  # one definition for drivers and rapid
from .errors import InvalidRequest

if TYPE_CHECKING:
    import numpy.typing as npt

    from ...robot import RobotModel

__all__ = [
    "STATES",
    "READY",
    "MOVING",
    "AT",
    "LATE",
    "ACKED",
    "ERROR",
    "ControllerInfo",
    "ControllerStatus",
    "FlangePose",
    "ToolData",
    "check_finite",
    "check_joints",
    "check_posture_index",
    "check_tooldata",
    "check_timeout",
    "check_write_key",
    "check_fingerprint",
    "write_key_code",
    "WRITE_KEY_PATTERN",
    "robot_model",
    "MAX_TOOL_TRANSLATION_MM",
    "QUATERNION_NORM_TOLERANCE",
]

#: States of the RAPID program as the PC sees them (STATUS reply, Modbus ``state`` register).
READY, MOVING, AT, LATE, ACKED, ERROR = "READY", "MOVING", "AT", "LATE", "ACKED", "ERROR"
#: The guided program's own (``src/handeye/rapid/guided.py``): the pendant prompts, the operator jogs (the program is
#: stopped), the operator pressed Done.
PROMPT, JOG, DONE = "PROMPT", "JOG", "DONE"
STATES = (READY, MOVING, AT, LATE, ACKED, ERROR, PROMPT, JOG, DONE)

#: A tool frame farther than this from the flange is refused (a camera sits within centimetres).
MAX_TOOL_TRANSLATION_MM = 1000.0
#: Largest accepted ``| |q| - 1 |`` of a tool quaternion; within it the quaternion is renormalised.
QUATERNION_NORM_TOLERANCE = 1e-4
#: Largest accepted tool mass (kg) and centre-of-gravity distance (mm).
MAX_TOOL_MASS_KG = 100.0
MAX_TOOL_COG_MM = 1000.0


@dataclass(frozen=True)
class ControllerInfo:
    """What the controller says about itself.

    Attributes
    ----------
    protocol_version : int
    program : str
        Name of the program answering (``RAPID`` on a controller, ``MOCK`` for the mock).
    postures : int
        Number of approved postures embedded in the RAPID program.
    """

    protocol_version: int
    program: str
    postures: int


@dataclass(frozen=True)
class ControllerStatus:
    """State of the RAPID program.

    Attributes
    ----------
    state : str
        ``READY`` (waiting for a posture request), ``MOVING``, ``AT`` (standing still at ``posture``
        after ``MoveAbsJ ... fine``, waiting for the PC's acknowledgement), ``LATE`` (as ``AT``, the
        acknowledgement is overdue), ``ACKED`` (Modbus only: acknowledged, waiting for the PC to clear
        its request) or ``ERROR`` (Modbus only: the last request was refused); the guided program
        (``src/handeye/rapid/guided.py``) also ``PROMPT``, ``JOG`` (Modbus only: over a line the stopped program
        answers nothing) and ``DONE``.
    posture : int
        The posture the robot is at or moving to (1-based); 0 before the first one.
    """

    state: str
    posture: int

    @property
    def moving(self) -> bool:
        return self.state == MOVING

    @property
    def awaiting_ack(self) -> bool:
        """Standing still at ``posture`` and waiting for :meth:`Controller.acknowledge`."""
        return self.state in (AT, LATE)

    @property
    def ready(self) -> bool:
        """A posture request would be accepted now."""
        return self.state == READY

    def at_posture(self, k: int) -> bool:
        """Standing still at posture ``k`` (acknowledged or not)."""
        return self.posture == k and self.state in (AT, LATE, ACKED, READY) and k > 0


@dataclass(frozen=True)
class FlangePose:
    """tool0 in base (``CRobT(\\Tool:=tool0 \\WObj:=wobj0)``).

    Attributes
    ----------
    position_mm : ndarray, shape (3,)
    quaternion_wxyz : ndarray, shape (4,)
        Unit, ``w >= 0``.
    """

    position_mm: np.ndarray
    quaternion_wxyz: np.ndarray

    def to_transform(self) -> np.ndarray:
        """tool02base, shape (4, 4)."""
        from ...geometry import transform_from_pose

        return transform_from_pose(self.position_mm, self.quaternion_wxyz)

    def to_json(self) -> dict:
        """``{"position_mm": [...], "quaternion_wxyz": [...]}`` as in conventions.md."""
        return {
            "position_mm": [float(v) for v in self.position_mm],
            "quaternion_wxyz": [float(v) for v in self.quaternion_wxyz],
        }


@dataclass(frozen=True)
class ToolData:
    """The part of a RAPID ``tooldata`` the link writes and reads back.

    ``robhold`` is always TRUE (the camera is on the flange); the load's axes of moment are
    ``[1,0,0,0]`` and its inertia 0, which RAPID accepts for a light tool.

    Attributes
    ----------
    position_mm : sequence of 3 float
        tframe translation, tool frame origin in tool0 (mm).
    quaternion_wxyz : sequence of 4 float
        tframe rotation (q1..q4).
    mass_kg : float
        Tool mass; RAPID refuses 0.
    cog_mm : sequence of 3 float
        Centre of gravity in tool0 (mm).
    """

    position_mm: tuple
    quaternion_wxyz: tuple
    mass_kg: float = 1.0
    cog_mm: tuple = (0.0, 0.0, 0.0)

    @classmethod
    def from_transform(cls, cam2tool0: npt.ArrayLike, mass_kg: float = 1.0,
                       cog_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> "ToolData":
        """Tool data whose frame is the 4x4 ``cam2tool0`` (mm)."""
        from ...geometry import canonical_quaternions, quaternion_from_matrix

        t = np.asarray(cam2tool0, dtype=float)
        if t.shape != (4, 4):
            raise InvalidRequest(f"a tool frame is a 4x4 transform; got shape {t.shape}")
        q = canonical_quaternions(quaternion_from_matrix(t[:3, :3]))
        return cls(tuple(float(v) for v in t[:3, 3]), tuple(float(v) for v in q), mass_kg, tuple(cog_mm))

    def as_arrays(self) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        return (np.asarray(self.position_mm, float), np.asarray(self.quaternion_wxyz, float),
                float(self.mass_kg), np.asarray(self.cog_mm, float))

    def values(self) -> list[float]:
        """The 11 numbers ``x y z q1 q2 q3 q4 mass cx cy cz``."""
        p, q, m, c = self.as_arrays()
        return [*map(float, p), *map(float, q), m, *map(float, c)]

    @classmethod
    def from_values(cls, values: Iterable[float]) -> "ToolData":
        v = [float(x) for x in values]
        if len(v) != 11:
            raise ValueError(f"tool data needs 11 numbers; got {len(v)}")
        return cls(tuple(v[0:3]), tuple(v[3:7]), v[7], tuple(v[8:11]))

    def close_to(self, other: "ToolData", position_mm: float = 1e-3, quaternion: float = 2e-6,
                 mass_kg: float = 1e-3) -> bool:
        """Equal within the link's precision (0.001 mm, 1e-6 per quaternion component)."""
        a, b = self.as_arrays(), other.as_arrays()
        return bool(np.all(np.abs(a[0] - b[0]) <= position_mm) and np.all(np.abs(a[1] - b[1]) <= quaternion)
                    and abs(a[2] - b[2]) <= mass_kg and np.all(np.abs(a[3] - b[3]) <= position_mm))


def check_finite(name: str, values: object) -> np.ndarray:
    """``values`` as a float array; :class:`InvalidRequest` if any is NaN or infinite."""
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InvalidRequest(f"{name} must be numbers; got {values!r}") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidRequest(f"{name} holds NaN or infinity ({np.array2string(arr, precision=4)}); nothing was sent")
    return arr


@lru_cache(maxsize=None)
def robot_model(name: str) -> RobotModel:
    """The kinematics model (joint limits) of a robot by name; ValueError if unknown."""
    from ...robot import load_robot

    return load_robot(name)


def check_joints(joints_deg: npt.ArrayLike, robot: str = "IRB1400", what: str = "posture") -> np.ndarray:
    """Controller axis angles (deg), shape (dof,) of ``robot``'s model, finite and inside its joint limits.

    Raises
    ------
    InvalidRequest
        Naming each axis outside its limits (from ``RobotModel.limit_violations``).
    """
    arr = check_finite(f"{what} joint angles", joints_deg)
    model = robot_model(robot)
    if arr.shape != (model.dof,):
        raise InvalidRequest(f"{what} needs {model.dof} joint angles; got shape {arr.shape}")
    problems = model.limit_violations(arr)
    if problems:
        raise InvalidRequest(f"{what} is outside the {model.name} joint limits: {'; '.join(problems)}; nothing was sent")
    return arr


def check_posture_index(k: object, count: int | None = None) -> int:
    """A 1-based posture index as an int (no bool, no NaN, no fraction), within ``1..count`` if known."""
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, numbers.Real):
        raise InvalidRequest(f"posture index must be an integer >= 1; got {k!r}")
    if isinstance(k, (float, np.floating)):
        if not math.isfinite(k) or k != int(k):
            raise InvalidRequest(f"posture index must be an integer >= 1; got {k!r}")
    try:
        value = int(cast(SupportsInt, k))  # a numbers.Real (float, numpy, Fraction) has __int__; typeshed's ABC omits it
    except (TypeError, ValueError):
        raise InvalidRequest(f"posture index must be an integer >= 1; got {k!r}") from None
    if value < 1 or (count is not None and value > count):
        known = f"1..{count}" if count is not None else ">= 1"
        raise InvalidRequest(f"posture {value} does not exist on the controller (approved postures: {known}); "
                             "regenerate the RAPID program with `handeye rapid generate` to add postures")
    return value


def check_tooldata(tool: ToolData, max_mass_kg: float = MAX_TOOL_MASS_KG) -> ToolData:
    """Validate tool data and return it normalised (unit quaternion with ``w >= 0``).

    Refused: NaN or infinity anywhere, a quaternion whose norm is off by more than
    ``QUATERNION_NORM_TOLERANCE``, a tool frame farther than 1 m from the flange, a mass <= 0 or
    above ``max_mass_kg``, a centre of gravity farther than 1 m.
    """
    if not isinstance(tool, ToolData):
        raise InvalidRequest(f"expected ToolData; got {type(tool).__name__}")
    p = check_finite("tool frame position", tool.position_mm)
    q = check_finite("tool frame quaternion", tool.quaternion_wxyz)
    m = check_finite("tool mass", tool.mass_kg)
    c = check_finite("tool centre of gravity", tool.cog_mm)
    if p.shape != (3,) or q.shape != (4,) or c.shape != (3,) or m.shape != ():
        raise InvalidRequest("tool data needs position (3), quaternion (4), mass and centre of gravity (3)")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise InvalidRequest(f"tool frame quaternion is not unit (norm {norm:.6g}); give (w, x, y, z) with norm 1; "
                             "nothing was sent")
    distance = float(np.linalg.norm(p))
    if distance > MAX_TOOL_TRANSLATION_MM:
        raise InvalidRequest(f"tool frame is {distance:.1f} mm from the flange (limit {MAX_TOOL_TRANSLATION_MM:g} mm): "
                             "check units (mm) and the calibration; nothing was sent")
    if not 0.0 < float(m) <= max_mass_kg:
        raise InvalidRequest(f"tool mass must be > 0 and <= {max_mass_kg:g} kg; got {float(m):g}; nothing was sent")
    if float(np.linalg.norm(c)) > MAX_TOOL_COG_MM:
        raise InvalidRequest(f"tool centre of gravity is over {MAX_TOOL_COG_MM:g} mm from the flange; nothing was sent")
    q = q / norm
    if q[0] < 0:
        q = -q
    return ToolData(tuple(float(v) for v in p), tuple(float(v) for v in q), float(m), tuple(float(v) for v in c))


def check_timeout(name: str, value: float | str) -> float:
    """A positive, finite number of seconds."""
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise InvalidRequest(f"{name} must be a number of seconds; got {value!r}") from None
    if not math.isfinite(t) or t <= 0:
        raise InvalidRequest(f"{name} must be a positive number of seconds; got {value!r}")
    return t


def check_write_key(value: object, name: str = "write_key") -> str | None:
    """The station's write key (None: no key), checked without ever echoing it.

    Raises
    ------
    InvalidRequest
        Not 8 to 32 letters, digits, ``_`` or ``-``; the message gives the length, never the value.
    """
    if value is None:
        return None
    if not isinstance(value, str):
        raise InvalidRequest(f"{name} must be a text of 8 to 32 letters, digits, '_' or '-'; got a {type(value).__name__}")
    if not WRITE_KEY_PATTERN.fullmatch(value):
        raise InvalidRequest(f"{name} must be 8 to 32 letters, digits, '_' or '-'; got another value of {len(value)} "
                             "characters (the key itself is never printed)")
    return value


def check_fingerprint(value: object, name: str = "controller.tls_fingerprint") -> str:
    """A SHA-256 certificate fingerprint as 64 lower-case hex digits (colons allowed in ``value``, as
    browsers and openssl print it).

    Raises
    ------
    InvalidRequest
        Not 64 hex digits once the colons are removed.
    """
    text = str(value).replace(":", "").strip().lower()
    if not re.fullmatch(r"[0-9a-f]{64}", text):
        raise InvalidRequest(f"{name} must be the SHA-256 of the controller's certificate: 64 hex digits (colons "
                             f"allowed); got {len(text)} characters")
    return text


