"""Rotations, rigid transforms and the board's description (checkerboard, ChArUco, circle grid: the target registry) (numpy and scipy).

The names below load on first use (importing the room is cheap)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "BoardGeometry": "board",
    "STATION_BOARD": "board",
    "board_corners": "board",
    "SQUARE_TOLERANCE": "board_scale",
    "judge_square_size": "board_scale",
    "canonical_quaternions": "rotations",
    "matrix_from_quaternion": "rotations",
    "quaternion_conjugate": "rotations",
    "quaternion_from_axis_angle": "rotations",
    "quaternion_from_matrix": "rotations",
    "quaternion_multiply": "rotations",
    "rotate_vectors": "rotations",
    "skew": "rotations",
    "CharucoBoard": "targets",
    "CircleGrid": "targets",
    "TargetKind": "targets",
    "TARGETS": "targets",
    "register_target": "targets",
    "target_kind": "targets",
    "target_to_dict": "targets",
    "target_from_dict": "targets",
    "parse_target_spec": "targets",
    "STATION_CHARUCO": "targets",
    "STATION_CIRCLES": "targets",
    "partial_ok": "targets",
    "describe": "targets",
    "MIN_CORNERS": "targets",
    "MIN_SPAN_FRACTION": "targets",
    "view_refusal": "targets",
    "STATION_CORNERS": "station_board",
    "STATION_SQUARE_MM": "station_board",
    "invert_transforms": "transforms",
    "pose_from_transform": "transforms",
    "rigid_defect": "transforms",
    "rotation_error_deg": "transforms",
    "transform_from_pose": "transforms",
    "transform_from_rotation_translation": "transforms",
    "translation_error_mm": "transforms",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .board import BoardGeometry, STATION_BOARD, board_corners  # noqa: F401
    from .board_scale import SQUARE_TOLERANCE, judge_square_size  # noqa: F401
    from .rotations import canonical_quaternions, matrix_from_quaternion, quaternion_conjugate, quaternion_from_axis_angle, quaternion_from_matrix, quaternion_multiply, rotate_vectors, skew  # noqa: F401
    from .station_board import STATION_CORNERS, STATION_SQUARE_MM  # noqa: F401
    from .targets import CharucoBoard, CircleGrid, TargetKind, TARGETS, register_target, target_kind, target_to_dict, target_from_dict, parse_target_spec, STATION_CHARUCO, STATION_CIRCLES, partial_ok, describe, MIN_CORNERS, MIN_SPAN_FRACTION, view_refusal  # noqa: F401
    from .transforms import invert_transforms, pose_from_transform, rigid_defect, rotation_error_deg, transform_from_pose, transform_from_rotation_translation, translation_error_mm  # noqa: F401
