"""Lu & Chou (1995): rotation and translation at once in an eight-dimensional quaternion space.

Y.-C. Lu and J. C. K. Chou, "Eight-space quaternion approach for robotic hand-eye calibration",
IEEE International Conference on Systems, Man and Cybernetics (Intelligent Systems for the 21st
Century), vol. 4, pp. 3316-3321, 1995.

Unknowns: the rotation quaternion ``q`` of ``X`` and ``w = t_X * q`` (``t_X`` a pure quaternion), an
eight-vector. From ``q_A * q = q * q_B`` and ``R_A t_X + t_A = R_X t_B + t_X`` written in quaternions
(and ``q_A * q = q * q_B`` used once more to clear ``q̄``) each pair gives eight linear homogeneous
equations, all four rows of each quaternion equation kept:

    [ L(q_A) - R(q_B)              0              ] [ q ]
    [ L(t_A q_A) - R(t_B q_B)   L(q_A) - R(q_B)   ] [ w ] = 0

with ``L(p) x = p * x`` and ``R(p) x = x * p``. The stacked matrix has, for exact data, the
two-dimensional null space ``{(q, w), (0, q)}``; the solution is the combination of the two least
right singular vectors with ``|q| = 1`` and ``q . w = 0`` (which every ``w = t * q`` satisfies), and
``t_X = w * q̄``. The paper's text was not at hand: its equation numbers are not quoted, and this
module states the eight-space equations as derived above. This is the dual-quaternion system of
Daniilidis (``w = 2 q'``) with the scalar rows kept and the dual rows weighted twice as much.
Lengths are normalised by the common module, so the answer does not depend on the unit.
"""

from __future__ import annotations

import numpy as np

from ...geometry import matrix_from_quaternion, quaternion_conjugate, quaternion_multiply
from .common import constrained_null_combination, left_matrix, prepare_motions, quaternions, right_matrix, solution_transform

__all__ = ["solve_lu"]


def _pure(vectors) -> np.ndarray:
    return np.concatenate([np.zeros(vectors.shape[:-1] + (1,)), vectors], axis=-1)


def solve_lu(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Lu & Chou (1995), simultaneous, eight-space quaternions.

    Minimises the algebraic residual of the stacked 8x8 blocks above over unit ``q`` with
    ``q . w = 0`` within the two-dimensional least-singular subspace (translations in the
    normalised length unit).

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j``; pairs rotating by < 2 deg or > 175 deg are dropped.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    q_a = quaternions(motions.rot_a)
    q_b = quaternions(motions.rot_b)
    rotation_rows = left_matrix(q_a) - right_matrix(q_b)  # q_A * q - q * q_B
    coupling = left_matrix(quaternion_multiply(_pure(motions.t_a), q_a)) - right_matrix(
        quaternion_multiply(_pure(motions.t_b), q_b)
    )  # (t_A q_A) * q - q * (t_B q_B)
    p = motions.count
    system = np.zeros((p, 8, 8))
    system[:, :4, :4] = rotation_rows
    system[:, 4:, :4] = coupling
    system[:, 4:, 4:] = rotation_rows
    _, _, vt = np.linalg.svd(system.reshape(-1, 8), full_matrices=False)
    x = constrained_null_combination(vt[-2], vt[-1])  # |q| = 1, q . w = 0
    q, w = x[:4], x[4:]
    rot_x = matrix_from_quaternion(q)
    t_x = quaternion_multiply(w, quaternion_conjugate(q))[1:]  # t_X = w * q̄
    return solution_transform(rot_x, t_x, motions)
