"""What every importer shares: pose checks, building the session from the reading the data support.

An importer reads its file(s) into two stacks of 4x4 poses in the file's own length unit and
direction (with what the format says they are: the flange in the base or the base in the flange,
the board in the camera or the camera in the board), or, for a log whose convention is not known,
every possible reading of each side (``inference.Side``); one label per pair names where it came
from (``entry 12``, ``pose_fPe_3.yaml``, ``line 40``). :func:`build_session` lets
``inference.infer`` choose the reading (units, directions, set-up, rotation convention), converts
to millimetres, flange in base and board in camera, and records how everything was decided in
``session.extra["import"]`` (written to ``session.yaml``, so a session says where it came from).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...geometry import BoardGeometry
from ...base import SessionError, brief
from ...base import parse_yaml, read_text_file
from ...calibration import SETUPS
from ...calibration import MAX_LENGTH_MM, MAX_LENGTH_WORDS, MAX_POSTURE_INDEX, Posture, Session
from ...geometry import rigid_defect
from .head import check_log_head, read_head
from .ambiguity import AmbiguousReading
from .inference import METRES_BELOW, Constraints, Side, SideReading, infer

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
    "quaternion_side",
    "read_text",
    "parse_json",
    "EntryErrors",
]

UNITS = ("m", "mm")
QUATERNION_ORDERS = ("wxyz", "xyzw")
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
        raise SessionError(f"setup must be one of {', '.join(SETUPS)}; got {brief(setup)}")
    return setup


def check_units(units):
    if units is not None and units not in UNITS:
        raise SessionError(f"units must be 'm' or 'mm'; got {brief(units)}")
    return units


def check_quaternion_order(order):
    if order not in QUATERNION_ORDERS:
        raise SessionError(f"quaternion order must be 'wxyz' (scalar first) or 'xyzw' (scalar last); got {brief(order)}")
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
    defect = rigid_defect(m, ROTATION_TOLERANCE)
    if defect:
        raise ValueError(defect)
    r = m[:3, :3]
    u, _, vt = np.linalg.svd(r)
    m[:3, :3] = u @ vt
    return m


def quaternion_pose_problems(values: np.ndarray, order: str) -> list:
    """Per row of ``(n, 7)`` values (position, then a quaternion in ``order``): why it is not a pose, or
    ``""``. The one check of :func:`transform_from_quaternion`, for many rows at once (a stream).
    """
    values = np.asarray(values, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        finite = np.all(np.isfinite(values), axis=1)
        norm = np.linalg.norm(values[:, 3:7], axis=1)
    out = [""] * len(values)
    for k in np.flatnonzero(~finite | (np.abs(norm - 1.0) > ROTATION_TOLERANCE)):
        out[k] = "holds NaN or inf" if not finite[k] else f"quaternion ({order}) has norm {norm[k]:.6g}, not 1"
    return out


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
    problem = quaternion_pose_problems(np.r_[p, q][None], order)[0]
    if problem:
        raise ValueError(problem)
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat(q / np.linalg.norm(q), scalar_first=(order == "wxyz")).as_matrix()
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


def _side(name: str, poses, words: str | None, declared_direction: str | None, declared_unit: str | None) -> Side:
    """A side with one reading: the poses as a format documents them (or a :class:`Side` as it is)."""
    if isinstance(poses, Side):
        return poses
    words = words or "4x4 matrix"
    reading = SideReading("as written", words, words, np.asarray(poses, dtype=float).reshape(-1, 4, 4), declared=True)
    return Side(name, [reading], declared_direction, declared_unit)


def quaternion_side(name: str, positions, quaternions, declared_order: str | None, given_order: str | None,
                    declared_direction: str | None, named: bool = False) -> Side:
    """A side of position + quaternion rows, read in both component orders unless the names fix it.

    Parameters
    ----------
    name : str
        ``robot`` or ``camera``.
    positions, quaternions : array-like, shape (n, 3) and (n, 4)
        As the file holds them (unit norm already checked).
    declared_order : str or None
        The order the format documents (``wxyz`` or ``xyzw``).
    given_order : str or None
        ``--quaternion-order``: the only order allowed.
    declared_direction : str or None
    named : bool
        The columns are named by component (``qw``, ``qx``, ...): ``declared_order`` is certain.
    """
    p = np.asarray(positions, dtype=float).reshape(-1, 3)
    q = np.asarray(quaternions, dtype=float).reshape(-1, 4)
    if named and declared_order is None:  # the column names are what declares the order
        raise ValueError(f"{name}: quaternion columns named by component but no order read from them")
    orders = [declared_order] if named and declared_order is not None else list(QUATERNION_ORDERS)
    readings = []
    for order in orders:
        poses = np.tile(np.eye(4), (len(p), 1, 1))
        if len(p):
            poses[:, :3, :3] = Rotation.from_quat(q / np.linalg.norm(q, axis=1, keepdims=True),
                                                  scalar_first=(order == "wxyz")).as_matrix()
        poses[:, :3, 3] = p
        words = f"quaternion ({', '.join(order)})" + (", by the column names" if named else "")
        readings.append(SideReading(f"quaternion:{order}", words, f"quaternion {order}", poses,
                                    declared=(order == declared_order), allowed=(named or given_order in (None, order))))
    return Side(name, readings, declared_direction)


def _units_record(inference, robot: Side, camera: Side, units, documented: str | None, notes: list) -> dict:
    chosen = inference.chosen
    medians = {"robot": float(np.median(np.linalg.norm(robot.readings[chosen.robot].poses[:, :3, 3], axis=1))),
               "camera": float(np.median(np.linalg.norm(camera.readings[chosen.camera].poses[:, :3, 3], axis=1)))}
    lengths = f"median lengths: robot {medians['robot']:.4g}, camera {medians['camera']:.4g}"
    out = {"robot": chosen.units[0], "camera": chosen.units[1],
           "how": f"given ({lengths})" if units is not None else f"detected from the values ({lengths})"}
    if units is None:
        for part, side in (("robot", robot), ("camera", camera)):
            documented_here = side.declared_unit or documented
            if documented_here is not None and out[part] != documented_here:
                notes.append(f"{part} translations have a median length of {medians[part]:.4g}: read as {out[part]} "
                             f"although this format is documented in {documented_here} (pass --units to force)")
        if out["robot"] != out["camera"]:
            notes.append(f"robot poses read as {out['robot']} and board poses as {out['camera']} (each detected from its "
                         f"values); pass --units to force one unit for both")
    return out


def _setup_how(inference, setup, declared, default: str | None) -> str:
    """How the set-up was decided, in words (``given``, ``declared in the file``, ``detected from the data ...``)."""
    if setup is not None:
        return "given"
    if declared is not None and inference.setup == declared:
        return "declared in the file"
    scores = inference.record["scores"]
    axis, translation = scores.get("axis_misfit_deg"), scores.get("translation_misfit")
    figures = ("rotation-axis misfit " + ("-" if axis is None else f"{axis:.2f} deg") + ", translation misfit "
               + ("-" if translation is None else f"{100 * translation:.1f} % of the motion"))
    if any("declares" in d for d in inference.record.get("decided_by", [])):
        what = "the file's pose directions" + (f" and the format's default set-up {default}" if default else "")
        return f"as {what} declare; the data fit it ({figures}) and another reading as well (see the notes)"
    how = f"detected from the data ({figures})"
    if default is not None and inference.setup != default:
        how += f"; this format's default is {default}"
    return how


def _check_lengths(where, labels, robot_mm, camera_mm) -> None:
    """Refuse translations beyond the session format's limit (10 km), naming the entry."""
    for part, poses in (("robot", robot_mm), ("camera", camera_mm)):
        farthest = np.max(np.abs(poses[:, :3, 3]), axis=1)
        k = int(np.argmax(farthest))
        if not farthest[k] <= MAX_LENGTH_MM:
            raise SessionError(f"{where}: {labels[k]}: the {part} translation reaches {farthest[k]:g} mm, beyond "
                               f"{MAX_LENGTH_WORDS}: is the unit right? (--units)")


