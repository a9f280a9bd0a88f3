"""RAPID data literals (``pose``, ``tooldata``) with the precision a controller keeps.

RAPID ``num`` is a 32-bit float (about 7 significant digits): positions are written to 0.001 mm
and quaternion components to 1e-6, which float32 holds exactly enough for calibration data.
"""

from __future__ import annotations

import math

import numpy as np

from ..calibration.rotations import canonical_quaternions, quaternion_from_matrix

__all__ = ["POSITION_DECIMALS", "QUATERNION_DECIMALS", "format_num", "pose_literal", "rounded_pose"]

POSITION_DECIMALS = 3
QUATERNION_DECIMALS = 6


def format_num(value: float, decimals: int) -> str:
    """A RAPID ``num`` literal: fixed decimals, trailing zeros trimmed, no ``-0``."""
    if not math.isfinite(value):
        raise ValueError(f"RAPID numbers must be finite; got {value}")
    text = f"{value:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def rounded_pose(transform) -> tuple[list, list]:
    """Position (mm) and quaternion ``(q1..q4)`` of a 4x4 transform, rounded as RAPID keeps them."""
    transform = np.asarray(transform, dtype=float)
    q = canonical_quaternions(quaternion_from_matrix(transform[:3, :3]))
    position = [round(float(v), POSITION_DECIMALS) for v in transform[:3, 3]]
    quaternion = [round(float(v), QUATERNION_DECIMALS) for v in q]
    return position, quaternion


def pose_literal(transform) -> str:
    """``[[x,y,z],[q1,q2,q3,q4]]`` of a 4x4 transform (mm), ready for a RAPID ``pose``/``tframe``."""
    position, quaternion = rounded_pose(transform)
    pos = ",".join(format_num(v, POSITION_DECIMALS) for v in position)
    rot = ",".join(format_num(v, QUATERNION_DECIMALS) for v in quaternion)
    return f"[[{pos}],[{rot}]]"
