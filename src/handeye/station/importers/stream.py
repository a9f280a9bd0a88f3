"""Time-stamped pose streams in CSV (the ETH Zurich ``hand_eye_calibration`` layout).

Two files, one pose per line, no header (a first line none of whose fields looks like a number is
skipped; values by the rules of :mod:`handeye.station.csv_values`)::

    t, x, y, z, qx, qy, qz, qw          stamp in seconds, position, quaternion scalar LAST, metres

- the robot stream: the hand (flange) in the robot base, ``tool0_in_base`` (``*_base_link_*.csv``,
  ~50 Hz in the ETH set);
- the camera stream: the CAMERA IN THE TARGET frame, as the ETH set stores it (``*_target_*.csv``,
  ~30 Hz); ``target_in_camera`` is its inverse. That is what the format declares; the data decide
  when they can (``inference``), and ``camera_pose="target_in_camera"`` forces the other reading.

Pairing: every camera sample takes the robot sample with the nearest stamp; pairs farther apart
than ``tolerance_s`` (default 30 ms) are dropped. Optionally only pairs where the hand is at rest
(slower than ``rest_mm_s`` and ``rest_deg_s``) are kept. A stream gives thousands of pairs: by
default the time span is cut into ``max_postures`` (40) equal windows and the pair where the hand
moves slowest is kept from each (least blur and time-offset error); ``max_postures=0`` keeps all.
Default set-up: eye-in-hand (the ETH set), unless the data clearly say otherwise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...base import SessionError, brief
from ...calibration import Session
from ..csv_values import is_header, parse_value, value_problem
from .common import (
    Dropped,
    EntryErrors,
    build_session,
    check_quaternion_order,
    check_units,
    detect_unit,
    quaternion_pose_problems,
    read_text,
)

__all__ = ["FORMAT", "DEFAULT_SETUP", "CAMERA_POSES", "read_stream", "read_pose_stream", "pair_by_stamp",
           "looks_like_stream", "split_stream_files"]

FORMAT = "stream"
#: No default set-up: the files this tool writes declare what their poses are, and with the data
#: that decides the set-up (``inference``); the set-up of the source's own example data is only a hint.
DEFAULT_SETUP = None
CAMERA_POSES = ("camera_in_target", "target_in_camera")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def looks_like_stream(head: str) -> bool:
    """CSV lines of 8 numbers whose first (the stamp) is large: ``t, x, y, z, q, q, q, q``."""
    lines = [ln for ln in head.splitlines() if ln.strip() and not ln.lstrip().startswith("#")][:3]
    if not lines:
        return False
    body = lines[1:] if not all(_is_number(f) for f in lines[0].split(",")) else lines
    for line in body[:2]:
        fields = [f.strip() for f in line.split(",")]
        if len(fields) != 8 or not all(_is_number(f) for f in fields):
            return False
    return bool(body)


def split_stream_files(paths) -> tuple[Path, Path]:
    """(robot stream, camera stream) from two files, or a folder holding exactly two CSV files.

    A name containing ``target`` or ``camera`` marks the camera stream (the ETH layout); otherwise
    the order given is kept: robot first, camera second.
    """
    if isinstance(paths, (str, Path)):
        paths = [paths]
    paths = [Path(p) for p in paths]
    if len(paths) == 1 and paths[0].is_dir():
        csvs = sorted(p for p in paths[0].iterdir() if p.suffix.lower() == ".csv")
        if len(csvs) != 2:
            raise SessionError(f"{paths[0]}: expected two CSV streams (robot, camera); found {len(csvs)} CSV files")
        paths = csvs
    if len(paths) != 2:
        raise SessionError(f"a stream import needs two CSV files, robot stream then camera stream; got {len(paths)}")
    marked = [any(word in p.name.lower() for word in ("target", "camera", "marker")) for p in paths]
    if marked == [True, False]:
        return paths[1], paths[0]
    return paths[0], paths[1]


def read_pose_stream(path, order: str = "xyzw", errors: EntryErrors | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Stamps ``(n,)`` and poses ``(n, 4, 4)`` (file units) of one CSV stream.

    The lines are split one by one and the poses converted all at once (a 250-Hz log has hundreds
    of thousands of lines); malformed lines are reported in file order, as they come.

    Parameters
    ----------
    path : str or Path
    order : str
        Quaternion order of the file, ``xyzw`` or ``wxyz``.
    errors : EntryErrors, optional
        Where malformed lines go (dropped when it skips invalid entries); default: stop at the first.

    Raises
    ------
    SessionError
        Naming the file and line of the first malformed row.
    """
    check_quaternion_order(order)
    errors = errors or EntryErrors(path, False, Dropped())
    numbers, rows, problems = _stream_rows(read_text(path), order)
    values = np.array(rows, dtype=float).reshape(-1, 8)
    reasons = _pose_problems(values, order)
    problems += [(numbers[k], reasons[k]) for k in range(len(rows)) if reasons[k]]
    for number, reason in sorted(problems):
        errors.bad(f"line {number}", reason)
    good = np.array([not r for r in reasons], dtype=bool)
    if not good.any():
        raise SessionError(f"{path}: no pose lines")
    values = values[good]
    q = values[:, 4:8] / np.linalg.norm(values[:, 4:8], axis=1, keepdims=True)
    poses = np.broadcast_to(np.eye(4), (len(values), 4, 4)).copy()
    poses[:, :3, :3] = Rotation.from_quat(q, scalar_first=(order == "wxyz")).as_matrix()
    poses[:, :3, 3] = values[:, 1:4]
    return values[:, 0], poses