#: The most postures a session holds: its posture files are postures/0000.yaml .. 9999.yaml.
MAX_POSTURES = MAX_POSTURE_INDEX + 1


def check_posture_count(where, n: int, format_name: str) -> None:
    """Refuse more pose pairs than a session holds (:data:`MAX_POSTURES`), in one line saying what to do.

    Raises
    ------
    SessionError
    """
    if n <= MAX_POSTURES:
        return
    if format_name == "stream":
        fix = f"keep at most {MAX_POSTURES} with --max-postures N (the slowest pair in each of N time windows)"
    else:
        fix = ("for a time-stamped log of a moving robot, import the robot and camera streams with --format stream, "
               f"which keeps the slowest pair per time window; else split the log into parts of at most {MAX_POSTURES} rows")
    raise SessionError(f"{where}: {n} pose pairs, more than the {MAX_POSTURES} postures a session holds "
                       f"(posture indices 0..{MAX_POSTURE_INDEX}); {fix}")


def _check_pair_count(where, n: int, format_name: str, dropped: Dropped) -> None:
    """Refuse more pose pairs than a session holds (:func:`check_posture_count`), or none at all
    (saying what was dropped and why)."""
    check_posture_count(where, n, format_name)
    if n == 0:
        why = "; ".join(f"{d['count']} {d['reason']}" for d in dropped.as_list())
        raise SessionError(f"{where}: no usable pose pair" + (f" ({why})" if why else ""))


