"""Chou & Kamel (1991): rotation as a quaternion from a homogeneous linear system (SVD), then translation.

J. C. K. Chou and M. Kamel, "Finding the position and orientation of a sensor on a robot manipulator
using quaternions", The International Journal of Robotics Research 10(3):240-254, 1991.

``R_A R_X = R_X R_B`` in unit quaternions is ``q_A * q_X - q_X * q_B = 0``: four linear homogeneous
equations per pair in ``q_X``,

    [ s_A - s_B     -(v_A - v_B)^T                 ]
    [ v_A - v_B     [v_A + v_B]_x + (s_A - s_B) I_3 ] q_X = 0

(``s``, ``v``: scalar and vector parts), as restated by Deniz & Cakir (2018), eq. 5-7, the paper this
project implements. Stacked over the pairs, ``q_X`` is the right singular vector of the smallest
singular value. The translation follows from ``(R_A - I) t_X = R_X t_B - t_A`` (Deniz & Cakir eq. 8)
in least squares. Chou & Kamel's own equation numbers are not quoted (the paper's text was not at hand).
"""

from __future__ import annotations

import numpy as np

from ...geometry import matrix_from_quaternion
from .common import left_matrix, prepare_motions, quaternions, right_matrix, solution_transform, translation_least_squares

__all__ = ["solve_chou"]


def solve_chou(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Chou & Kamel (1991), quaternion SVD then translation.

    Minimises ``Σ |q_A * q - q * q_B|^2`` over unit quaternions ``q``: per pair this is
    ``4 sin^2(θ/2) |n_A - R_X n_B|^2``-like, so pairs with larger rotations weigh more (unlike
    Horaud's unit axes).

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j``; pairs rotating by < 2 deg or > 175 deg are dropped (near 180 deg
        the signs of ``q_A`` and ``q_B`` cannot be matched).

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    q_a = quaternions(motions.rot_a)  # w >= 0 on both sides: the scalar parts agree (eq. 6)
    q_b = quaternions(motions.rot_b)
    blocks = left_matrix(q_a) - right_matrix(q_b)  # eq. 5-7: (q_A *) - (* q_B), 4x4 per pair
    _, _, vt = np.linalg.svd(blocks.reshape(-1, 4), full_matrices=False)
    q = vt[-1]  # right singular vector of the smallest singular value
    rot_x = matrix_from_quaternion(q / np.linalg.norm(q))
    t_x = translation_least_squares(rot_x, motions)  # eq. 8
    return solution_transform(rot_x, t_x, motions)
