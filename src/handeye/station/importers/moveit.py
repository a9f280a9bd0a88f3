"""MoveIt Calibration sample files (``pose_samples.json``).

Layout (the file MoveIt Calibration's solver tests read)::

    [ [T_base_eef, T_cam_target], ... ]      each T a 4x4 row-major nested list, metres

``T_base_eef`` is the end effector (flange, ``tool0``) in the robot base: ``tool0_in_base``.
``T_cam_target`` is the calibration target in the camera frame: ``target_in_camera``.
The file does not say which set-up it holds: the set-up is detected from the data when they
decide it clearly, else the default ``eye_to_hand`` (the data set in shared/datasets is eye-to-hand).
"""

from __future__ import annotations

import numpy as np

from ...base import SessionError
from ...calibration import Session
from .common import Dropped, EntryErrors, build_session, parse_json, read_text, rigid_transform

__all__ = ["FORMAT", "DEFAULT_SETUP", "read_moveit", "looks_like_moveit"]

FORMAT = "moveit"
#: No default set-up: the files this tool writes declare what their poses are, and with the data
#: that decides the set-up (``inference``); the set-up of the source's own example data is only a hint.
DEFAULT_SETUP = None


def looks_like_moveit(path, head: str) -> bool:
    """A ``.json`` file whose text starts with ``[[[[`` (a list of pairs of nested 4x4 lists)."""
    return head.lstrip().replace(" ", "").replace("\n", "").replace("\r", "").replace("\t", "").startswith("[[[[")


def read_moveit(path, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                robot_pose=None, camera_pose=None) -> Session:
    """Read a MoveIt Calibration ``pose_samples.json`` into a session (mm).

    Parameters
    ----------
    path : str or Path
    setup : str, optional
        ``eye_in_hand`` or ``eye_to_hand``; default: detected from the data, else ``eye_to_hand``.
    units : str, optional
        ``m`` or ``mm``; default: detected from the values (MoveIt writes metres).
    board : BoardGeometry, optional
        The target's geometry, when known.
    skip_invalid : bool
        Drop malformed entries (reported) instead of stopping at the first.

    Raises
    ------
    SessionError
        One line naming the file and the entry at fault.
    """
    text = read_text(path)
    data = parse_json(text, path)
    if not isinstance(data, list):
        raise SessionError(f"{path}: expected a JSON list of [T_base_eef, T_cam_target] pairs; got a {type(data).__name__}")
    dropped = Dropped()
    errors = EntryErrors(path, skip_invalid, dropped)
    robot, camera, labels = [], [], []
    for k, item in enumerate(data):
        label = f"entry {k}"
        if not isinstance(item, list) or len(item) != 2:
            errors.bad(label, "expected a pair [T_base_eef, T_cam_target] of 4x4 matrices")
            continue
        try:
            a = rigid_transform(item[0])
        except ValueError as exc:
            errors.bad(label, f"T_base_eef {exc}")
            continue
        try:
            b = rigid_transform(item[1])
        except ValueError as exc:
            errors.bad(label, f"T_cam_target {exc}")
            continue
        robot.append(a)
        camera.append(b)
        labels.append(label)
    return build_session(FORMAT, path, np.array(robot).reshape(-1, 4, 4), np.array(camera).reshape(-1, 4, 4), labels,
                         setup=setup, default_setup=DEFAULT_SETUP, units=units, documented_units="m", board=board,
                         dropped=dropped, entries_read=len(data), robot_pose=robot_pose,
                         camera_pose=camera_pose, robot_words="4x4 matrix (T_base_eef)", camera_words="4x4 matrix (T_cam_target)")
