"""ViSP pose vectors: a folder of ``pose_fPe_<i>.yaml`` (or ``<robot>_pose_rPe_<i>.yaml``) and
``pose_cPo_<i>.yaml`` files, as ViSP's hand-eye tutorial and apps write them.

Each file is a ``vpPoseVector`` saved as YAML::

    rows: 6
    cols: 1
    data:
      - [tx]
      - [ty]
      - [tz]
      - [θux]
      - [θuy]
      - [θuz]

translation in metres, rotation as axis x angle (θu, radians). ``fPe`` / ``rPe`` is the end
effector in the robot base frame (``tool0_in_base``); ``cPo`` the object (the board) in the camera
frame (``target_in_camera``). Files pair by their number ``<i>``; a number with only one of the
two is dropped and reported. ViSP's tutorial is eye-in-hand, the default set-up (unless the data
clearly say otherwise).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import yaml

from ...calibration.errors import SessionError
from ...calibration.session import Session
from .common import Dropped, EntryErrors, build_session, read_text, transform_from_rotvec

__all__ = ["FORMAT", "DEFAULT_SETUP", "read_visp", "read_pose_vector", "looks_like_visp", "ROBOT_PATTERN", "CAMERA_PATTERN"]

FORMAT = "visp"
DEFAULT_SETUP = "eye_in_hand"
#: ``pose_fPe_3.yaml``, ``franka_pose_rPe_3.yaml``: end effector in the robot base.
ROBOT_PATTERN = re.compile(r"(?:^|_)pose_(?:fPe|rPe)_(\d+)\.ya?ml$")
#: ``pose_cPo_3.yaml``: the object (board) in the camera frame.
CAMERA_PATTERN = re.compile(r"(?:^|_)pose_cPo_(\d+)\.ya?ml$")


def looks_like_visp(path) -> bool:
    """A folder holding ViSP pose files, or one such file."""
    path = Path(path)
    if path.is_dir():
        return any(ROBOT_PATTERN.search(p.name) or CAMERA_PATTERN.search(p.name) for p in path.iterdir())
    return bool(ROBOT_PATTERN.search(path.name) or CAMERA_PATTERN.search(path.name))


def read_pose_vector(path) -> np.ndarray:
    """The six numbers ``[tx, ty, tz, θux, θuy, θuz]`` of one ViSP pose file.

    Raises
    ------
    SessionError
        Not YAML (with the line), no ``data``, not six numbers.
    """
    text = read_text(path)
    if text.startswith("%YAML"):  # OpenCV-style directive line that PyYAML rejects
        text = "\n" + text.split("\n", 1)[-1] if "\n" in text else ""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise SessionError(f"{path}: not valid YAML{where}") from None
    if not isinstance(data, dict) or "data" not in data:
        raise SessionError(f"{path}: expected a ViSP pose vector (keys rows, cols, data)")
    try:
        values = np.asarray(data["data"], dtype=float).ravel()
    except (TypeError, ValueError):
        raise SessionError(f"{path}: data must hold six numbers [tx, ty, tz, θux, θuy, θuz]") from None
    if values.size != 6:
        raise SessionError(f"{path}: data must hold six numbers [tx, ty, tz, θux, θuy, θuz]; got {values.size}")
    return values


def _collect(paths) -> tuple[dict, dict, list]:
    robot, camera, other = {}, {}, []
    for p in paths:
        m_robot, m_camera = ROBOT_PATTERN.search(p.name), CAMERA_PATTERN.search(p.name)
        if m_robot:
            number = int(m_robot.group(1))
            if number in robot:
                raise SessionError(f"{p.parent}: two robot pose files numbered {number}: {robot[number].name} and {p.name}")
            robot[number] = p
        elif m_camera:
            number = int(m_camera.group(1))
            if number in camera:
                raise SessionError(f"{p.parent}: two board pose files numbered {number}: {camera[number].name} and {p.name}")
            camera[number] = p
        else:
            other.append(p)
    return robot, camera, other


def read_visp(path, *, setup=None, units=None, board=None, skip_invalid: bool = False) -> Session:
    """Read ViSP pose files into a session (mm).

    Parameters
    ----------
    path : str, Path or list of them
        A folder holding the pose files, or the files themselves.
    setup : str, optional
        Default: detected from the data, else ``eye_in_hand``.
    units : str, optional
        ``m`` or ``mm``; default: detected (ViSP writes metres).
    board : BoardGeometry, optional
    skip_invalid : bool
        Drop unreadable pose files (reported) instead of stopping at the first.

    Raises
    ------
    SessionError
    """
    if isinstance(path, (str, Path)):
        folder = Path(path)
        if folder.is_dir():
            files = sorted(p for p in folder.iterdir() if p.is_file())
        elif folder.exists():
            files = [folder]
        else:
            raise SessionError(f"{folder}: no such file or folder")
        source = folder
    else:
        files = [Path(p) for p in path]
        source = [str(p) for p in files]
    robot_files, camera_files, _ = _collect(files)
    where = source if isinstance(source, Path) else (Path(files[0]).parent if files else "input")
    if not robot_files:
        raise SessionError(f"{where}: no robot pose files (pose_fPe_<i>.yaml or <robot>_pose_rPe_<i>.yaml)")
    if not camera_files:
        raise SessionError(
            f"{where}: robot poses ({len(robot_files)} files) but no board poses (pose_cPo_<i>.yaml): "
            f"compute them first (e.g. ViSP's visp-compute-chessboard-poses on the images)")
    dropped = Dropped()
    errors = EntryErrors(where, skip_invalid, dropped)
    robot, camera, labels = [], [], []
    for number in sorted(set(robot_files) | set(camera_files)):
        if number not in camera_files:
            dropped.add("robot pose without a board pose (pose_cPo) of the same number", robot_files[number].name)
            continue
        if number not in robot_files:
            dropped.add("board pose without a robot pose (pose_fPe/rPe) of the same number", camera_files[number].name)
            continue
        pair = []
        for file in (robot_files[number], camera_files[number]):
            try:
                v = read_pose_vector(file)
                pair.append(transform_from_rotvec(v[:3], v[3:]))
            except (SessionError, ValueError) as exc:
                reason = str(exc).split(": ", 1)[-1] if isinstance(exc, SessionError) else str(exc)
                errors.bad(file.name, reason)
                break
        if len(pair) != 2:
            continue
        robot.append(pair[0])
        camera.append(pair[1])
        labels.append(f"{robot_files[number].name} + {camera_files[number].name}")
    return build_session(FORMAT, source, np.array(robot).reshape(-1, 4, 4), np.array(camera).reshape(-1, 4, 4), labels,
                         setup=setup, default_setup=DEFAULT_SETUP, units=units, documented_units="m", board=board,
                         dropped=dropped, entries_read=len(set(robot_files) | set(camera_files)))
