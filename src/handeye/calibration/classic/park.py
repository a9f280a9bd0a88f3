"""Park & Martin (1994): rotation from the Lie algebra (rotation vectors), closed form; then translation.

F. C. Park and B. J. Martin, "Robot sensor calibration: solving AX = XB on the Euclidean group",
IEEE Transactions on Robotics and Automation 10(5):717-721, 1994.

The paper's symbols are kept: ``α_i = log R_A``, ``β_i = log R_B`` (rotation vectors), so that
``α_i = R_X β_i``; ``M = Σ β_i α_i^T`` and ``R_X = (M^T M)^(-1/2) M^T`` (its closed-form least-squares
solution). The paper's text was not at hand when this was written, so its equation numbers are not
quoted; the formulas are the ones the paper states.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .common import nearest_rotation, prepare_motions, solution_transform, translation_least_squares

__all__ = ["solve_park"]


def solve_park(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Park & Martin (1994).

    Minimises ``Σ |R_X β_i - α_i|^2`` over rotations (an orthogonal Procrustes problem on the
    rotation vectors, so pairs with larger rotations weigh more), then ``t_X`` from
    ``(R_A - I) t_X = R_X t_B - t_A`` in least squares.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i``, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Default all pairs ``i < j`` (as OpenCV); pairs rotating by < 2 deg or > 175 deg are dropped
        for the rotation.

    Returns
    -------
    ndarray, shape (4, 4)
        ``X``, same length unit as the input.

    Raises
    ------
    CalibrationError
    """
    motions = prepare_motions(hand, target2cam, pairs)
    alpha = Rotation.from_matrix(motions.rot_a).as_rotvec()  # α_i = log R_A
    beta = Rotation.from_matrix(motions.rot_b).as_rotvec()  # β_i = log R_B
    m = beta.T @ alpha  # M = Σ β_i α_i^T
    # R_X = (M^T M)^(-1/2) M^T: the polar factor U V^T of M^T = U S V^T (identical when M is regular),
    # taken with det = +1 so noise can never turn it into a reflection.
    rot_x = nearest_rotation(m.T)
    t_x = translation_least_squares(rot_x, motions)  # (R_A - I) t_X = R_X t_B - t_A
    return solution_transform(rot_x, t_x, motions)
