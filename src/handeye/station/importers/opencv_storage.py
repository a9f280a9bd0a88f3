"""OpenCV FileStorage pose pairs (camodocal's ``TransformPairsInput.yml`` layout).

Layout, YAML or XML as OpenCV writes them::

    %YAML:1.0
    frameCount: 42                 optional
    T1_0: !!opencv-matrix          robot: end effector in base (tool0_in_base), 4x4, metres
       rows: 4
       cols: 4
       dt: d
       data: [ ... 16 values, row-major ... ]
    T2_0: !!opencv-matrix          camera: marker/board in camera (target_in_camera), 4x4, metres
       ...

Pairs are ``T1_<i>`` / ``T2_<i>`` for ``i = 0, 1, ...`` (other prefixes by option). The file is read
with ``cv2.FileStorage``. A folder (or several files) is read as camodocal leaves it: its pairs file
(``TransformPairsInput.yml``; a ``TransformPairsOutput.yml`` with the same pairs is read once) and,
beside it, the tool's own result (``CalibratedTransform.yml``: ``ArmTipToMarkerTagTransform`` or
``eeTeye``, one 4x4 matrix), which is skipped and named in the notes, as is any other file.
Default set-up: detected from the data when they decide it clearly, else ``eye_to_hand`` (the
camodocal example, an AR tag on the arm seen by a fixed camera).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from ...base import SessionError
from ...calibration import Session
from .common import Dropped, EntryErrors, build_session, read_text, rigid_transform
from .head import head_text

__all__ = ["FORMAT", "DEFAULT_SETUP", "read_opencv", "looks_like_opencv", "pairs_files"]

FORMAT = "opencv"
#: No default set-up: the files this tool writes declare what their poses are, and with the data
#: that decides the set-up (``inference``); the set-up of the source's own example data is only a hint.
DEFAULT_SETUP = None
#: The suffixes of OpenCV FileStorage files looked into in a folder (XML, YAML).
_SUFFIXES = (".yml", ".yaml", ".xml")
_KEY = re.compile(r"^([A-Za-z][A-Za-z0-9]*)_(\d+)$")


def looks_like_opencv(path, head: str) -> bool:
    """An OpenCV FileStorage file (``%YAML:1.0`` or ``<opencv_storage>``) holding ``T1_0``-like matrices."""
    start = head.lstrip()
    return (start.startswith("%YAML:1.") or "<opencv_storage>" in head[:200]) and (
        "opencv-matrix" in head or "T1_0" in head)


def _has_pairs(head: str, robot_prefix: str = "T1", camera_prefix: str = "T2") -> bool:
    """An OpenCV FileStorage head naming a ``T1_<i>`` / ``T2_<i>`` matrix (YAML key or XML element)."""
    names = f"(?:{re.escape(robot_prefix)}|{re.escape(camera_prefix)})"
    return looks_like_opencv("", head) and re.search(rf"^\s*<?{names}_\d+\b", head, re.M) is not None


def _skipped(path: Path, head: str) -> str:
    """Why a file beside the pairs is left out, for the notes."""
    start = head.lstrip()
    if start.startswith("%YAML:1.") or "<opencv_storage>" in head[:200]:
        keys = re.findall(r"^<?([A-Za-z_]\w*)[:> ]", head, re.M)
        keys = [k for k in keys if k not in ("opencv_storage", "rows", "cols", "dt", "data")]
        what = f" ({', '.join(keys[:2])})" if keys else ""
        return f"{path.name} skipped: an OpenCV file without pose pairs{what}, e.g. camodocal's own result"
    return f"{path.name} skipped: not an OpenCV file of pose pairs"


def pairs_files(paths, robot_prefix: str = "T1", camera_prefix: str = "T2") -> tuple[Path, list] | None:
    """The file of pose pairs among ``paths`` (a folder, or files) and notes on the files left out.

    Returns
    -------
    (Path, list of str) or None
        None when no file holds ``T1_<i>`` / ``T2_<i>`` pairs.

    Raises
    ------
    SessionError
        Two files hold different pairs.
    """
    paths = [Path(p) for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
    folder = len(paths) == 1 and paths[0].is_dir()
    if folder:
        paths = sorted(p for p in paths[0].iterdir() if p.is_file() and not p.name.startswith("."))
    heads = {p: head_text(p, strict=False) for p in paths
             if p.is_file() and (not folder or p.suffix.lower() in _SUFFIXES)}
    pairs = [p for p in paths if p in heads and _has_pairs(heads[p], robot_prefix, camera_prefix)]
    if not pairs:
        return None
    notes = [_skipped(p, heads.get(p, "")) for p in paths if p not in pairs]
    for other in pairs[1:]:
        if read_text(other) != read_text(pairs[0]):
            raise SessionError(f"{pairs[0].name} and {other.name} both hold {robot_prefix}_<i> / {camera_prefix}_<i> "
                               f"pose pairs, and they differ: give one of them")
        notes.append(f"{other.name} skipped: the same pairs as {pairs[0].name}")
    return pairs[0], notes


def _cv_message(exc: BaseException) -> str:
    """The useful part of an OpenCV error: ``line N: message`` when OpenCV names a line."""
    text = str(exc.__cause__ or exc).strip()
    found = re.search(r"in function '.*?\((\d+)\):\s*(.*?)'?\s*$", text, re.S)
    if found:
        return f"line {found.group(1)}: {found.group(2).strip()}"
    found = re.search(r"error: \([-\d]+:([^)]*)\)\s*(.*?)(?: in function .*)?$", text, re.S)
    if found:
        return f"{found.group(1).strip()}: {found.group(2).strip()}"
    return text.splitlines()[0] if text else type(exc).__name__


def _source(path, robot_prefix: str, camera_prefix: str) -> tuple[Path, list]:
    """The pairs file to read (``path`` itself, or the one in a folder or among files) and the notes on
    the files left out."""
    several = isinstance(path, (list, tuple))
    if not several and not Path(path).is_dir():
        return Path(path), []
    if several and len(path) == 1 and not Path(path[0]).is_dir():
        return Path(path[0]), []
    found = pairs_files(path, robot_prefix, camera_prefix)
    if found is None:
        where = ", ".join(str(p) for p in path) if several else f"{path}"
        raise SessionError(f"{where}: no file holds {robot_prefix}_<i> / {camera_prefix}_<i> pose pairs "
                           f"(camodocal's TransformPairsInput.yml)")
    return found


def read_opencv(path, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                robot_prefix: str = "T1", camera_prefix: str = "T2", robot_pose=None, camera_pose=None) -> Session:
    """Read OpenCV FileStorage pose pairs into a session (mm).

    Parameters
    ----------
    path : str or Path
    setup : str, optional
        Default: detected from the data, else ``eye_to_hand``.
    units : str, optional
        ``m`` or ``mm``; default: detected (camodocal writes metres).
    board : BoardGeometry, optional
    skip_invalid : bool
        Drop malformed pairs (reported) instead of stopping at the first.
    robot_prefix, camera_prefix : str
        Matrix names ``<prefix>_<i>`` of the robot and camera poses.

    Raises
    ------
    SessionError
    """
    import cv2  # station-side only: the calibration core does not depend on OpenCV

    from ...drivers import refuse_base64_filestorage

    path, skipped = _source(path, robot_prefix, camera_prefix)
    # a regular UTF-8 file of sane size without base64 values: cv2 would hang on a named pipe or on a
    # damaged !!binary value
    refuse_base64_filestorage(read_text(path), path, SessionError)
    previous = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        try:
            storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        except (cv2.error, SystemError) as exc:
            raise SessionError(f"{path}: not a readable OpenCV FileStorage file ({_cv_message(exc)})") from None
        if not storage.isOpened():
            raise SessionError(f"{path}: not a readable OpenCV FileStorage file")
        try:
            return _read_pairs(path, storage, setup, units, board, skip_invalid, robot_prefix, camera_prefix,
                               robot_pose, camera_pose, skipped)
        except (cv2.error, SystemError) as exc:
            raise SessionError(f"{path}: not a readable OpenCV FileStorage file ({_cv_message(exc)})") from None
        finally:
            storage.release()
    finally:
        cv2.utils.logging.setLogLevel(previous)


def _read_matrix(storage, name: str):
    import cv2

    node = storage.getNode(name)
    if node.isNone():
        return None
    try:
        matrix = node.mat()
    except (cv2.error, SystemError) as exc:
        raise ValueError(f"not a matrix ({_cv_message(exc)})") from None
    if matrix is None:
        raise ValueError("not an opencv-matrix")
    return rigid_transform(matrix)


def _read_pairs(path, storage, setup, units, board, skip_invalid, robot_prefix, camera_prefix, robot_pose=None,
                camera_pose=None, skipped=()) -> Session:
    import cv2

    indices = set()
    root = storage.root()
    for name in (root.keys() if root.isMap() else []):
        found = _KEY.match(name)
        if found and found.group(1) in (robot_prefix, camera_prefix):
            indices.add(int(found.group(2)))
    if not indices:
        raise SessionError(f"{path}: no {robot_prefix}_<i> / {camera_prefix}_<i> matrices (camodocal TransformPairsInput layout)")
    count_node = storage.getNode("frameCount")
    declared = None
    if count_node.isInt() or count_node.isReal():
        count = count_node.real()
        declared = int(count) if math.isfinite(count) else None
    dropped = Dropped()
    errors = EntryErrors(path, skip_invalid, dropped)
    robot, camera, labels = [], [], []
    for i in sorted(indices):
        pair = []
        for prefix in (robot_prefix, camera_prefix):
            name = f"{prefix}_{i}"
            try:
                m = _read_matrix(storage, name)
            except ValueError as exc:
                errors.bad(name, str(exc))
                break
            except (cv2.error, SystemError) as exc:
                errors.bad(name, _cv_message(exc))
                break
            if m is None:
                other = camera_prefix if prefix == robot_prefix else robot_prefix
                dropped.add(f"{other}_<i> without a matching {prefix}_<i>", f"pair {i}")
                break
            pair.append(m)
        if len(pair) != 2:
            continue
        robot.append(pair[0])
        camera.append(pair[1])
        labels.append(f"{robot_prefix}_{i} + {camera_prefix}_{i}")
    notes = list(skipped)
    if declared is not None and declared != len(indices):
        notes.append(f"frameCount says {declared} but the file holds {len(indices)} numbered pairs")
    return build_session(FORMAT, path, np.array(robot).reshape(-1, 4, 4), np.array(camera).reshape(-1, 4, 4), labels,
                         setup=setup, default_setup=DEFAULT_SETUP, units=units, documented_units="m", board=board,
                         dropped=dropped, entries_read=len(indices), notes=notes,
                         robot_pose=robot_pose, camera_pose=camera_pose, robot_words=f"4x4 matrix ({robot_prefix}_<i>)",
                         camera_words=f"4x4 matrix ({camera_prefix}_<i>)")