def _stream_rows(text: str, order: str) -> tuple[list, list, list]:
    """The line numbers and values of the lines of 8 numbers, and ``(line, reason)`` of the others
    (blank lines, comments and a header line left out: :mod:`handeye.station.csv_values`)."""
    numbers, rows, problems = [], [], []
    first = True
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        fields = [f.strip() for f in stripped.split(",")]
        if first and is_header(fields):
            first = False
            continue  # a header line: no field of it looks like a number
        first = False
        bad = next((p for p in map(value_problem, fields) if p), None)
        if bad:
            problems.append((number, bad))
            continue
        if len(fields) != 8:
            problems.append((number, f"expected 8 values (t, x, y, z, quaternion {order}); got {len(fields)}"))
            continue
        rows.append([parse_value(f) for f in fields])
        numbers.append(number)
    return numbers, rows, problems


def _pose_problems(values: np.ndarray, order: str) -> list:
    """Per row of ``(n, 8)`` stream values: why it is not a pose (``common.quaternion_pose_problems``,
    then an infinite stamp), or ``""``."""
    out = quaternion_pose_problems(values[:, 1:8], order)
    for k in np.flatnonzero(~np.isfinite(values[:, 0])):
        out[k] = out[k] or "the stamp is not finite"
    return out


def pair_by_stamp(robot_t, camera_t, tolerance_s: float) -> tuple[np.ndarray, np.ndarray]:
    """For every camera stamp the index of the nearest robot stamp and the offset (s).

    Parameters
    ----------
    robot_t : ndarray, shape (n,)
        Sorted robot stamps.
    camera_t : ndarray, shape (m,)

    Returns
    -------
    nearest : ndarray of int, shape (m,)
    offset : ndarray, shape (m,)
        ``|camera_t - robot_t[nearest]|``; compare with ``tolerance_s``.
    """
    right = np.clip(np.searchsorted(robot_t, camera_t), 1, len(robot_t) - 1) if len(robot_t) > 1 else np.zeros(len(camera_t), int)
    left = np.maximum(right - 1, 0)
    take_left = np.abs(camera_t - robot_t[left]) <= np.abs(camera_t - robot_t[right])
    nearest = np.where(take_left, left, right)
    return nearest, np.abs(camera_t - robot_t[nearest])


