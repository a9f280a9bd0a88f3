"""When the data cannot tell readings apart: what each would give, and the flags that pick it.

A refusal that only says "pass --euler or --setup" leaves the user to guess; each reading left gives
a different camera mount ``X``, and the user usually knows roughly where the camera is (a tape
measure, the CAD model). So the refusal carries one line per reading: the flags that select it and
the ``X`` it gives (translation in mm, rotation as an angle about an axis), from the same linear
AX = XB fit that scored it (``calibration.invariants.fit_hand_eye``; a yardstick, not a calibration).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ...base import SessionError
from ...calibration import fit_hand_eye, pair_indices
from ...calibration import EYE_IN_HAND
from ...geometry import invert_transforms
from .readings import FIT_PAIRS, Reading, Side, pose_outcome

__all__ = ["AmbiguousReading", "choice_lines", "reading_flags"]

#: At most this many readings are listed.
MAX_CHOICES = 6


class AmbiguousReading(SessionError):
    """The data fit several readings equally well; ``choices`` holds one line per reading (flags, X)."""

    def __init__(self, message: str, choices: list):
        super().__init__(message)
        self.choices = list(choices)


def _rotation_flag(side: str, key: str) -> str | None:
    """The flag that selects side reading ``key`` (``euler:ZYX:deg``, ``rotvec``, ``quaternion:wxyz``)."""
    kind, _, rest = key.partition(":")
    if kind == "euler":
        return f"--euler {side}:{rest}"
    if kind == "rotvec":
        return f"--euler {side}:{'rvec-tvec' if rest == 'first' else 'rotvec'}"
    if kind == "quaternion":
        return f"--quaternion-order {rest.split(':')[0]}"
    return None


def reading_flags(robot: Side, camera: Side, r: Reading, names: list) -> list:
    """The flags (with values) among ``names`` that select reading ``r``."""
    flags = []
    if "--euler" in names or "--quaternion-order" in names:
        for side, key in (("robot", robot.readings[r.robot].key), ("camera", camera.readings[r.camera].key)):
            flag = _rotation_flag(side, key)
            if flag and flag.split()[0] in names and flag not in flags:
                flags.append(flag)
    for attr, flag in (("robot_pose", "--robot-pose"), ("camera_pose", "--camera-pose"), ("setup", "--setup")):
        if flag in names:
            flags.append(f"{flag} {getattr(r, attr)}")
    if "--units" in names and r.units[0] == r.units[1]:
        flags.append(f"--units {r.units[0]}")
    return flags


def _mount_words(robot: Side, camera: Side, r: Reading) -> str:
    """``camera in flange at (x, y, z) mm, turned A deg about (ax, ay, az)`` for reading ``r``."""
    tool0, target = pose_outcome(robot, camera, r)
    hand = tool0 if r.setup == EYE_IN_HAND else invert_transforms(tool0)
    x = fit_hand_eye(hand, target, pair_indices(len(tool0), FIT_PAIRS)).x
    where = "camera in flange" if r.setup == EYE_IN_HAND else "camera in base"
    if not np.all(np.isfinite(x)):
        return f"{where}: too little rotation to fit"
    vector = Rotation.from_matrix(x[:3, :3]).as_rotvec(degrees=True)
    angle = float(np.linalg.norm(vector))
    axis = vector / angle if angle > 1e-9 else np.array([0.0, 0.0, 1.0])
    t = x[:3, 3]
    return (f"{where} at ({t[0]:.1f}, {t[1]:.1f}, {t[2]:.1f}) mm, turned {angle:.1f} deg about "
            f"({axis[0]:.3f}, {axis[1]:.3f}, {axis[2]:.3f})")


def choice_lines(robot: Side, camera: Side, readings: list, names: list) -> list:
    """One line per reading (the best of each outcome, at most :data:`MAX_CHOICES`): flags, then the X it gives.

    Parameters
    ----------
    robot, camera : Side
    readings : list of Reading
        The best reading of each outcome the data leave, best first.
    names : list of str
        The flags that tell them apart (``inference._flag_names``).
    """
    lines = []
    for r in readings[:MAX_CHOICES]:
        flags = " ".join(reading_flags(robot, camera, r, names)) or "(no flag tells it apart)"
        lines.append(f"{flags}: {_mount_words(robot, camera, r)}")
    if len(readings) > MAX_CHOICES:
        lines.append(f"... and {len(readings) - MAX_CHOICES} more (give one of the flags above to narrow them down)")
    return lines
