"""What every importer shares: pose checks, unit and set-up resolution, building the session.

An importer reads its file(s) into two stacks of 4x4 poses in the file's own length unit (robot:
``tool0_in_base``, camera: ``target_in_camera``), one label per pair naming where it came from
(``entry 12``, ``pose_fPe_3.yaml``, ``line 40``), and hands them to :func:`build_session`, which
converts to millimetres, chooses the set-up and records how everything was decided in
``session.extra["import"]`` (written to ``session.yaml``, so a session says where it came from).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...calibration.compact_points import BoardGeometry
from ...calibration.diagnostics import DiagnosticLimits, hand_eye_fit, setup_rotation_residuals
from ...calibration.errors import SessionError, brief
from ...calibration.files import read_text_file
from ...calibration.problem import SETUPS
from ...calibration.session import MAX_LENGTH_MM, MAX_LENGTH_WORDS, Posture, Session

__all__ = [
    "UNITS",
    "QUATERNION_ORDERS",
    "METRES_BELOW",
    "Dropped",
    "rigid_transform",
    "transform_from_quaternion",
    "transform_from_rotvec",
    "detect_unit",
    "flat_numbers",
    "check_setup",
    "check_units",
    "check_quaternion_order",
    "build_session",
    "read_text",
    "parse_json",
    "EntryErrors",
]

UNITS = ("m", "mm")
QUATERNION_ORDERS = ("wxyz", "xyzw")
#: A median translation length below this (in the file's numbers) is read as metres, above as mm:
#: a flange 20 m from the base or a board 20 m from the camera is as implausible as one 20 mm away.
METRES_BELOW = 20.0
_SCALE = {"m": 1000.0, "mm": 1.0}
#: Largest accepted deviation of a rotation matrix from orthonormal, and of a quaternion's norm from 1.
ROTATION_TOLERANCE = 1e-3


@dataclass
class Dropped:
    """Pairs left out while importing, by reason (counts and the first few labels)."""

    reasons: dict = field(default_factory=dict)

    def add(self, reason: str, label: str) -> None:
        entry = self.reasons.setdefault(reason, {"count": 0, "examples": []})
        entry["count"] += 1
        if len(entry["examples"]) < 5:
            entry["examples"].append(label)

    @property
    def total(self) -> int:
        return sum(v["count"] for v in self.reasons.values())

    def as_list(self) -> list:
        return [{"reason": k, "count": v["count"], "examples": list(v["examples"])} for k, v in self.reasons.items()]


def check_setup(setup):
    if setup is not None and setup not in SETUPS:
        raise SessionError(f"setup must be one of {', '.join(SETUPS)}; got {setup!r}")
    return setup


def check_units(units):
    if units is not None and units not in UNITS:
        raise SessionError(f"units must be 'm' or 'mm'; got {units!r}")
    return units


def check_quaternion_order(order):
    if order not in QUATERNION_ORDERS:
        raise SessionError(f"quaternion order must be 'wxyz' (scalar first) or 'xyzw' (scalar last); got {order!r}")
    return order


def rigid_transform(value) -> np.ndarray:
    """A checked 4x4 rigid transform from nested lists (or an array), re-orthonormalised.

    Raises
    ------
    ValueError
        With a short reason: wrong shape, not numbers, not finite, bottom row not (0, 0, 0, 1),
        rotation part not orthonormal (tolerance 1e-3) or a reflection.
    """
    try:
        m = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError("is not a 4x4 matrix of numbers") from None
    if m.shape == (16,):
        m = m.reshape(4, 4)
    if m.shape != (4, 4):
        raise ValueError(f"must be a 4x4 matrix; got shape {'x'.join(map(str, m.shape)) or 'scalar'}")
    if not np.all(np.isfinite(m)):
        raise ValueError("holds NaN or inf")
    if np.max(np.abs(m[3] - [0.0, 0.0, 0.0, 1.0])) > 1e-6:
        raise ValueError(f"bottom row must be 0 0 0 1; got {' '.join(f'{v:g}' for v in m[3])}")
    r = m[:3, :3]
    error = float(np.max(np.abs(r.T @ r - np.eye(3))))
    if error > ROTATION_TOLERANCE:
        raise ValueError(f"rotation part is not orthonormal (|R^T R - I| = {error:.3g})")
    if np.linalg.det(r) < 0:
        raise ValueError("rotation part is a reflection (determinant -1)")
    u, _, vt = np.linalg.svd(r)
    m[:3, :3] = u @ vt
    return m


def transform_from_quaternion(position, quaternion, order: str) -> np.ndarray:
    """4x4 transform from a position and a quaternion given in ``order`` (``wxyz`` or ``xyzw``).

    Raises
    ------
    ValueError
        Not 3 + 4 finite numbers, or the quaternion's norm is off 1 by more than 1e-3.
    """
    try:
        p = np.asarray(position, dtype=float)
        q = np.asarray(quaternion, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError("needs a position (3 numbers) and a quaternion (4 numbers)") from None
    if p.shape != (3,) or q.shape != (4,):
        raise ValueError("needs a position (3 numbers) and a quaternion (4 numbers)")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))):
        raise ValueError("holds NaN or inf")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > ROTATION_TOLERANCE:
        raise ValueError(f"quaternion ({order}) has norm {norm:.6g}, not 1")
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat(q / norm, scalar_first=(order == "wxyz")).as_matrix()
    m[:3, 3] = p
    return m


def transform_from_rotvec(position, rotvec) -> np.ndarray:
    """4x4 transform from a position and a rotation vector (axis x angle, radians)."""
    try:
        p = np.asarray(position, dtype=float)
        v = np.asarray(rotvec, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError("needs 3 translation and 3 rotation values") from None
    if p.shape != (3,) or v.shape != (3,):
        raise ValueError("needs 3 translation and 3 rotation values")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(v))):
        raise ValueError("holds NaN or inf")
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(v).as_matrix()
    m[:3, 3] = p
    return m


def flat_numbers(value, count: int) -> np.ndarray:
    """Exactly ``count`` numbers from a number or nested lists of them, in reading order.

    Walks the lists depth first and stops at the ``count + 1``-th number, so a YAML alias bomb (a
    list of lists of the same list ...) is refused without being expanded. Numeric strings count as
    numbers (PyYAML reads ``1e-05`` as a string); ``true``/``false`` do not.

    Raises
    ------
    ValueError
        Saying what is wrong: ``got 5``, ``got more``, ``'abc' is not a number``.
    """
    out = []
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, list):
            stack.extend(reversed(item))
            continue
        if len(out) == count:
            raise ValueError("got more")
        if type(item) not in (int, float, str):
            raise ValueError(f"{brief(item)} is not a number")
        try:
            out.append(float(item))
        except (ValueError, OverflowError):
            raise ValueError(f"{brief(item)} is not a number") from None
    if len(out) != count:
        raise ValueError(f"got {len(out)}")
    return np.array(out)


def detect_unit(poses) -> tuple[str, float]:
    """``('m' | 'mm', median translation length)`` of poses ``(n, 4, 4)`` in a file's numbers."""
    median = float(np.median(np.linalg.norm(np.asarray(poses)[:, :3, 3], axis=1)))
    return ("m" if median < METRES_BELOW else "mm"), median


