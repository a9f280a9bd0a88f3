"""Tsai & Lenz (1989): rotation from modified Rodrigues vectors, then translation by least squares.

R. Y. Tsai and R. K. Lenz, "A new technique for fully autonomous and efficient 3D robotics hand/eye
calibration", IEEE Transactions on Robotics and Automation 5(3):345-358, 1989.

Equation numbers are the paper's, as cross-referenced in OpenCV's ``calibration_handeye.cpp``
(``calibrateHandEyeTsai``). The paper writes ``H_gij H_cg = H_cg H_cij`` with ``H_g`` the gripper and
``H_c`` the camera motion; here ``A_ij`` is the hand motion and ``B_ij`` the board (camera) motion.
"""

from __future__ import annotations

import numpy as np

from .common import prepare_motions, quaternions, skew, solution_transform, translation_least_squares

__all__ = ["solve_tsai"]


def solve_tsai(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """Hand-eye ``X`` by Tsai & Lenz (1989).

    Minimises, in the least-squares sense, the linear residual
    ``[P_A + P_B]_x P' - (P_B - P_A)`` over the pairs, where ``P = 2 sin(θ/2) n`` is each relative
    rotation's modified Rodrigues vector and ``P' = tan(θ_X/2) n_X``; then ``t_X`` from eq. 15.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses ``B_i`` in the camera frame, same length unit as ``hand``.
    pairs : array-like of int, shape (p, 2), optional
        Posture pairs ``(i, j)``; default all pairs ``i < j`` (as OpenCV). Pairs rotating by less
        than 2 deg or more than 175 deg are dropped for the rotation.

    Returns
    -------
    ndarray, shape (4, 4)
        ``X`` (``cam2tool0`` or ``cam2base``), same length unit as the input.

    Raises
    ------
    CalibrationError
        Fewer than 3 postures, bad values, or motion that cannot determine ``X``.

    Notes
    -----
    ``P' = tan(θ_X/2) n_X`` is infinite when ``X`` rotates by 180 deg: the method degrades as
    ``θ_X`` nears 180 deg (no problem for the station's ~90 deg mount; the camodocal set's
    ``θ_X`` of ~167 deg already costs it).
    """
    motions = prepare_motions(hand, target2cam, pairs)
    # eq. 6-7: relative motions (common.relative_transforms); P = 2 sin(θ/2) n = twice the quaternion's vector part.
    p_a = 2.0 * quaternions(motions.rot_a)[:, 1:]
    p_b = 2.0 * quaternions(motions.rot_b)[:, 1:]
    # eq. 12: skew(P_A + P_B) P' = P_B - P_A, stacked over the pairs, least squares.
    lhs = skew(p_a + p_b).reshape(-1, 3)
    rhs = (p_b - p_a).reshape(-1)
    p_prime, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    # eq. 14: P_X = 2 P' / sqrt(1 + |P'|^2)  (= 2 sin(θ_X/2) n_X).
    p_x = 2.0 * p_prime / np.sqrt(1.0 + p_prime @ p_prime)
    # R_X from P_X: R = (1 - |P|^2/2) I + (P P^T + sqrt(4 - |P|^2) [P]_x) / 2 (Rodrigues in P).
    norm2 = p_x @ p_x
    rot_x = (1.0 - norm2 / 2.0) * np.eye(3) + 0.5 * (np.outer(p_x, p_x) + np.sqrt(max(4.0 - norm2, 0.0)) * skew(p_x))
    # eq. 15: (R_A - I) t_X = R_X t_B - t_A, least squares.
    t_x = translation_least_squares(rot_x, motions)
    return solution_transform(rot_x, t_x, motions)
