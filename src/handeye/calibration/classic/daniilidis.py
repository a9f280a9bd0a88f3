"""Daniilidis (1999): rotation and translation at once from unit dual quaternions (SVD).

K. Daniilidis, "Hand-eye calibration using dual quaternions", The International Journal of Robotics
Research 18(3):286-298, 1999.

A motion ``(R, t)`` is the unit dual quaternion ``q + ε q'`` with ``q' = (1/2) t q`` (``t`` a pure
quaternion). ``A X = X B`` becomes ``ǎ x̌ = x̌ b̌``; with the scalar parts equal (the screw congruence
theorem) the vector parts ``a, a', b, b'`` give six linear equations per pair in the eight unknowns
``(q, q')`` of ``X`` (eq. 31 as numbered in OpenCV's ``calibrateHandEyeDaniilidis``):

    [ a - b     [a + b]_x    0_3       0_3x3    ] [ q  ]
    [ a' - b'   [a' + b']_x  a - b     [a + b]_x] [ q' ] = 0

The stacked matrix ``T`` has (for exact data) a two-dimensional null space spanned by the right
singular vectors ``v7, v8`` of its two smallest singular values; ``x̌ = λ1 v7 + λ2 v8`` with
``|q| = 1`` and ``q . q' = 0`` (eq. 34-35 as numbered in OpenCV) fixes ``λ1, λ2``.
Lengths enter the dual parts only: the common module normalises them so the answer does not depend
on the unit (OpenCV's DANIILIDIS does, on raw millimetres).
"""

from __future__ import annotations

import numpy as np

from ...geometry import matrix_from_quaternion, quaternion_conjugate, quaternion_multiply
from .common import constrained_null_combination, prepare_motions, quaternions, skew, solution_transform

__all__ = ["solve_daniilidis"]


def _dual_quaternions(rotation, translation) -> tuple[np.ndarray, np.ndarray]:
    """``(q, q')`` of motions, ``q`` with ``w >= 0`` and ``q' = t q / 2``."""
    q = quaternions(rotation)
    t = np.concatenate([np.zeros(translation.shape[:-1] + (1,)), translation], axis=-1)
    return q, 0.5 * quaternion_multiply(t, q)


def solve_daniilidis(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Daniilidis (1999), simultaneous rotation and translation.

    Minimises ``|T x̌|`` over the 8-vectors ``x̌`` of the two-dimensional least-singular subspace,
    subject to ``x̌`` being a unit dual quaternion (algebraic error, translations in the normalised
    length unit).

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j`` (as OpenCV); pairs rotating by < 2 deg or > 175 deg are dropped
        (near 180 deg the quaternion signs of ``A_ij`` and ``B_ij`` cannot be matched).

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    qa, qa_dual = _dual_quaternions(motions.rot_a, motions.t_a)
    qb, qb_dual = _dual_quaternions(motions.rot_b, motions.t_b)
    a, a_dual, b, b_dual = qa[:, 1:], qa_dual[:, 1:], qb[:, 1:], qb_dual[:, 1:]
    p = motions.count
    s = np.zeros((p, 6, 8))  # eq. 31, one 6x8 block per pair
    s[:, :3, 0] = a - b
    s[:, :3, 1:4] = skew(a + b)
    s[:, 3:, 0] = a_dual - b_dual
    s[:, 3:, 1:4] = skew(a_dual + b_dual)
    s[:, 3:, 4] = a - b
    s[:, 3:, 5:8] = skew(a + b)
    _, _, vt = np.linalg.svd(s.reshape(-1, 8), full_matrices=False)
    x = constrained_null_combination(vt[-2], vt[-1])  # eq. 34-35: |q| = 1, q . q' = 0
    q, q_dual = x[:4], x[4:]
    rot_x = matrix_from_quaternion(q)
    t_x = 2.0 * quaternion_multiply(q_dual, quaternion_conjugate(q))[1:]  # t = 2 q' q̄
    return solution_transform(rot_x, t_x, motions)
