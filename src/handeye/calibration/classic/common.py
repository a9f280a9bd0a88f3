"""What every classic ``AX = XB`` solver shares: input checks, relative motions, pair selection,
degenerate-pair filtering, unit normalisation and the common translation least squares.

Conventions (the same for every solver in this package)
-------------------------------------------------------
``hand`` holds the hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand) and
``target2cam`` the board poses ``B_i``; the unknown ``X`` (``cam2tool0`` or ``cam2base``) satisfies
``hand_i @ X @ target2cam_i = constant``. For a posture pair ``(i, j)`` the relative motions

    A_ij = A_i^-1 A_j,        B_ij = B_i B_j^-1,        A_ij X = X B_ij        (AX = XB)

split into ``R_A R_X = R_X R_B`` and ``(R_A - I) t_X = R_X t_B - t_A`` (Deniz & Cakir eq. 2 and 8).

Length unit
-----------
Solvers that mix rotation and translation in one linear system (Andreff, Daniilidis, Lu-Chou) give
different answers in mm and in m when fed raw numbers (OpenCV's ANDREFF and DANIILIDIS do). Here
every translation is divided by one length, the RMS length of the relative translations, before any
solver sees it, and the answer is scaled back: mm in, mm out; m in, m out; the same pose either way.

Degenerate pairs
----------------
A pair whose relative rotation is nearly zero has a rotation axis made of noise; one whose rotation is
nearly 180 deg has an axis whose sign (and the sign of its quaternion's vector part) flips with a
fraction of a degree of noise, which breaks every solver that compares the axes of ``A_ij`` and
``B_ij``. Such pairs are dropped (for the rotation; the translation keeps the near-180 ones, which are
its best-conditioned rows). If what is left cannot determine ``X`` (fewer than two usable pairs, all
axes parallel: rotation-axis divergence of ``calibration.quality_words`` below
``MIN_AXIS_DIVERGENCE_DEG``) a :class:`~handeye.base.errors.CalibrationError` says so in one line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ...base import CalibrationError
from ..problem import MIN_POSTURES
from ..invariants import relative_transforms
from ..quality_words import MIN_AXIS_DIVERGENCE_DEG, rotation_axis_divergence_deg
from ...geometry import quaternion_from_matrix, skew
from ...geometry import transform_from_rotation_translation

__all__ = [
    "MIN_POSTURES",
    "MIN_PAIR_ANGLE_DEG",
    "MAX_PAIR_ANGLE_DEG",
    "MIN_AXIS_DIVERGENCE_DEG",
    "MAX_DEFAULT_PAIRS",
    "Motions",
    "check_poses",
    "all_pairs",
    "default_pairs",
    "consecutive_pairs",
    "check_pairs",
    "relative_transforms",
    "rotation_angles_deg",
    "prepare_motions",
    "translation_least_squares",
    "solution_transform",
    "nearest_rotation",
    "rotation_from_scaled_matrix",
    "quaternions",
    "skew",
    "left_matrix",
    "right_matrix",
    "constrained_null_combination",
]

#: Pairs rotating less than this (deg) carry an axis made of noise: dropped for the rotation.
MIN_PAIR_ANGLE_DEG = 2.0
#: Pairs rotating more than this (deg) have a sign-ambiguous axis: dropped for the rotation.
MAX_PAIR_ANGLE_DEG = 175.0
#: Above this many pairs the default keeps an evenly spread subset of all pairs (memory stays ~100 MB).
MAX_DEFAULT_PAIRS = 20000
#: Largest accepted ``max |R^T R - I|`` of an input rotation before it is refused.
ORTHONORMAL_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Motions:
    """Relative motions ready for a solver, translations in normalised units.

    Attributes
    ----------
    pairs : ndarray of int, shape (p, 2)
        Pairs used for the rotation (degenerate pairs removed).
    rot_a, rot_b : ndarray, shape (p, 3, 3)
        ``R_A``, ``R_B`` of those pairs.
    t_a, t_b : ndarray, shape (p, 3)
        ``t_A / scale``, ``t_B / scale``.
    translation_pairs : ndarray of int, shape (k, 2)
        Pairs used by :func:`translation_least_squares` (all requested pairs rotating by at least
        ``MIN_PAIR_ANGLE_DEG``, near-180 ones included).
    rot_a_translation, t_a_translation, t_b_translation : ndarray
        ``R_A``, ``t_A / scale``, ``t_B / scale`` of ``translation_pairs``.
    scale : float
        The length unit of the normalised translations, in the caller's unit.
    dropped : ndarray of int, shape (d, 2)
        Requested pairs left out of the rotation (near-zero or near-180 deg).
    """

    pairs: np.ndarray
    rot_a: np.ndarray
    rot_b: np.ndarray
    t_a: np.ndarray
    t_b: np.ndarray
    translation_pairs: np.ndarray
    rot_a_translation: np.ndarray
    t_a_translation: np.ndarray
    t_b_translation: np.ndarray
    scale: float
    dropped: np.ndarray

    @property
    def count(self) -> int:
        return len(self.pairs)


def check_poses(hand: np.ndarray, target2cam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate the two pose stacks; return them as float64 with exactly orthonormal rotations.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)

    Returns
    -------
    hand, target2cam : ndarray, shape (n, 4, 4)

    Raises
    ------
    CalibrationError
        Wrong shapes, different counts, fewer than 3 postures, NaN/inf, a rotation block that is
        not a rotation.
    """
    out = []
    for name, poses in (("hand", hand), ("target2cam", target2cam)):
        poses = np.asarray(poses, dtype=float)
        if poses.ndim != 3 or poses.shape[1:] != (4, 4):
            raise CalibrationError(f"{name} poses must be an (n, 4, 4) stack of transforms; got shape {poses.shape}")
        if not np.all(np.isfinite(poses)):
            bad = int(np.nonzero(~np.all(np.isfinite(poses), axis=(1, 2)))[0][0])
            raise CalibrationError(f"{name} pose {bad} holds NaN or inf; remove or re-measure that posture")
        rot = poses[:, :3, :3]
        deviation = np.abs(np.swapaxes(rot, 1, 2) @ rot - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(rot)
        bad = np.nonzero((deviation > ORTHONORMAL_TOLERANCE) | (det < 0))[0]
        if len(bad):
            raise CalibrationError(
                f"{name} pose {int(bad[0])} has a rotation block that is not a rotation "
                f"(|R^T R - I| = {deviation[bad[0]]:.2g}, det = {det[bad[0]]:.3g}); check the pose's units and layout"
            )
        out.append(transform_from_rotation_translation(nearest_rotation(rot), poses[:, :3, 3]))
    hand, target2cam = out
    if len(hand) != len(target2cam):
        raise CalibrationError(f"{len(hand)} hand poses but {len(target2cam)} board poses; give one of each per posture")
    if len(hand) < MIN_POSTURES:
        raise CalibrationError(f"at least {MIN_POSTURES} postures are needed; got {len(hand)}")
    return hand, target2cam


def all_pairs(n: int) -> np.ndarray:
    """All posture pairs ``i < j``, shape ``(n(n-1)/2, 2)``, lexicographic order."""
    i, j = np.triu_indices(n, k=1)
    return np.stack([i, j], axis=1)


def default_pairs(n: int) -> np.ndarray:
    """The pairs every solver here uses when none are given.

    All pairs ``i < j``; when there are more than ``MAX_DEFAULT_PAIRS`` of them (continuous streams
    of thousands of samples), the pairs ``(i, i + s)`` for a few strides ``s`` spread evenly over
    ``1 .. n/2``, so that every posture takes part and at most ``MAX_DEFAULT_PAIRS`` remain.
    """
    if n * (n - 1) // 2 <= MAX_DEFAULT_PAIRS:
        return all_pairs(n)
    count = max(1, MAX_DEFAULT_PAIRS // n)
    strides = np.unique(np.round(np.linspace(1, n // 2, count)).astype(np.intp))
    return np.concatenate([np.stack([np.arange(n - s), np.arange(s, n)], axis=1) for s in strides])


def consecutive_pairs(n: int) -> np.ndarray:
    """Consecutive pairs ``(i, i+1)``, shape ``(n-1, 2)`` (what several papers write their sums over)."""
    i = np.arange(n - 1)
    return np.stack([i, i + 1], axis=1)


def check_pairs(pairs: ArrayLike | None, n: int) -> np.ndarray:
    """Validate user-given pairs; ``None`` gives :func:`default_pairs`.

    Raises
    ------
    CalibrationError
        Not an integer ``(p, 2)`` array, an index outside ``0..n-1``, or a pair ``(i, i)``.
    """
    if pairs is None:
        return default_pairs(n)
    arr = np.asarray(pairs)
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) == 0:
        raise CalibrationError(f"pairs must be a non-empty (p, 2) array of posture indices; got shape {arr.shape}")
    integral = arr.dtype.kind in "iu" or (arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)))
    if not integral:
        raise CalibrationError("pairs must hold integer posture indices")
    arr = arr.astype(np.intp)
    if arr.min() < 0 or arr.max() >= n:
        bad = int(arr.max()) if arr.max() >= n else int(arr.min())
        raise CalibrationError(f"pairs refer to posture {bad}; valid indices are 0..{n - 1}")
    if np.any(arr[:, 0] == arr[:, 1]):
        raise CalibrationError("a pair (i, i) carries no motion; give pairs of two different postures")
    return arr


def rotation_angles_deg(rotation: ArrayLike) -> np.ndarray:
    """Rotation angles in degrees, in [0, 180], of rotation matrices ``(..., 3, 3)``."""
    rotation = np.asarray(rotation, dtype=float)
    lead = rotation.shape[:-2]
    return np.degrees(Rotation.from_matrix(rotation.reshape(-1, 3, 3)).magnitude()).reshape(lead)


def _unit_axes(rotation) -> np.ndarray:
    """Unit rotation axes ``(p, 3)`` of rotation matrices ``(p, 3, 3)`` (none of them the identity)."""
    axes = Rotation.from_matrix(rotation).as_rotvec()
    return axes / np.linalg.norm(axes, axis=1, keepdims=True)


def prepare_motions(hand: np.ndarray, target2cam: np.ndarray, pairs: np.ndarray | None = None) -> Motions:
    """Check the input, build the relative motions, normalise lengths and drop degenerate pairs.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
    pairs : array-like of int, shape (p, 2), optional
        Default: all pairs ``i < j`` (:func:`default_pairs`).

    Returns
    -------
    Motions

    Raises
    ------
    CalibrationError
        Bad input (see :func:`check_poses`, :func:`check_pairs`), fewer than two usable pairs, or
        rotation axes that are all parallel.
    """
    hand, target2cam = check_poses(hand, target2cam)
    pairs = check_pairs(pairs, len(hand))
    a, b = relative_transforms(hand, target2cam, pairs)
    # One length for both sides: the RMS relative translation (falls back to 1 without translation).
    lengths = np.concatenate([np.linalg.norm(a[:, :3, 3], axis=1), np.linalg.norm(b[:, :3, 3], axis=1)])
    scale = float(np.sqrt(np.mean(lengths**2)))
    if not scale > 0:
        scale = 1.0
    angle_a = rotation_angles_deg(a[:, :3, :3])
    angle_b = rotation_angles_deg(b[:, :3, :3])
    keep = (np.minimum(angle_a, angle_b) >= MIN_PAIR_ANGLE_DEG) & (np.maximum(angle_a, angle_b) <= MAX_PAIR_ANGLE_DEG)
    if keep.sum() < 2:
        raise CalibrationError(
            f"only {int(keep.sum())} of {len(pairs)} posture pairs rotate by between {MIN_PAIR_ANGLE_DEG:g} and "
            f"{MAX_PAIR_ANGLE_DEG:g} deg; rotate the flange by 15-90 deg about different axes between postures"
        )
    divergence = rotation_axis_divergence_deg(_unit_axes(a[keep, :3, :3]))  # calibration.quality_words
    if divergence < MIN_AXIS_DIVERGENCE_DEG:
        raise CalibrationError(
            f"all relative rotations are about nearly parallel axes (rotation-axis divergence {divergence:.2f} deg); "
            f"rotate the flange about at least two different axes"
        )
    moving = angle_a >= MIN_PAIR_ANGLE_DEG
    return Motions(
        pairs=pairs[keep],
        rot_a=a[keep, :3, :3],
        rot_b=b[keep, :3, :3],
        t_a=a[keep, :3, 3] / scale,
        t_b=b[keep, :3, 3] / scale,
        translation_pairs=pairs[moving],
        rot_a_translation=a[moving, :3, :3],
        t_a_translation=a[moving, :3, 3] / scale,
        t_b_translation=b[moving, :3, 3] / scale,
        scale=scale,
        dropped=pairs[~keep],
    )


def translation_least_squares(rot_x: ArrayLike, motions: Motions) -> np.ndarray:
    """``t_X`` (normalised units) from ``(R_A - I) t_X = R_X t_B - t_A`` stacked over the pairs.

    The common second step of the separable methods (Tsai-Lenz eq. 15, Deniz & Cakir eq. 8),
    solved in the least-squares sense.

    Parameters
    ----------
    rot_x : ndarray, shape (3, 3)
    motions : Motions

    Returns
    -------
    ndarray, shape (3,)
    """
    lhs = motions.rot_a_translation - np.eye(3)  # (R_A - I), eq. 8
    rhs = motions.t_b_translation @ np.asarray(rot_x).T - motions.t_a_translation  # R_X t_B - t_A
    t, *_ = np.linalg.lstsq(lhs.reshape(-1, 3), rhs.reshape(-1), rcond=None)
    return t


def solution_transform(rot_x: ArrayLike, t_x_normalised: ArrayLike, motions: Motions) -> np.ndarray:
    """The 4x4 ``X`` in the caller's length unit from a rotation and a normalised translation."""
    return transform_from_rotation_translation(np.asarray(rot_x, float), np.asarray(t_x_normalised, float) * motions.scale)


def nearest_rotation(matrix: ArrayLike) -> np.ndarray:
    """Closest rotation (Frobenius norm, ``det = +1``) to each matrix ``(..., 3, 3)``, via SVD."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=float))
    d = np.sign(np.linalg.det(u @ vt))
    d = np.where(d == 0, 1.0, d)
    u = u.copy()
    u[..., :, 2] *= d[..., None]
    return u @ vt


def rotation_from_scaled_matrix(matrix: ArrayLike) -> np.ndarray:
    """Rotation from a matrix known only up to scale and sign (a null vector reshaped to 3x3).

    ``M`` is scaled by ``sign(det M) / |det M|^(1/3)`` (so that ``det = +1``) and then projected on
    the rotations (Andreff et al. eq. 15 as numbered in OpenCV; Liang & Mao's orthogonalisation).

    Raises
    ------
    CalibrationError
        If ``M`` is (numerically) singular: the data do not determine the rotation.
    """
    matrix = np.asarray(matrix, dtype=float)
    det = float(np.linalg.det(matrix))
    size = float(np.linalg.norm(matrix)) ** 3
    if not np.isfinite(det) or abs(det) <= 1e-9 * max(size, np.finfo(float).tiny):
        raise CalibrationError("the rotation system is singular; rotate the flange about at least two different axes")
    return nearest_rotation(np.sign(det) * matrix / abs(det) ** (1.0 / 3.0))


def _product_matrix(q, sign: float) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    w, v = q[..., 0], q[..., 1:]
    out = np.empty(q.shape[:-1] + (4, 4))
    out[..., 0, 0] = w
    out[..., 0, 1:] = -v
    out[..., 1:, 0] = v
    out[..., 1:, 1:] = w[..., None, None] * np.eye(3) + sign * skew(v)
    return out


def left_matrix(q: np.ndarray) -> np.ndarray:
    """``L(q)`` with ``L(q) p = q * p`` (Hamilton product), for quaternions ``(..., 4)`` (w, x, y, z).

    Horaud & Dornaika's ``Q(q)`` (appendix A).
    """
    return _product_matrix(q, 1.0)


def right_matrix(q: np.ndarray) -> np.ndarray:
    """``R(q)`` with ``R(q) p = p * q``, for quaternions ``(..., 4)`` (w, x, y, z).

    Horaud & Dornaika's ``W(q)`` (appendix A).
    """
    return _product_matrix(q, -1.0)


def quaternions(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` (w, x, y, z), ``w >= 0``, of rotation matrices ``(..., 3, 3)``."""
    return quaternion_from_matrix(rotation)


def constrained_null_combination(v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """The combination ``x = l1 v1 + l2 v2`` of two 8-vectors with ``|x[:4]| = 1`` and ``x[:4] . x[4:] = 0``.

    The two right singular vectors of the smallest singular values of the Daniilidis and Lu-Chou
    systems span ``{(q, q'), (0, q)}`` for exact data; the unit dual quaternion of ``X`` is the
    combination whose real part has unit norm and is orthogonal to its dual part (Daniilidis eq. 34-35
    as numbered in OpenCV). The quadratic ``l^T S l = 0``, ``S = [[u1.w1, (u1.w2 + u2.w1)/2], [., u2.w2]]``
    (``u`` = real parts, ``w`` = dual parts), is solved in the eigenbasis of ``S``, which stays finite
    when the leading coefficient vanishes; of its two roots the one with the larger ``|u|`` is taken.
    With noise the quadratic may have no real root: the direction with the smallest ``|l^T S l|`` is
    used then.

    Parameters
    ----------
    v1, v2 : ndarray, shape (8,)

    Returns
    -------
    ndarray, shape (8,)
        With ``|x[:4]| = 1``.
    """
    u1, w1, u2, w2 = v1[:4], v1[4:], v2[:4], v2[4:]
    off = 0.5 * (u1 @ w2 + u2 @ w1)
    s = np.array([[u1 @ w1, off], [off, u2 @ w2]])
    evals, evecs = np.linalg.eigh(s)  # evals ascending
    if evals[0] <= 0.0 <= evals[1]:
        candidates = [np.sqrt(evals[1]) * evecs[:, 0] + sign * np.sqrt(-evals[0]) * evecs[:, 1] for sign in (1.0, -1.0)]
    else:
        candidates = [evecs[:, int(np.argmin(np.abs(evals)))]]
    best = None
    for lam in candidates:
        x = lam[0] * v1 + lam[1] * v2
        norm = np.linalg.norm(x[:4])
        if best is None or norm > best[0]:
            best = (norm, x)
    if best is None:
        raise CalibrationError("no candidate combination of the two null vectors")  # candidates is never empty
    norm, x = best
    if not norm > 1e-12:
        raise CalibrationError("the dual quaternion system is degenerate; rotate the flange about at least two different axes")
    return x / norm
