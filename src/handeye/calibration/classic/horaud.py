"""Horaud & Dornaika (1995): rotation from the rotation axes as a unit quaternion (linear, eigenvector).

R. Horaud and F. Dornaika, "Hand-eye calibration", The International Journal of Robotics Research
14(3):195-210, 1995.

The paper's linear (closed-form) formulation: the axes ``n_A`` of ``R_A`` and ``n_B`` of ``R_B``
satisfy ``n_A = R_X n_B``, i.e. ``n_A * q = q * n_B`` for pure quaternions, so
``(Q(n_A) - W(n_B)) q = 0`` with the left/right product matrices ``Q``, ``W`` of its appendix A;
``q`` minimises ``q^T (Σ A_i^T A_i) q`` over unit quaternions: the eigenvector of the smallest
eigenvalue. The paper's nonlinear simultaneous variant is not implemented here. Equation numbers
are not quoted (the paper's text was not at hand); appendix A is referenced as OpenCV does.
OpenCV's HORAUD builds the same matrix from the full rotation quaternions instead of unit axes
(a weight ``sin^2(θ/2)`` per pair); this module follows the paper's unit axes.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ...geometry import matrix_from_quaternion
from .common import left_matrix, prepare_motions, right_matrix, solution_transform, translation_least_squares

__all__ = ["solve_horaud"]


def _unit_axes(rotation) -> np.ndarray:
    rotvec = Rotation.from_matrix(rotation).as_rotvec()
    return rotvec / np.linalg.norm(rotvec, axis=1, keepdims=True)


def solve_horaud(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Horaud & Dornaika (1995), linear rotation then translation.

    Minimises ``Σ |n_A - R_X n_B|^2`` over rotations (unit axes: every kept pair weighs the same,
    whatever its angle), then ``t_X`` from ``(R_A - I) t_X = R_X t_B - t_A`` in least squares.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j``; pairs rotating by < 2 deg or > 175 deg are dropped for the rotation.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    zeros = np.zeros((motions.count, 1))
    n_a = np.hstack([zeros, _unit_axes(motions.rot_a)])  # pure quaternions of the axes
    n_b = np.hstack([zeros, _unit_axes(motions.rot_b)])
    blocks = left_matrix(n_a) - right_matrix(n_b)  # A_i = Q(n_A) - W(n_B), appendix A
    normal = np.einsum("pki,pkj->ij", blocks, blocks)  # Σ A_i^T A_i
    _, vectors = np.linalg.eigh(normal)
    q = vectors[:, 0]  # eigenvector of the smallest eigenvalue
    rot_x = matrix_from_quaternion(q / np.linalg.norm(q))
    t_x = translation_least_squares(rot_x, motions)  # (R_A - I) t_X = R_X t_B - t_A
    return solution_transform(rot_x, t_x, motions)
