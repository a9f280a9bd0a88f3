"""What the paper stops short of: outlier postures, a robust refinement and an uncertainty for X.

Refinement (point consistency). With hand poses ``A_i``, board points ``q_ip`` in the camera frame
(the compact points of the paper, section 3.1) and the unknowns ``X`` and the board points ``g_p`` in
the fixed frame, minimise

    sum_ip  rho( | A_i X q_ip - g_p |^2 )                                    (cf. eq. 13, 21-22)

over ``X`` (6 parameters) and ``g`` (3 per point) with a robust loss ``rho`` (scipy's ``soft_l1``,
scaled to the residual spread). This is the error the paper selects by (d_org, d_back) made
continuous, so the answer is no longer limited to one triplet's solution.

Outliers. A posture is an outlier when its fit residual (mean distance of its board points from the
fitted ones; not the posture residual the result reports, ``quality_words``) stands far out of the others' spread (robust z-score from the median and the MAD), or
when it breaks the X-free invariant that ``A_ij`` and ``B_ij`` rotate by the same angle (eq. 30:
``S_A = S_B``): its median angle gap to the other postures stands out in the same way.

Uncertainty. A cluster-robust (sandwich) covariance of the six X parameters at the solution, with
postures as clusters (inliers, robust weights); reported as one-sigma values in mm and degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from .invariants import posture_medians
from .triplets import RelativeMotions

__all__ = [
    "Refinement",
    "refine_point_consistency",
    "posture_residuals_to",
    "compact_point_angle_gaps_deg",
    "robust_outliers",
    "at_most_half",
    "keep_majority",
]

#: Robust z-score above which a posture is an outlier (z = (r - median) / (1.4826 MAD)).
OUTLIER_Z = 5.0
#: ... and its residual must also exceed this multiple of the median residual.
OUTLIER_RATIO = 2.0
#: ... and these absolute floors (below them nothing is an outlier, whatever the spread): point
#: residuals in mm, rotation-angle gaps in degrees.
RESIDUAL_FLOOR_MM = 0.05
ANGLE_GAP_FLOOR_DEG = 0.3


@dataclass(frozen=True)
class Refinement:
    """Result of :func:`refine_point_consistency`.

    Attributes
    ----------
    x : ndarray, shape (4, 4)
    fixed_points : ndarray, shape (p, 3)
        ``g_p``: the board points in the fixed frame.
    residuals_mm : ndarray, shape (n,)
        Per posture: mean distance of its points from ``g``.
    sigma_translation_mm : ndarray, shape (3,)
        One-sigma uncertainty of the translation of X (x, y, z).
    sigma_rotation_deg : ndarray, shape (3,)
        One-sigma uncertainty of the rotation of X about its own x, y, z axes.
    iterations : int
    success : bool
    """

    x: np.ndarray
    fixed_points: np.ndarray
    residuals_mm: np.ndarray
    sigma_translation_mm: np.ndarray
    sigma_rotation_deg: np.ndarray
    iterations: int
    success: bool


def _fixed(hand: np.ndarray, rotation: np.ndarray, translation: np.ndarray, points: np.ndarray) -> np.ndarray:
    cam_in_hand = points @ rotation.T + translation  # (n, p, 3)
    return np.einsum("nij,npj->npi", hand[:, :3, :3], cam_in_hand) + hand[:, None, :3, 3]


def posture_residuals_to(hand: np.ndarray, x: np.ndarray, points_cam: np.ndarray, fixed_points: np.ndarray) -> np.ndarray:
    """Mean distance per posture of ``hand_i X points_i`` from given fixed-frame points; ``(n,)``."""
    pts = _fixed(hand, x[:3, :3], x[:3, 3], points_cam)
    return np.linalg.norm(pts - fixed_points[None], axis=-1).mean(axis=1)


def refine_point_consistency(hand: ArrayLike, points_cam: ArrayLike, x0: np.ndarray, loss: str = "soft_l1", f_scale: float | None = None) -> Refinement:
    """Robust nonlinear least squares of point consistency over X and the fixed board points.

    Parameters
    ----------
    hand : ndarray, shape (n, 4, 4)
        Hand poses (inliers only).
    points_cam : ndarray, shape (n, p, 3)
        Board points in the camera frame (the compact points).
    x0 : ndarray, shape (4, 4)
        Start (the selected triplet solution).
    loss : str
        scipy ``least_squares`` loss (``soft_l1``, ``huber``, ``cauchy``, ``linear``).
    f_scale : float, optional
        Residual scale in mm where the loss turns robust; default: the robust spread at the start.
    """
    hand = np.asarray(hand, float)
    pts = np.asarray(points_cam, float)
    n, p, _ = pts.shape
    r0 = x0[:3, :3]
    g0 = _fixed(hand, r0, x0[:3, 3], pts).mean(axis=0)
    if f_scale is None:
        dev = _fixed(hand, r0, x0[:3, 3], pts) - g0
        f_scale = max(1.4826 * float(np.median(np.abs(dev - np.median(dev, axis=0)))), 1e-6)

    def unpack(theta):
        rotation = Rotation.from_rotvec(theta[:3]).as_matrix() @ r0  # left perturbation of R_X
        return rotation, theta[3:6], theta[6:].reshape(p, 3)

    def residual(theta):
        rotation, translation, g = unpack(theta)
        return (_fixed(hand, rotation, translation, pts) - g).ravel()

    def jacobian(theta):
        rotation, _, _ = unpack(theta)
        v = pts @ rotation.T  # R_X q in the hand frame, (n, p, 3)
        skew = np.zeros((n, p, 3, 3))
        skew[..., 0, 1], skew[..., 0, 2] = -v[..., 2], v[..., 1]
        skew[..., 1, 0], skew[..., 1, 2] = v[..., 2], -v[..., 0]
        skew[..., 2, 0], skew[..., 2, 1] = -v[..., 1], v[..., 0]
        jac = np.zeros((n, p, 3, 6 + 3 * p))
        rot_hand = hand[:, None, :3, :3]
        # d(exp(δ) v)/dδ = -[v]x ; the translation enters through R_i ; g_p with -I
        jac[..., :3] = -np.einsum("nij,npjk->npik", hand[:, :3, :3], skew)
        jac[..., 3:6] = np.broadcast_to(rot_hand, (n, p, 3, 3))
        for k in range(p):
            jac[:, k, :, 6 + 3 * k:9 + 3 * k] = -np.eye(3)
        return jac.reshape(n * p * 3, -1)

    theta0 = np.concatenate([np.zeros(3), x0[:3, 3], g0.ravel()])
    fit = least_squares(residual, theta0, jac=jacobian, loss=loss, f_scale=f_scale, method="trf",  # pyright: ignore[reportArgumentType]  (scipy leaves jac unannotated; its default '2-point' makes pyright infer str)
                        x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
    rotation, translation, g = unpack(fit.x)
    x = np.eye(4)
    x[:3, :3], x[:3, 3] = rotation, translation
    per_posture = np.linalg.norm((_fixed(hand, rotation, translation, pts) - g), axis=-1).mean(axis=1)
    sigma_t, sigma_r = _uncertainty(fit, n, 6 + 3 * p)
    return Refinement(x, g, per_posture, sigma_t, sigma_r, int(fit.nfev), bool(fit.success))


def _uncertainty(fit, n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """One-sigma of X from a cluster-robust (sandwich) covariance at the optimum.

    The residuals of one posture share its robot pose and board fit, so they are not independent:
    the "meat" sums the score ``J_i^T r_i`` posture by posture (clusters), which keeps the estimate
    honest when the residuals within a posture are correlated. The Jacobian and residuals are the
    ones scipy returns, already scaled by the robust loss. Small-sample factor ``n / (n - k)`` for the