def _inferred_postures(where, robot_side, camera_side, constraints, labels) -> tuple:
    """``(inference, postures)``: the reading :func:`~.inference.infer` chooses, and the postures in mm
    it gives, each with its ``source`` label (lengths checked against the session format's limits)."""
    try:
        inference = infer(robot_side, camera_side, constraints)
    except AmbiguousReading as exc:  # keeps what each reading would give
        raise AmbiguousReading(f"{where}: {exc}", exc.choices) from None
    except SessionError as exc:
        raise SessionError(f"{where}: {exc}") from None
    robot_mm, camera_mm = inference.robot_mm, inference.camera_mm
    _check_lengths(where, labels, robot_mm, camera_mm)
    postures = [
        Posture(index=k, tool0_in_base=robot_mm[k], target_in_camera=camera_mm[k], extra={"source": str(labels[k])})
        for k in range(len(robot_mm))
    ]
    return inference, postures


def _import_record(source, inference, unit_info: dict, notes: list, dropped: Dropped) -> dict:
    """The parts of a session's ``import`` record that say where it came from and how it was read."""
    sources = [str(source)] if isinstance(source, (str, Path)) else [str(s) for s in source]
    return {
        "source": sources[0] if len(sources) == 1 else sources,
        "units": unit_info,
        "conventions": {k: inference.record[k] for k in ("robot", "camera", "setup", "decided_by")},
        "inference": {k: inference.record[k] for k in ("scores", "candidates")},
        "dropped": dropped.as_list(),
        "notes": notes,
        "warnings": list(inference.warnings),
    }


def build_session(
    format_name: str,
    source,
    robot,
    camera,
    labels,
    *,
    setup=None,
    declared_setup=None,
    default_setup: str | None,
    units=None,
    documented_units: str | None = "m",
    board: BoardGeometry | None = None,
    dropped: Dropped | None = None,
    entries_read: int | None = None,
    notes: list | None = None,
    details: dict | None = None,
    robot_pose: str | None = None,
    camera_pose: str | None = None,
    robot_declared: str | None = "flange_in_base",
    camera_declared: str | None = "target_in_camera",
    robot_words: str | None = None,
    camera_words: str | None = None,
    conventions_given: str | None = None,
) -> Session:
    """Choose the reading of pose pairs (``inference.infer``) and build a session in mm with its record.

    Parameters
    ----------
    format_name : str
    source : path or list of paths
    robot, camera : array-like, shape (n, 4, 4), or Side
        The robot and camera poses as the file holds them (file length unit, file direction), or
        every reading of them (:class:`~.inference.Side`, for logs whose convention is not known).
    labels : sequence of str, length n
        Where each pair came from (kept in each posture file as ``source``).
    setup, units, robot_pose, camera_pose : str, optional
        The user's flags (win over everything; a contradiction with the data is a warning).
    declared_setup : str, optional
        What the file itself says.
    default_setup : str or None
        The format's documented default (a declaration of the weakest kind).
    documented_units : str, optional
        The unit the format is documented in (a note is added when the values disagree).
    robot_declared, camera_declared : str or None
        What the format says the poses are (``flange_in_base`` / ``base_in_flange``,
        ``target_in_camera`` / ``camera_in_target``); ``None``: not said.
    robot_words, camera_words : str, optional
        The rotation convention of poses given as arrays, in words.
    conventions_given : str, optional
        The rotation-convention flags as the user gave them (``--euler robot:kuka``), for warnings.

    Raises
    ------
    SessionError
        When no pair is left, or the data cannot decide the reading (naming the flag that decides).
    """
    check_setup(setup)
    check_units(units)
    notes = list(notes or [])
    dropped = dropped or Dropped()
    where = source if isinstance(source, (str, Path)) else (source[0] if source else "input")
    robot_side = _side("robot", robot, robot_words, robot_declared, None)
    camera_side = _side("camera", camera, camera_words, camera_declared, None)
    n = len(robot_side.readings[0].poses)
    _check_pair_count(where, n, format_name, dropped)
    constraints = Constraints(setup=setup, robot_pose=robot_pose, camera_pose=camera_pose, units=units,
                              declared_setup=declared_setup, default_setup=default_setup,
                              conventions_given=conventions_given)
    inference, postures = _inferred_postures(where, robot_side, camera_side, constraints, labels)
    unit_info = _units_record(inference, robot_side, camera_side, units, documented_units, notes)
    notes.extend(inference.notes)
    read = _import_record(source, inference, unit_info, notes, dropped)
    record = {"format": format_name, "setup_how": _setup_how(inference, setup, declared_setup, default_setup),
              "entries_read": int(entries_read if entries_read is not None else n + dropped.total),
              "postures": len(postures), **read}
    order = ("format", "source", "units", "setup_how", "conventions", "inference", "entries_read", "postures",
             "dropped", "notes", "warnings")
    record = {**{key: record[key] for key in order}, **(details or {})}  # the order session.yaml shows
    return Session(setup=inference.setup, robot=None, target=board, postures=postures, extra={"import": record})


