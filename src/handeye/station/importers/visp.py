"""ViSP pose vectors: a folder of ``pose_fPe_<i>.yaml`` (or ``<robot>_pose_rPe_<i>.yaml``, newer
``pose_w_P_ee-<i>.yaml``) and ``pose_cPo_<i>.yaml`` (newer ``pose_c_P_o-<i>.yaml``) files, as
ViSP's hand-eye tutorial and apps write them.

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
two is dropped and reported.

A ViSP *app* folder holds robot poses and images only (``<robot>_image-<i>.png``, the intrinsics
``<robot>_camera.xml``, ``chessboard-data.txt``): the board poses are then measured from the
images with OpenCV (see ``visp_images``), expressed in metres like ViSP's own ``pose_cPo`` files;
images where the board is not found are dropped and reported. ViSP's tutorial is eye-in-hand, the default set-up (unless the data
clearly say otherwise).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ...base import SessionError, SessionUsageError
from ...calibration import Session
from ...geometry import BoardGeometry
from ...base import parse_yaml
from .common import Dropped, EntryErrors, build_session, flat_numbers, read_text, transform_from_rotvec
from .visp_images import (find_images, measure_board_pose, measure_tag_pose, read_apriltag_data, read_chessboard_data,
                          read_visp_camera)

__all__ = ["FORMAT", "DEFAULT_SETUP", "read_visp", "read_pose_vector", "looks_like_visp", "ROBOT_PATTERN", "CAMERA_PATTERN"]

FORMAT = "visp"
THETA_U = "ViSP pose vector: rotation vector theta-u (axis x angle, radians)"
#: No default set-up: the files this tool writes declare what their poses are, and with the data
#: that decides the set-up (``inference``); the set-up of the source's own example data is only a hint.
DEFAULT_SETUP = None
#: ``pose_fPe_3.yaml``, ``franka_pose_rPe_3.yaml``, ``pose_w_P_ee-3.yaml`` (newer ViSP): end effector
#: in the robot base.
ROBOT_PATTERN = re.compile(r"(?:^|_)(?:pose_(?:fPe|rPe)_|(?:pose_)?w_P_ee-)(\d+)\.ya?ml$")
#: ``pose_cPo_3.yaml``, ``pose_c_P_o-3.yaml`` (newer ViSP): the object (board) in the camera frame.
CAMERA_PATTERN = re.compile(r"(?:^|_)(?:pose_cPo_|(?:pose_)?c_P_o-)(\d+)\.ya?ml$")


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
    data = parse_yaml(text, path)
    if not isinstance(data, dict) or "data" not in data:
        raise SessionError(f"{path}: expected a ViSP pose vector (keys rows, cols, data)")
    try:
        return flat_numbers(data["data"], 6)
    except ValueError as exc:
        raise SessionError(f"{path}: data must hold six numbers [tx, ty, tz, θux, θuy, θuz]; {exc}") from None


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


def read_visp(path, *, setup=None, units=None, board=None, skip_invalid: bool = False, robot_pose=None,
              camera_pose=None, tag_mm: float | None = None) -> Session:
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
    robot_pose, camera_pose : str, optional
        Force what the pose files hold (default: decided from the data, else ViSP's ``rPe`` / ``cPo``).
    tag_mm : float, optional
        App folders with images: measure an AprilTag 36h11 of this size (the black square's side,
        mm) instead of a chessboard.

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
    if tag_mm is not None and not (np.isfinite(tag_mm) and 0 < tag_mm <= 10000):
        raise SessionUsageError(f"--tag-mm must be the tag's side in mm (0 .. 10000); got {tag_mm}")
    if not camera_files:
        images = find_images(files)
        if images:
            return _read_with_images(where, source, files, robot_files, images, setup, units, board, skip_invalid,
                                    robot_pose, camera_pose, tag_mm)
        raise SessionError(
            f"{where}: robot poses ({len(robot_files)} files) but no board poses (pose_cPo_<i>.yaml) and no "
            f"images (<robot>_image-<i>.png) to measure them from")
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
                         dropped=dropped, entries_read=len(set(robot_files) | set(camera_files)),
                         robot_pose=robot_pose, camera_pose=camera_pose, robot_words=THETA_U, camera_words=THETA_U)


def _known_board(board: BoardGeometry | None, where) -> BoardGeometry:
    """The chessboard the images are measured with: :func:`_read_with_images` reads it (ViSP's
    chessboard-data.txt) or refuses the images without one when no AprilTag is given."""
    if board is None:
        raise SessionError(f"{where}: no chessboard (--board, --square-mm) to measure the images with")
    return board


def _read_with_images(where, source, files, robot_files, images, setup, units, board, skip_invalid, robot_pose=None,
                      camera_pose=None, tag_mm=None) -> Session:
    """Robot pose files + images: measure the board (chessboard or AprilTag) poses, then build the session."""
    xml = [p for p in files if p.suffix.lower() == ".xml"]
    if len(xml) != 1:
        raise SessionError(f"{where}: board poses must be measured from the images, which needs exactly one ViSP "
                           f"camera file (*.xml with px, py, u0, v0); found {len(xml)}")
    camera = read_visp_camera(xml[0])
    if tag_mm is None and (board is None or board.square_mm is None):
        data = [p for p in files if p.name == "chessboard-data.txt"]
        tags = [p for p in files if p.name == "apriltag-data.txt"]
        if tags and data:
            raise SessionError(f"{where}: both chessboard-data.txt and apriltag-data.txt: pass --tag-mm MM (the "
                               f"AprilTag) or --board NXxNY --square-mm MM (the chessboard)")
        if tags:
            tag_mm = read_apriltag_data(tags[0])
        elif not data:
            raise SessionError(f"{where}: the target's size is needed to measure its poses from the images: pass "
                               f"--tag-mm MM (an AprilTag 36h11) or --board NXxNY --square-mm MM (a chessboard; or add "
                               f"ViSP's chessboard-data.txt)")
        else:
            board = read_chessboard_data(data[0])
    target = f"AprilTag 36h11 of {tag_mm:g} mm" if tag_mm is not None else "board"
    dropped = Dropped()
    errors = EntryErrors(where, skip_invalid, dropped)
    robot, measured, labels, rms = [], [], [], []
    turned = 0
    for number in sorted(set(robot_files) | set(images)):
        if number not in images:
            dropped.add("robot pose without an image of the same number", robot_files[number].name)
            continue
        if number not in robot_files:
            dropped.add("image without a robot pose of the same number", images[number].name)
            continue
        try:
            v = read_pose_vector(robot_files[number])
            pose = transform_from_rotvec(v[:3], v[3:])
        except (SessionError, ValueError) as exc:
            errors.bad(robot_files[number].name, str(exc).split(": ", 1)[-1])
            continue
        try:
            if tag_mm is not None:
                result = measure_tag_pose(images[number], tag_mm, camera)
            else:
                result = measure_board_pose(images[number], _known_board(board, where), camera)
        except ValueError as exc:
            dropped.add(f"{target.split(' of ')[0]} not measured ({exc})", images[number].name)
            continue
        target_pose = result["pose"].copy()
        target_pose[:3, 3] /= 1000.0  # metres, like ViSP's pose_cPo files
        robot.append(pose)
        measured.append(target_pose)
        rms.append(result["rms_px"])
        turned += result.get("turned", False)
        labels.append(f"{robot_files[number].name} + {images[number].name} (measured, {result['rms_px']:.3f} px rms)")
    if tag_mm is not None:
        what = f"AprilTag 36h11, {tag_mm:g} mm"
    else:
        chessboard = _known_board(board, where)
        what = f"chessboard {chessboard.corners[0]}x{chessboard.corners[1]}, {chessboard.square_mm:g} mm squares"
    notes = [f"{'tag' if tag_mm is not None else 'board'} poses measured from {len(measured)} images with OpenCV "
             f"({what}, intrinsics from {xml[0].name})"]
    if turned:
        notes.append(f"{turned} detection(s) turned 180 deg to the conventions' board orientation")
    details = {"board_measurement": {"camera_file": str(xml[0]), "px": camera.px, "py": camera.py, "u0": camera.u0,
                                     "v0": camera.v0, "kud": camera.kud, "target": what,
                                     "max_rms_px": float(max(rms)) if rms else None}}
    return build_session(FORMAT, source, np.array(robot).reshape(-1, 4, 4), np.array(measured).reshape(-1, 4, 4),
                         labels, setup=setup, default_setup=DEFAULT_SETUP, units=units, documented_units="m",
                         board=board if tag_mm is None else None, dropped=dropped,
                         entries_read=len(set(robot_files) | set(images)), notes=notes, details=details,
                         robot_pose=robot_pose, camera_pose=camera_pose, robot_words=THETA_U,
                         camera_words=f"measured from the images ({what})")
