"""Liang & Mao (2008): rotation from the null space of a Kronecker-product system, then translation.

R.-H. Liang and J.-F. Mao, "Hand-eye calibration with a new linear decomposition algorithm",
Journal of Zhejiang University SCIENCE A 9(10):1363-1368, 2008.

``R_A R_X = R_X R_B`` is linear in ``vec R_X``; with ``vec`` stacking rows (numpy's order)
``vec(R_A R_X) = (R_A ⊗ I_3) vec R_X`` and ``vec(R_X R_B) = (I_3 ⊗ R_B^T) vec R_X``, so each pair
gives ``(R_A ⊗ I_3 - I_3 ⊗ R_B^T) vec R_X = 0``. The stacked 9-column matrix is decomposed by SVD;
the right singular vector of the smallest singular value, reshaped to 3x3, is ``R_X`` up to scale;
it is rescaled to ``det = +1`` and replaced by the closest rotation (the paper's "estimation of the
optimal rotation matrix"); ``t_X`` follows from ``(R_A - I) t_X = R_X t_B - t_A`` in least squares.
The paper's text was not at hand: its equation numbers are not quoted.
"""

from __future__ import annotations

import numpy as np

from .common import prepare_motions, rotation_from_scaled_matrix, solution_transform, translation_least_squares

__all__ = ["solve_liang"]


def solve_liang(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Liang & Mao (2008), Kronecker null space then translation.

    Minimises ``Σ |R_A M - M R_B|_F^2`` over 3x3 matrices ``M`` with ``|M|_F = 1`` (no rotation
    constraint), then projects ``M`` on the rotations.

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
    p = motions.count
    eye = np.eye(3)
    kron_a = np.einsum("pij,kl->pikjl", motions.rot_a, eye).reshape(p, 9, 9)  # R_A ⊗ I_3
    kron_b = np.einsum("ij,plk->pikjl", eye, motions.rot_b).reshape(p, 9, 9)  # I_3 ⊗ R_B^T
    _, _, vt = np.linalg.svd((kron_a - kron_b).reshape(-1, 9), full_matrices=False)
    rot_x = rotation_from_scaled_matrix(vt[-1].reshape(3, 3))
    t_x = translation_least_squares(rot_x, motions)  # (R_A - I) t_X = R_X t_B - t_A
    return solution_transform(rot_x, t_x, motions)