def _hand_speeds(t, poses, scale_mm) -> tuple[np.ndarray, np.ndarray]:
    """Translational (mm/s) and angular (deg/s) speed at each robot sample (central differences)."""
    n = len(t)
    if n < 2:
        return np.zeros(n), np.zeros(n)
    lo = np.maximum(np.arange(n) - 1, 0)
    hi = np.minimum(np.arange(n) + 1, n - 1)
    dt = np.maximum(t[hi] - t[lo], 1e-9)
    v = np.linalg.norm(poses[hi, :3, 3] - poses[lo, :3, 3], axis=1) * scale_mm / dt
    rel = np.einsum("nji,njk->nik", poses[lo, :3, :3], poses[hi, :3, :3])
    w = np.degrees(np.linalg.norm(Rotation.from_matrix(rel).as_rotvec(), axis=1)) / dt
    return v, w


def _moving(keep, v, w, camera_t, rest_mm_s, rest_deg_s, dropped: Dropped) -> np.ndarray:
    """Pairs ``(m,)`` among ``keep`` whose hand moves faster than the rest limits (reported as dropped)."""
    if rest_mm_s is None and rest_deg_s is None:
        return np.zeros(len(keep), dtype=bool)
    moving = keep & (((v > rest_mm_s) if rest_mm_s is not None else False)
                     | ((w > rest_deg_s) if rest_deg_s is not None else False))
    limits = " / ".join(s for s in (f"{rest_mm_s:g} mm/s" if rest_mm_s is not None else "",
                                    f"{rest_deg_s:g} deg/s" if rest_deg_s is not None else "") if s)
    for k in np.flatnonzero(moving):
        dropped.add(f"hand moving (faster than {limits})", f"t={camera_t[k]:.3f}")
    return moving


def _slowest_per_window(candidates, camera_t, v, w, max_postures: int, dropped: Dropped) -> np.ndarray:
    """At most ``max_postures`` of the ``candidates`` (camera sample indices): the slowest pair in each of
    as many time windows (0 keeps all); the others are reported as dropped."""
    if not max_postures or len(candidates) <= max_postures:
        return candidates
    edges = np.linspace(camera_t[candidates[0]], camera_t[candidates[-1]], max_postures + 1)
    window = np.clip(np.searchsorted(edges, camera_t[candidates], side="right") - 1, 0, max_postures - 1)
    score = v[candidates] / 100.0 + w[candidates] / 10.0  # 100 mm/s ~ 10 deg/s
    order = np.lexsort((np.arange(len(candidates)), score, window))  # by window, slowest (then earliest) first
    first = order[np.r_[True, window[order][1:] != window[order][:-1]]]
    chosen = np.sort(candidates[first]).astype(int)
    for k in np.setdiff1d(candidates, chosen):
        dropped.add(f"decimated (kept the slowest pair in each of {max_postures} time windows)",
                    f"t={camera_t[k]:.3f}")
    return chosen


