"""Error measures of the paper (section 2.2, eq. 16-23) and errors against a known truth.

Conventions: lengths in mm; rotation metrics in radians unless the name ends in ``_deg``.
``fixed`` points are the board points carried into the frame the board is fixed in
(``base`` eye-in-hand, ``tool0`` eye-to-hand): ``fixed_i = hand_i @ X @ points_cam_i`` (eq. 13).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..geometry import invert_transforms, rotation_error_deg, translation_error_mm

__all__ = [
    "axxb_residuals",
    "lp_distance",
    "d_geod_matrix",
    "d_hyper",
    "d_frob",
    "d_1",
    "d_2",
    "d_geod_quaternion",
    "fixed_points",
    "mean_point",
    "d_org",
    "d_back",
    "posture_residuals",
    "errors_against_truth",
]


def axxb_residuals(hand: np.ndarray, target2cam: np.ndarray, x: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-pair ``δR = ||R_A R_X - R_X R_B||_F`` and ``δt = |R_A t_X + t_A - R_X t_B - t_X|`` (eq. 16).

    Parameters
    ----------
    hand : ndarray, shape (n, 4, 4)
        Hand poses ``A_i``.
    target2cam : ndarray, shape (n, 4, 4)
        Board poses ``B_i``.
    x : ndarray, shape (4, 4)
    pairs : ndarray, shape (p, 2)

    Returns
    -------
    delta_r : ndarray, shape (p,)
    delta_t_mm : ndarray, shape (p,)
    """
    i, j = pairs[:, 0], pairs[:, 1]
    a = invert_transforms(hand[i]) @ hand[j]
    b = target2cam[i] @ invert_transforms(target2cam[j])
    ax = a @ x
    xb = x @ b
    delta_r = np.linalg.norm(ax[:, :3, :3] - xb[:, :3, :3], axis=(1, 2))
    delta_t = np.linalg.norm(ax[:, :3, 3] - xb[:, :3, 3], axis=1)
    return delta_r, delta_t


def lp_distance(t_r: ArrayLike, t_s: ArrayLike, p: float = 2.0) -> np.ndarray:
    """``L_p`` distance between positions (eq. 17); ``p = inf`` gives the largest coordinate gap."""
    diff = np.abs(np.asarray(t_r, float) - np.asarray(t_s, float))
    if np.isinf(p):
        return diff.max(axis=-1)
    return np.sum(diff**p, axis=-1) ** (1.0 / p)


def d_geod_matrix(r_r: np.ndarray, r_s: np.ndarray) -> np.ndarray:
    """``||log(R_r^-1 R_s)||`` (eq. 18): the rotation angle between two rotations, radians."""
    return np.radians(rotation_error_deg(r_r, r_s))


def d_hyper(r_r: ArrayLike, r_s: ArrayLike) -> np.ndarray:
    """``||log(R_r) - log(R_s)||`` (eq. 18) with ``log`` as the rotation vector, radians."""
    a = Rotation.from_matrix(np.asarray(r_r, float)).as_rotvec()
    b = Rotation.from_matrix(np.asarray(r_s, float)).as_rotvec()
    return np.linalg.norm(a - b, axis=-1)


def d_frob(r_r: ArrayLike, r_s: ArrayLike) -> np.ndarray:
    """``||R_r - R_s||_F`` (eq. 18)."""
    return np.linalg.norm(np.asarray(r_r, float) - np.asarray(r_s, float), axis=(-2, -1))


def d_1(q_r: ArrayLike, q_s: ArrayLike) -> np.ndarray:
    """``1 - |q_r . q_s|`` (eq. 19), in [0, 1]."""
    return 1.0 - np.abs(np.sum(np.asarray(q_r, float) * np.asarray(q_s, float), axis=-1))


def d_2(q_r: ArrayLike, q_s: ArrayLike) -> np.ndarray:
    """``min(|q_r - q_s|, |q_r + q_s|)`` (eq. 19), in [0, sqrt(2)]."""
    q_r = np.asarray(q_r, float)
    q_s = np.asarray(q_s, float)
    return np.minimum(np.linalg.norm(q_r - q_s, axis=-1), np.linalg.norm(q_r + q_s, axis=-1))


