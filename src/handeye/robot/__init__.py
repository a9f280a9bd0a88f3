"""The robot and its cell: kinematics from the robot files (``robots/*.yaml``), the cell's keep-out
volumes, clearance and self-collision of the moving arm, camera view points.

The names below load on first use (importing the room is cheap)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "base_clearances": "base_clearance",
    "base_envelope": "base_clearance",
    "Box": "cell",
    "CellModel": "cell",
    "Cylinder": "cell",
    "DEFAULT_CARRIED": "cell",
    "Floor": "cell",
    "Sphere": "cell",
    "CellGuard": "clearance",
    "arm_capsules": "clearance",
    "RobotModel": "kinematics",
    "dh_transforms": "kinematics",
    "inverse_kinematics": "kinematics",
    "known_robots": "kinematics",
    "load_robot": "kinematics",
    "NOMINAL_XB3": "views",
    "NOMINAL_XB3_LEFT": "views",
    "PinholeView": "views",
    "ViewSampling": "views",
    "board_visible": "views",
    "corners_in_view": "views",
    "ik_from_standard_seeds": "views",
    "look_at": "views",
    "sample_eye_in_hand_postures": "views",
    "robot_file": "kinematics",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .kinematics import robot_file  # noqa: F401
    from .base_clearance import base_clearances, base_envelope  # noqa: F401
    from .cell import Box, CellModel, Cylinder, DEFAULT_CARRIED, Floor, Sphere  # noqa: F401
    from .clearance import CellGuard, arm_capsules  # noqa: F401
    from .kinematics import RobotModel, dh_transforms, inverse_kinematics, known_robots, load_robot  # noqa: F401
    from .views import NOMINAL_XB3, NOMINAL_XB3_LEFT, PinholeView, ViewSampling, board_visible, corners_in_view, ik_from_standard_seeds, look_at, sample_eye_in_hand_postures  # noqa: F401