def _resolve_units(robot, camera, units, documented: str | None, notes: list) -> dict:
    out = {}
    medians = {}
    for part, poses in (("robot", robot), ("camera", camera)):
        guess, median = detect_unit(poses)
        medians[part] = median
        if units is not None:
            out[part] = units
            if guess != units:
                notes.append(f"{part} translations have a median length of {median:.4g}, which looks like {guess}, "
                             f"but {units} was given: read as {units}")
        else:
            out[part] = guess
            if documented is not None and guess != documented:
                notes.append(f"{part} translations have a median length of {median:.4g}: read as {guess} although "
                             f"this format is documented in {documented} (pass --units to force)")
    lengths = f"median lengths: robot {medians['robot']:.4g}, camera {medians['camera']:.4g}"
    out["how"] = f"given ({lengths})" if units is not None else f"detected from the values ({lengths})"
    if units is None and out["robot"] != out["camera"]:
        notes.append(f"robot poses read as {out['robot']} and board poses as {out['camera']} (each detected from its "
                     f"values); pass --units to force one unit for both")
    return out


def _resolve_setup(robot_mm, camera_mm, setup, declared, default: str, notes: list) -> tuple[str, str]:
    """Set-up from: the option, else the file's declaration, else the data when decisive, else the default.

    Decisive: the rotation axes fit one set-up 3x better than the other, and the translations fit it
    too (otherwise the rotations are probably read in a wrong convention and the checks say so).
    """
    if setup is not None:
        return setup, "given"
    if declared is not None:
        return declared, "declared in the file"
    limits = DiagnosticLimits()
    if len(robot_mm) >= 3:
        residuals = setup_rotation_residuals(robot_mm, camera_mm, limits)
        fits = {k: v for k, v in residuals.items() if np.isfinite(v)}
        if len(fits) == 2:
            best = min(fits, key=fits.get)
            other = next(k for k in fits if k != best)
            fit = hand_eye_fit(robot_mm, camera_mm, best, limits)
            translations_fit = fit["motion_mm"] > 0 and fit["translation_mm"] <= limits.translation_ratio * fit["motion_mm"]
            if (fits[other] > limits.setup_ratio * max(fits[best], 0.05) and fits[other] > limits.gap_floor_deg
                    and translations_fit):
                how = (f"detected from the data: median rotation residual {fits[best]:.2f} deg as {best}, "
                       f"{fits[other]:.2f} deg as {other}")
                if best != default:
                    notes.append(f"set-up {best} detected from the data although this format's default is {default}; "
                                 f"pass --setup to force")
                return best, how
    return default, "the format's default; the data do not decide"


