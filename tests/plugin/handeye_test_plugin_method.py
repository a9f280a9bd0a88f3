"""A third-party calibration method as the tests see one: ``kabsch``, an AX = XB solver of its own
(the rotation axes of the hand and board motions aligned by an SVD, then the translation by least
squares), added through the ``handeye.methods`` entry point of the ``.dist-info`` with no change to
handeye. Its row names the solver by ``"module:function"``, so it is imported only when it runs, and
asks to be in the report's method comparison.
"""

from __future__ import annotations

import numpy as np

from handeye.calibration import Method

METHOD = Method("kabsch", "classic", "Test plug-in (2025)", "rotation axes aligned by SVD, then translation",
                solver=f"{__name__}:solve_kabsch", in_comparison=True)

#: Posture pairs rotating less than this or more than 180 deg minus this carry no usable axis (deg).
MARGIN_DEG = 5.0


def solve_kabsch(hand, target2cam, pairs=None) -> np.ndarray:
    """``X`` with ``hand_i @ X @ target2cam_i`` constant.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` and board poses ``B_i``, same length unit.
    pairs : array-like of int, shape (p, 2), optional
        Posture pairs ``(i, j)``; default all pairs ``i < j``.

    Returns
    -------
    ndarray, shape (4, 4)
    """
    from scipy.spatial.transform import Rotation

    a, b = np.asarray(hand, float), np.asarray(target2cam, float)
    i, j = np.asarray(pairs).T if pairs is not None else np.triu_indices(len(a), k=1)
    a_ij = np.linalg.inv(a[i]) @ a[j]  # A_ij = A_i^-1 A_j
    b_ij = b[i] @ np.linalg.inv(b[j])  # B_ij = B_i B_j^-1; A_ij X = X B_ij
    rot_a, rot_b = Rotation.from_matrix(a_ij[:, :3, :3]).as_rotvec(), Rotation.from_matrix(b_ij[:, :3, :3]).as_rotvec()
    angle = np.degrees(np.linalg.norm(rot_a, axis=1))
    use = (angle > MARGIN_DEG) & (angle < 180.0 - MARGIN_DEG)
    axes_a = rot_a[use] / np.linalg.norm(rot_a[use], axis=1, keepdims=True)
    axes_b = rot_b[use] / np.linalg.norm(rot_b[use], axis=1, keepdims=True)
    u, _, vt = np.linalg.svd(axes_b.T @ axes_a)  # axis_a = R_X axis_b (Kabsch)
    rot_x = vt.T @ np.diag([1.0, 1.0, np.linalg.det(vt.T @ u.T)]) @ u.T
    lhs = (a_ij[:, :3, :3] - np.eye(3)).reshape(-1, 3)  # (R_A - I) t_X = R_X t_B - t_A
    rhs = (np.einsum("ij,pj->pi", rot_x, b_ij[:, :3, 3]) - a_ij[:, :3, 3]).reshape(-1)
    x = np.eye(4)
    x[:3, :3], x[:3, 3] = rot_x, np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    return x
