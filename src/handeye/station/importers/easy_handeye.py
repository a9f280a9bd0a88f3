"""easy_handeye2 sample files (``<name>.samples``, YAML), as its "save samples" writes them::

    parameters:
      calibration_type: eye_in_hand          or eye_on_base (= eye-to-hand); may be empty
      robot_base_frame: ...
      ...
    samples:
    - robot:
        translation: {x: .., y: .., z: ..}     metres
        rotation: {x: .., y: .., z: .., w: ..}
      tracking:
        translation: {...}
        rotation: {...}

``tracking`` is the marker (board) in the tracking/camera frame: ``target_in_camera``. ``robot``
is a tf lookup: for ``eye_in_hand`` the effector in the robot base (``tool0_in_base``); for
``eye_on_base`` easy_handeye2 looks it up the other way round (the base in the effector). That is
what the file declares; the data decide when they can (``inference``). When ``calibration_type``
is empty nothing is declared but the effector in the base, and the set-up comes from the data.
"""

from __future__ import annotations

import numpy as np

from ...base import SessionError, brief
from ...calibration import Session
from ...base import parse_yaml
from .common import Dropped, EntryErrors, build_session, read_text, transform_from_quaternion

__all__ = ["FORMAT", "DEFAULT_SETUP", "read_easy_handeye", "looks_like_easy_handeye"]

FORMAT = "easy_handeye"
#: No default set-up: the files this tool writes declare what their poses are, and with the data
#: that decides the set-up (``inference``); the set-up of the source's own example data is only a hint.
DEFAULT_SETUP = None
_TYPES = {"eye_in_hand": "eye_in_hand", "eye_on_hand": "eye_in_hand", "eye_on_base": "eye_to_hand",
          "eye_to_hand": "eye_to_hand"}


def looks_like_easy_handeye(head: str) -> bool:
    return "samples:" in head and "tracking:" in head and "translation:" in head


def _transform(value) -> np.ndarray:
    if not isinstance(value, dict) or not isinstance(value.get("translation"), dict) or not isinstance(value.get("rotation"), dict):
        raise ValueError("needs translation {x, y, z} and rotation {x, y, z, w}")
    t, r = value["translation"], value["rotation"]
    try:
        position = [float(t[k]) for k in "xyz"]
        quaternion = [float(r[k]) for k in "xyzw"]
    except KeyError as exc:
        raise ValueError(f"lacks {exc.args[0]}") from None
    except (TypeError, ValueError, OverflowError):
        raise ValueError("holds a value that is not a number") from None
    return transform_from_quaternion(position, quaternion, "xyzw")


def read_easy_handeye(path, *, setup=None, units=None, board=None, skip_invalid: bool = False,
                      robot_pose=None, camera_pose=None) -> Session:
    """Read an easy_handeye2 ``.samples`` file into a session (mm).

    Raises
    ------
    SessionError
    """
    text = read_text(path)
    data = parse_yaml(text, path)
    if not isinstance(data, dict) or not isinstance(data.get("samples"), list):
        raise SessionError(f"{path}: expected easy_handeye2 samples (a 'samples' list of robot/tracking transforms)")
    parameters = data.get("parameters")
    if not isinstance(parameters, dict):
        parameters = {}
    kind = parameters.get("calibration_type") or ""
    if not isinstance(kind, str) or kind.strip() not in ("", *_TYPES):
        raise SessionError(f"{path}: parameters.calibration_type {brief(kind)} is neither eye_in_hand nor eye_on_base")
    kind = kind.strip()
    declared = _TYPES.get(kind)
    dropped = Dropped()
    errors = EntryErrors(path, skip_invalid, dropped)
    robot, camera, labels = [], [], []
    for k, sample in enumerate(data["samples"]):
        label = f"samples[{k}]"
        if not isinstance(sample, dict) or "robot" not in sample or "tracking" not in sample:
            errors.bad(label, "needs robot and tracking transforms")
            continue
        try:
            a = _transform(sample["robot"])
        except ValueError as exc:
            errors.bad(label, f"robot {exc}")
            continue
        try:
            b = _transform(sample["tracking"])
        except ValueError as exc:
            errors.bad(label, f"tracking {exc}")
            continue
        robot.append(a)
        camera.append(b)
        labels.append(label)
    notes = []
    if setup is not None and declared is not None and setup != declared:
        notes.append(f"--setup {setup} overrides the file's calibration_type {kind}")
    return build_session(FORMAT, path, np.array(robot).reshape(-1, 4, 4), np.array(camera).reshape(-1, 4, 4), labels,
                         setup=setup, declared_setup=declared, default_setup=DEFAULT_SETUP, units=units,
                         documented_units="m", board=board, dropped=dropped, entries_read=len(data["samples"]),
                         notes=notes, robot_pose=robot_pose, camera_pose=camera_pose,
                         robot_declared="base_in_flange" if declared == "eye_to_hand" else "flange_in_base",
                         robot_words="quaternion (x, y, z, w)", camera_words="quaternion (x, y, z, w)")
