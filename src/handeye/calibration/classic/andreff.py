"""Andreff, Horaud & Espiau (1999): rotation and translation from one linear system (Kronecker products).

N. Andreff, R. Horaud and B. Espiau, "On-line hand-eye calibration", Second International Conference
on 3-D Digital Imaging and Modeling (3DIM'99), pp. 430-436, 1999.

With ``vec`` stacking a matrix row by row (numpy's order), ``vec(R_A R_X R_B^T) = (R_A ⊗ R_B) vec(R_X)``
and ``R_X t_B = (I_3 ⊗ t_B^T) vec(R_X)``, so each pair gives twelve linear equations in the twelve
unknowns ``(vec R_X, t_X)`` (eq. 10 as numbered in OpenCV's ``calibrateHandEyeAndreff``):

    [ I_9 - R_A ⊗ R_B    0_9x3   ] [vec R_X]   [ 0_9 ]
    [ I_3 ⊗ t_B^T       I_3 - R_A] [  t_X  ] = [ t_A ]

solved in least squares; ``R_X`` is then rescaled to ``det = +1`` and orthogonalised (eq. 15 as
numbered in OpenCV). The translation rows carry lengths and the rotation rows do not: the common
module divides every length by the data's RMS relative translation first, so the answer does not
depend on the unit (OpenCV's ANDREFF, fed raw millimetres, lets the translation rows swamp the
rotation rows).
"""

from __future__ import annotations

import numpy as np

from .common import prepare_motions, rotation_from_scaled_matrix, solution_transform

__all__ = ["solve_andreff"]


def solve_andreff(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Andreff, Horaud & Espiau (1999), linear in ``(vec R_X, t_X)``.

    Minimises the algebraic residual of the stacked system above (rotation rows unitless,
    translation rows in the normalised length unit) over an unconstrained 3x3 ``R_X``; the
    rotation is projected on the rotations afterwards and ``t_X`` kept from the joint solve.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j`` (as OpenCV); pairs rotating by < 2 deg or > 175 deg are dropped.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    p = motions.count
    rot_a, rot_b, t_a, t_b = motions.rot_a, motions.rot_b, motions.t_a, motions.t_b
    system = np.zeros((p, 12, 12))
    rhs = np.zeros((p, 12))
    kron_ab = np.einsum("pij,pkl->pikjl", rot_a, rot_b).reshape(p, 9, 9)  # R_A ⊗ R_B
    system[:, :9, :9] = np.eye(9) - kron_ab  # eq. 10, rotation rows
    system[:, 9:, :9] = np.einsum("ij,pk->pijk", np.eye(3), t_b).reshape(p, 3, 9)  # I_3 ⊗ t_B^T
    system[:, 9:, 9:] = np.eye(3) - rot_a  # I_3 - R_A
    rhs[:, 9:] = t_a
    solution, *_ = np.linalg.lstsq(system.reshape(-1, 12), rhs.reshape(-1), rcond=None)
    rot_x = rotation_from_scaled_matrix(solution[:9].reshape(3, 3))  # eq. 15: det = +1, orthogonalise
    return solution_transform(rot_x, solution[9:], motions)
