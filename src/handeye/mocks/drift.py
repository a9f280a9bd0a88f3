"""What can change at a station after its calibration: the mock's faults (``mock.faults`` of the config).

A mild collision moves the camera on its bracket, a knock moves the board on its stand, a motor swap
with a wrong revolution-counter update moves a joint's zero. :class:`StationFaults` holds such changes
and applies them to the mock's hidden truth: the camera renders from the changed mount, sees the
changed board, from the flange pose of the axes as they physically stand (the controller's angle plus
the zero error), while the controller reports its own angles and their nominal flange pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

__all__ = ["StationFaults"]


def _turned(pose: np.ndarray, shift_mm, turn_deg) -> np.ndarray:
    """``pose`` turned by the rotation vector ``turn_deg`` about its own origin (axes of its parent
    frame) and shifted by ``shift_mm`` (parent frame)."""
    out = np.array(pose, float)
    out[:3, :3] = Rotation.from_rotvec(np.radians(np.asarray(turn_deg, float))).as_matrix() @ out[:3, :3]
    out[:3, 3] = out[:3, 3] + np.asarray(shift_mm, float)
    return out


@dataclass(frozen=True)
class StationFaults:
    """Changes of the station since its calibration (all zero: none).

    Attributes
    ----------
    camera_shift_mm, camera_turn_deg : tuple of float, shape (3,)
        The camera moved on the flange: its origin by the shift, its axes turned by the rotation
        vector about its origin, both in tool0 coordinates.
    board_shift_mm, board_turn_deg : tuple of float, shape (3,)
        The board moved: its frame (origin at the first inner corner) shifted and turned in base
        coordinates.
    joint_zero_deg : tuple of float, shape (dof,)
        Zero error of each axis: axis ``k`` stands ``joint_zero_deg[k]`` further than its controller
        angle says.
    """

    camera_shift_mm: tuple = (0.0, 0.0, 0.0)
    camera_turn_deg: tuple = (0.0, 0.0, 0.0)
    board_shift_mm: tuple = (0.0, 0.0, 0.0)
    board_turn_deg: tuple = (0.0, 0.0, 0.0)
    joint_zero_deg: tuple = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def any(self) -> bool:
        return bool(np.any([np.any(np.asarray(v, float)) for v in self.__dict__.values()]))

    def mount(self, cam2tool0: np.ndarray) -> np.ndarray:
        """The camera mount after the change, shape (4, 4)."""
        return _turned(cam2tool0, self.camera_shift_mm, self.camera_turn_deg)

    def board(self, board2base: np.ndarray) -> np.ndarray:
        """The board in base after the change, shape (4, 4)."""
        return _turned(board2base, self.board_shift_mm, self.board_turn_deg)

    def axes(self, joints_deg: npt.ArrayLike) -> np.ndarray:
        """Where the axes physically stand for the controller angles ``joints_deg`` (dof,)."""
        joints = np.asarray(joints_deg, float)
        return joints + np.asarray(self.joint_zero_deg, float)[: joints.shape[-1]]

    def to_dict(self) -> dict:
        return {key: [float(v) for v in value] for key, value in self.__dict__.items()}
