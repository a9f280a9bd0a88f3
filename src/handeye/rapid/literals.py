"""RAPID data literals (``pose``, ``tooldata``) with the precision a controller keeps.

RAPID ``num`` is a 32-bit float (about 7 significant digits): positions are written to 0.001 mm
and quaternion components to 1e-6, which float32 holds exactly enough for calibration data.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import canonical_quaternions, quaternion_from_matrix

__all__ = [
    "POSITION_DECIMALS",
    "QUATERNION_DECIMALS",
    "ANGLE_DECIMALS",
    "MASS_DECIMALS",
    "format_num",
    "pose_literal",
    "rounded_pose",
    "tooldata_literal",
    "jointtarget_literal",
    "speeddata_literal",
]

POSITION_DECIMALS = 3
QUATERNION_DECIMALS = 6
ANGLE_DECIMALS = 4
MASS_DECIMALS = 3


def format_num(value: float, decimals: int) -> str:
    """A RAPID ``num`` literal: fixed decimals, trailing zeros trimmed, no ``-0``."""
    if not math.isfinite(value):
        raise ValueError(f"RAPID numbers must be finite; got {value}")
    text = f"{value:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def rounded_pose(transform: ArrayLike) -> tuple[list, list]:
    """Position (mm) and quaternion ``(q1..q4)`` of a 4x4 transform, rounded as RAPID keeps them."""
    transform = np.asarray(transform, dtype=float)
    q = canonical_quaternions(quaternion_from_matrix(transform[:3, :3]))
    position = [round(float(v), POSITION_DECIMALS) for v in transform[:3, 3]]
    quaternion = [round(float(v), QUATERNION_DECIMALS) for v in q]
    return position, quaternion


def pose_literal(transform: ArrayLike) -> str:
    """``[[x,y,z],[q1,q2,q3,q4]]`` of a 4x4 transform (mm), ready for a RAPID ``pose``/``tframe``."""
    position, quaternion = rounded_pose(transform)
    pos = ",".join(format_num(v, POSITION_DECIMALS) for v in position)
    rot = ",".join(format_num(v, QUATERNION_DECIMALS) for v in quaternion)
    return f"[[{pos}],[{rot}]]"


def _nums(values, decimals: int) -> str:
    return ",".join(format_num(float(v), decimals) for v in values)


def tooldata_literal(transform: ArrayLike, mass_kg: float, cog_mm: Sequence[float] = (0.0, 0.0, 0.0), robhold: bool = True) -> str:
    """A RAPID ``tooldata`` literal for a tool whose frame in tool0 is ``transform``.

    ``[robhold,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[1,0,0,0],0,0,0]]``: tframe from the 4x4
    ``transform`` (mm; quaternion with q1 >= 0), load with the axes of moment along tool0 and zero
    inertia (RAPID's usual values for a light tool).

    Parameters
    ----------
    transform : array-like, shape (4, 4)
        ``cam2tool0`` (mm).
    mass_kg : float
        Tool mass; RAPID refuses 0.
    cog_mm : array-like, shape (3,)
        Centre of gravity in tool0 (mm).
    robhold : bool
        TRUE for a tool on the flange (the camera), FALSE for a stationary tool.

    Raises
    ------
    ValueError
        Mass not > 0, or a value that is not finite.
    """
    mass = float(mass_kg)
    if not math.isfinite(mass) or mass <= 0:
        raise ValueError(f"tool mass must be > 0 kg (RAPID refuses 0); got {mass_kg}")
    cog = np.asarray(cog_mm, dtype=float)
    if cog.shape != (3,):
        raise ValueError(f"centre of gravity needs 3 values; got shape {cog.shape}")
    hold = "TRUE" if robhold else "FALSE"
    return (f"[{hold},{pose_literal(transform)},"
            f"[{format_num(mass, MASS_DECIMALS)},[{_nums(cog, POSITION_DECIMALS)}],[1,0,0,0],0,0,0]]")


#: Axes of RAPID's ``robjoint`` (``rax_1`` .. ``rax_6``): fixed by the data type, not taken from the
#: robot model; the generated program is for robots of six axes (the line protocol's JOINTS reply and
#: the Modbus map's ``joints`` registers hold six values too).
ROBJOINT_AXES = 6


def jointtarget_literal(joints_deg: ArrayLike) -> str:
    """``[[j1,...,j6],[9E9,9E9,9E9,9E9,9E9,9E9]]`` (degrees, 0.0001 deg; external axes unused)."""
    joints = np.asarray(joints_deg, dtype=float)
    if joints.shape != (ROBJOINT_AXES,):
        raise ValueError(f"a jointtarget needs {ROBJOINT_AXES} robot axes (RAPID robjoint); got shape {joints.shape}")
    return f"[[{_nums(joints, ANGLE_DECIMALS)}],[9E9,9E9,9E9,9E9,9E9,9E9]]"


def speeddata_literal(tcp_mm_s: float, ori_deg_s: float, leax_mm_s: float = 5000.0, reax_deg_s: float = 1000.0) -> str:
    """``[v_tcp,v_ori,v_leax,v_reax]`` (mm/s, deg/s; external-axis speeds as ABB's predefined data)."""
    return f"[{_nums((tcp_mm_s, ori_deg_s, leax_mm_s, reax_deg_s), 3)}]"