def build_session(
    format_name: str,
    source,
    robot,
    camera,
    labels,
    *,
    setup=None,
    declared_setup=None,
    default_setup: str,
    units=None,
    documented_units: str | None = "m",
    board: BoardGeometry | None = None,
    dropped: Dropped | None = None,
    entries_read: int | None = None,
    notes: list | None = None,
    details: dict | None = None,
) -> Session:
    """Convert pose pairs in file units to a session in mm with its import record.

    Parameters
    ----------
    format_name : str
    source : path or list of paths
    robot, camera : array-like, shape (n, 4, 4)
        ``tool0_in_base`` and ``target_in_camera`` in the file's length unit.
    labels : sequence of str, length n
        Where each pair came from (kept in each posture file as ``source``).
    setup : str, optional
        The user's choice (wins over everything).
    declared_setup : str, optional
        What the file itself says.
    default_setup : str
        The format's documented default, used when the data do not decide.
    units : str, optional
        The user's choice (``m`` or ``mm``); else each side is detected from its values.
    documented_units : str, optional
        The unit the format is documented in (a note is added when the values disagree).

    Raises
    ------
    SessionError
        When no pair is left.
    """
    check_setup(setup)
    check_units(units)
    notes = list(notes or [])
    dropped = dropped or Dropped()
    robot = np.asarray(robot, dtype=float).reshape(-1, 4, 4)
    camera = np.asarray(camera, dtype=float).reshape(-1, 4, 4)
    where = source if isinstance(source, (str, Path)) else (source[0] if source else "input")
    if len(robot) == 0:
        why = "; ".join(f"{d['count']} {d['reason']}" for d in dropped.as_list())
        raise SessionError(f"{where}: no usable pose pair" + (f" ({why})" if why else ""))
    unit_info = _resolve_units(robot, camera, units, documented_units, notes)
    robot_mm = robot.copy()
    camera_mm = camera.copy()
    robot_mm[:, :3, 3] *= _SCALE[unit_info["robot"]]
    camera_mm[:, :3, 3] *= _SCALE[unit_info["camera"]]
    for part, poses in (("robot", robot_mm), ("camera", camera_mm)):
        farthest = np.max(np.abs(poses[:, :3, 3]), axis=1)
        k = int(np.argmax(farthest))
        if not farthest[k] <= MAX_LENGTH_MM:
            raise SessionError(f"{where}: {labels[k]}: the {part} translation reaches {farthest[k]:g} mm, beyond "
                               f"{MAX_LENGTH_WORDS}: is the unit right? (--units)")
    chosen, setup_how = _resolve_setup(robot_mm, camera_mm, setup, declared_setup, default_setup, notes)
    postures = [
        Posture(index=k, tool0_in_base=robot_mm[k], target_in_camera=camera_mm[k], extra={"source": str(labels[k])})
        for k in range(len(robot_mm))
    ]
    sources = [str(source)] if isinstance(source, (str, Path)) else [str(s) for s in source]
    record = {
        "format": format_name,
        "source": sources[0] if len(sources) == 1 else sources,
        "units": {"robot": unit_info["robot"], "camera": unit_info["camera"], "how": unit_info["how"]},
        "setup_how": setup_how,
        "entries_read": int(entries_read if entries_read is not None else len(robot) + dropped.total),
        "postures": len(postures),
        "dropped": dropped.as_list(),
        "notes": notes,
    }
    if details:
        record.update(details)
    return Session(setup=chosen, robot=None, target=board, postures=postures, extra={"import": record})


def read_text(path) -> str:
    """The UTF-8 text of ``path``, or a one-line :class:`SessionError` (missing, a folder, a named pipe,
    unreadable, over 64 MB, not UTF-8; see ``calibration.files.read_text_file``)."""
    return read_text_file(Path(path), "input file", SessionError, missing=f"{path}: no such file")


def parse_json(text: str, path):
    """``json.loads(text)``, or a one-line :class:`SessionError` naming the file (and line)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise SessionError(f"{path}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except RecursionError:
        raise SessionError(f"{path}: nested too deeply to be read as JSON") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise SessionError(f"{path}: not valid JSON: a value cannot be read ({str(exc)[:100]})") from None


class EntryErrors:
    """Collects bad entries: raise at the first one, or drop them when ``skip_invalid``."""

    def __init__(self, path, skip_invalid: bool, dropped: Dropped):
        self.path = path
        self.skip_invalid = skip_invalid
        self.dropped = dropped

    def bad(self, label: str, reason: str) -> None:
        """Report ``label: reason``: raises :class:`SessionError` unless bad entries are skipped."""
        if not self.skip_invalid:
            raise SessionError(f"{self.path}: {label}: {reason} (fix it, or pass --skip-invalid to drop such entries)")
        self.dropped.add(f"invalid: {reason.split(' (')[0]}", label)