def read_stream(paths, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                quaternion_order: str = "xyzw", camera_pose: str | None = None, robot_pose: str | None = None,
                tolerance_s: float = 0.03, max_postures: int = 40,
                rest_mm_s: float | None = None, rest_deg_s: float | None = None) -> Session:
    """Pair two time-stamped pose streams into a session (mm).

    Parameters
    ----------
    paths : sequence of two paths, or a folder
        Robot stream then camera stream (names with ``target``/``camera``/``marker`` mark the camera).
    setup : str, optional
        Default: detected from the data, else ``eye_in_hand``.
    units : str, optional
        ``m`` or ``mm``; default: detected (the ETH set is in metres).
    board : BoardGeometry, optional
    skip_invalid : bool
        Drop malformed lines (reported) instead of stopping at the first.
    quaternion_order : str
        ``xyzw`` (scalar last, default, the ETH layout) or ``wxyz``.
    camera_pose, robot_pose : str, optional
        Force what the streams hold (``camera_in_target`` / ``target_in_camera``, ``flange_in_base``
        / ``base_in_flange``); default: decided from the data, else the ETH layout.
    tolerance_s : float
        Largest stamp difference of a pair.
    max_postures : int
        Keep at most this many pairs, the slowest in each of as many time windows; 0 keeps all.
    rest_mm_s, rest_deg_s : float, optional
        Keep only pairs where the hand moves slower than these.

    Raises
    ------
    SessionError
    """
    check_units(units)
    check_quaternion_order(quaternion_order)
    if camera_pose is not None and camera_pose not in CAMERA_POSES:
        raise SessionError(f"camera pose must be one of {', '.join(CAMERA_POSES)}; got {brief(camera_pose)}")
    if not (tolerance_s > 0):
        raise SessionError(f"the pairing tolerance must be positive; got {tolerance_s}")
    if max_postures < 0 or (0 < max_postures < 3):
        raise SessionError(f"max postures must be 0 (keep all) or at least 3; got {max_postures}")
    robot_path, camera_path = split_stream_files(paths)
    dropped = Dropped()
    robot_t, robot_poses = read_pose_stream(robot_path, quaternion_order, EntryErrors(robot_path, skip_invalid, dropped))
    camera_t, camera_poses = read_pose_stream(camera_path, quaternion_order, EntryErrors(camera_path, skip_invalid, dropped))
    notes = []
    for name, t in (("robot", robot_t), ("camera", camera_t)):
        if np.any(np.diff(t) < 0):
            notes.append(f"the {name} stream's stamps are not in order: sorted")
    order = np.argsort(robot_t, kind="stable")
    robot_t, robot_poses = robot_t[order], robot_poses[order]
    order = np.argsort(camera_t, kind="stable")
    camera_t, camera_poses = camera_t[order], camera_poses[order]
    nearest, offset = pair_by_stamp(robot_t, camera_t, tolerance_s)
    keep = offset <= tolerance_s
    for k in np.flatnonzero(~keep):
        dropped.add(f"no robot sample within {tolerance_s * 1000:g} ms", f"t={camera_t[k]:.3f}")
    robot_unit = units or detect_unit(robot_poses)[0]
    speed_v, speed_w = _hand_speeds(robot_t, robot_poses, 1000.0 if robot_unit == "m" else 1.0)
    v, w = speed_v[nearest], speed_w[nearest]
    keep &= ~_moving(keep, v, w, camera_t, rest_mm_s, rest_deg_s, dropped)
    paired = np.flatnonzero(keep)
    candidates = _slowest_per_window(paired, camera_t, v, w, max_postures, dropped)
    labels = [f"t={camera_t[k]:.4f} (robot t={robot_t[nearest[k]]:.4f}, {offset[k] * 1000:.1f} ms apart)"
              for k in candidates]
    details = {"pairing": {"tolerance_ms": tolerance_s * 1000.0, "robot_samples": int(len(robot_t)),
                           "camera_samples": int(len(camera_t)),
                           "max_postures": int(max_postures)}}
    if len(candidates) < len(paired):
        details["decimated"] = {"rows": int(len(camera_t)), "pairs": int(len(paired)), "postures": int(len(candidates)),
                                "how": f"keeping the slowest pair in each of {max_postures} time windows (--max-postures)"}
    return build_session(FORMAT, [robot_path, camera_path], robot_poses[nearest[candidates]],
                         camera_poses[candidates], labels, setup=setup, default_setup=DEFAULT_SETUP, units=units,
                         documented_units="m", board=board, dropped=dropped, entries_read=len(camera_t),
                         notes=notes, details=details, robot_pose=robot_pose, camera_pose=camera_pose,
                         camera_declared="camera_in_target", robot_words=f"quaternion ({', '.join(quaternion_order)})",
                         camera_words=f"quaternion ({', '.join(quaternion_order)})")