def read_text(path) -> str:
    """The UTF-8 text of ``path``, or a one-line :class:`SessionError` (missing, a folder, a named pipe,
    unreadable, over 64 MB, not UTF-8; see ``base.files.read_text_file``; empty, binary, or
    without a number in its first 64 KB: ``head.check_log_head``, before the file is read whole)."""
    check_log_head(path, read_head(path))
    return read_text_file(Path(path), "input file", SessionError, missing=f"{path}: no such file")


def parse_json(text: str, path):
    """``json.loads(text)``, or a one-line :class:`SessionError` naming the file (and line)."""
    keys = [0]

    def counted(pairs: list) -> dict:  # the bound is met while parsing, before a huge tree is built
        keys[0] += len(pairs)
        if keys[0] > MAX_JSON_KEYS:
            raise _TooManyJsonKeys()
        return _object_without_duplicates(pairs)

    try:
        if _more_keys_than(text, MAX_JSON_KEYS):  # refused before any parse: no pairs built
            raise _TooManyJsonKeys()
        return json.loads(text, object_pairs_hook=counted)
    except _TooManyJsonKeys:
        raise SessionError(f"{path}: over {MAX_JSON_KEYS} keys: not a hand-eye log (a log of 10000 postures "
                           f"holds a few tens of thousands); give the log itself") from None
    except _DuplicateJsonKey as exc:
        parse_yaml(text, path)  # JSON is YAML: its reader names both lines of the duplicated key
        raise SessionError(f"{path}: the key '{exc.args[0]}' is written twice in one object; JSON readers "
                           "would silently keep only the last: merge them into one") from None
    except json.JSONDecodeError as exc:
        raise SessionError(f"{path}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except RecursionError:
        raise SessionError(f"{path}: nested too deeply to be read as JSON") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise SessionError(f"{path}: not valid JSON: a value cannot be read ({str(exc)[:100]})") from None


#: A hand-eye log holds a few keys per posture; a JSON with more keys than this is refused while parsing.
MAX_JSON_KEYS = 200_000


#: A JSON string (its quotes, the characters and escapes between them), written to match in linear time.
_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)


def _more_keys_than(text: str, bound: int) -> bool:
    """Whether a JSON text holds more than ``bound`` keys, told without parsing it: its keys are its
    colons outside strings (each key has one, nothing else in valid JSON does). ``text.count(":")``
    bounds them from above; only when that bound is above ``bound`` are the colons between the strings
    counted, string by string, stopping once ``bound`` is passed (no copy, no list: constant memory)."""
    if text.count(":") <= bound:
        return False
    keys, after = 0, 0
    for string in _JSON_STRING.finditer(text):
        keys += text.count(":", after, string.start())
        if keys > bound:
            return True
        after = string.end()
    return keys + text.count(":", after) > bound


class _TooManyJsonKeys(ValueError):
    """The JSON holds more than :data:`MAX_JSON_KEYS` keys."""


class _DuplicateJsonKey(ValueError):
    """A JSON object holds a key twice (``args[0]``)."""


def _object_without_duplicates(pairs: list) -> dict:
    """``dict(pairs)`` for :func:`json.loads`, refusing a key written twice (JSON keeps the last)."""
    result = {}
    for key, value in pairs:
        if key in result:
            raise _DuplicateJsonKey(key)
        result[key] = value
    return result


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