``k`` parameters (X and the fixed points) estimated from ``n`` postures.
    """
    jac = fit.jac
    res = fit.fun
    bread = np.linalg.pinv(jac.T @ jac)
    scores = np.einsum("nrk,nr->nk", jac.reshape(n, -1, k), res.reshape(n, -1))
    meat = scores.T @ scores * (n / max(n - k, 1))
    cov = bread @ meat @ bread
    diag = np.sqrt(np.maximum(np.diag(cov)[:6], 0.0))
    return diag[3:6], np.degrees(diag[:3])


def compact_point_angle_gaps_deg(motions: RelativeMotions) -> np.ndarray:
    """Per posture: median over the others of ``|angle(A_ij) - angle(B_ij)|`` in degrees (eq. 30, X-free),
    with ``B_ij`` the rotation of the compact points from posture j to i (``absROT(P_j -> P_i)``, the
    motions of Algorithm 1, step 2) over the pairs of ``motions``.

    The same invariant as :func:`~handeye.calibration.eiv.start.board_pose_angle_gaps_deg`, measured
    on other data: the compact points here, the board poses there.
    """
    gap = np.abs(motions.angle_a_deg - motions.angle_b_deg)
    return posture_medians(gap, motions.pairs, motions.rot_hand.shape[0])


def robust_outliers(values: np.ndarray, floor: float = 0.0, z: float = OUTLIER_Z, ratio: float = OUTLIER_RATIO) -> np.ndarray:
    """Mask of values far above the rest: robust z-score above ``z``, above ``ratio`` x median and
    above ``floor`` (so noise-free or very clean data never produce outliers)."""
    values = np.asarray(values, float)
    median = float(np.median(values))
    mad = 1.4826 * float(np.median(np.abs(values - median)))
    score = (values - median) / max(mad, 1e-12 * max(median, 1e-12))
    return (score > z) & (values > ratio * median) & (values > floor)


def at_most_half(flags: np.ndarray, score: np.ndarray) -> np.ndarray:
    """``flags``, or, when they hold more than half of the postures, the worse half by ``score`` (the
    rule of every outlier loop: never more than half the postures are outliers).

    Parameters
    ----------
    flags : array-like of bool, shape (n,)
    score : array-like, shape (n,)
        Higher is worse (a residual, a Mahalanobis distance).
    """
    flags = np.asarray(flags, bool).copy()
    score = np.asarray(score, float)
    n = flags.size
    if flags.sum() > n // 2:
        flags = score > np.sort(score)[n - n // 2 - 1]
    return flags


def keep_majority(flags: np.ndarray, minimum: int = 3) -> np.ndarray:
    """``flags`` when the postures left keep a majority (at least half, and ``minimum``), else none.

    Parameters
    ----------
    flags : array-like of bool, shape (n,)
        Postures a robust rule would leave out.
    minimum : int
        Fewest postures to keep.

    Returns
    -------
    ndarray of bool, shape (n,)
        ``flags``, or all False: a rule that would drop most postures is judging the data, not outliers.
    """
    flags = np.asarray(flags, dtype=bool).copy()
    n = flags.size
    if n - flags.sum() < max(minimum, (n + 1) // 2):
        flags[:] = False
    return flags