def d_geod_quaternion(q_r: ArrayLike, q_s: ArrayLike) -> np.ndarray:
    """``2 acos(|q_r . q_s|)`` (eq. 19), in [0, pi]: equals :func:`d_geod_matrix`."""
    dot = np.abs(np.sum(np.asarray(q_r, float) * np.asarray(q_s, float), axis=-1))
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


def fixed_points(hand: np.ndarray, x: np.ndarray, points_cam: np.ndarray) -> np.ndarray:
    """Board points in the fixed frame, ``hand_i @ X @ points_i`` (eq. 13).

    Parameters
    ----------
    hand : ndarray, shape (n, 4, 4)
    x : ndarray, shape (4, 4)
    points_cam : ndarray, shape (n, m, 3)

    Returns
    -------
    ndarray, shape (n, m, 3)
    """
    chain = hand @ x
    return np.einsum("nij,nmj->nmi", chain[:, :3, :3], points_cam) + chain[:, None, :3, 3]


def mean_point(fixed: ArrayLike) -> np.ndarray:
    """Mean position of each point over the postures (eq. 21): ``(n, m, 3) -> (m, 3)``."""
    return np.asarray(fixed, float).mean(axis=0)


def d_org(fixed: ArrayLike) -> float:
    """Mean distance of the points from their mean point (eq. 22), averaged over the points, mm."""
    fixed = np.asarray(fixed, float)
    return float(np.linalg.norm(fixed - fixed.mean(axis=0), axis=-1).mean())


def d_back(fixed: ArrayLike, pairs: ArrayLike | None = None) -> float:
    """Mean distance between the same point seen from two postures (eq. 23), averaged over points, mm.

    Parameters
    ----------
    fixed : array-like, shape (n, m, 3)
    pairs : array-like of int, shape (p, 2), optional
        The posture pairs to average over (e.g. ``invariants.bounded_pairs`` of a large session);
        default every pair ``i < j``, as eq. 23. Taken a block at a time, so memory stays bounded.
    """
    fixed = np.asarray(fixed, float)
    if pairs is None:
        i, j = np.triu_indices(fixed.shape[0], k=1)
        return float(np.linalg.norm(fixed[i] - fixed[j], axis=-1).mean())
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    block = max(1, 2_000_000 // max(fixed.shape[1], 1))
    total = sum(float(np.linalg.norm(fixed[p[:, 0]] - fixed[p[:, 1]], axis=-1).sum())
                for p in (pairs[k:k + block] for k in range(0, len(pairs), block)))
    return total / (len(pairs) * fixed.shape[1])


def posture_residuals(fixed: ArrayLike, kept: ArrayLike | None = None) -> np.ndarray:
    """Per posture: mean distance of its points from the mean points (eq. 21-22 per posture), mm.

    Parameters
    ----------
    fixed : array-like, shape (n, m, 3)
        Board points in the fixed frame (:func:`fixed_points`).
    kept : array-like of bool, shape (n,), optional
        The postures whose mean points are the reference (all by default, or when none is kept); every
        posture's distance from it is returned.

    Returns
    -------
    ndarray, shape (n,)
    """
    fixed = np.asarray(fixed, float)
    kept = None if kept is None or not np.any(kept) else np.asarray(kept, bool)
    reference = fixed.mean(axis=0) if kept is None else fixed[kept].mean(axis=0)  # eq. 21
    return np.linalg.norm(fixed - reference, axis=-1).mean(axis=1)


def errors_against_truth(x: np.ndarray, x_true: np.ndarray) -> dict:
    """Rotation (deg) and translation (mm) errors of ``X`` against a known truth."""
    return {
        "rotation_error_deg": float(rotation_error_deg(x, x_true)),
        "translation_error_mm": float(translation_error_mm(x, x_true)),
    }
