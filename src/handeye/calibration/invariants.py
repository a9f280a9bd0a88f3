"""X-free invariants of ``AX = XB``: what the poses must satisfy whatever the camera mount ``X`` is.

In the frame-neutral form of the problem (``problem.py``) every posture ``i`` has a hand pose
``H_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand) and a board pose ``B_i``
(``target2cam``), and ``H_i X B_i = G`` is the same for every posture (``G``: the board in the
base, or the board on the flange). For two postures the relative motions

    A_ij = H_i^-1 H_j          and          B_ij = B_i B_j^-1

are then conjugate, ``A_ij = X B_ij X^-1``, so they share everything conjugation keeps:

- **the rotation angle** (eq. 30 of the paper, ``S_A = S_B``): independent of ``X``, of the set-up
  and even of inverting either pose set (``T_i^-1 T_j`` and ``T_i T_j^-1`` turn by the same angle);
- **the screw pitch**: the translation along the rotation axis, ``d = n . t`` (same independence);
- **the rotation axes up to one rotation**: ``n_A = R_X n_B`` for every pair with one ``R_X``; this
  one depends on the set-up and on which pose sets are inverted, which is what makes it useful;
- **the translations up to one rigid X**: ``(R_A - I) t_X = R_X t_B - t_A`` is solvable.

:func:`relative_angles_deg` and :func:`screw_pitches` are the per-side parts of the first two, so
that many readings of a file can be compared cheaply; :func:`fit_hand_eye` does the full test for
one reading and returns the fitted ``X`` and ``G`` with the residuals. Angles in degrees; lengths in
the poses' own unit.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..geometry import invert_transforms

__all__ = [
    "MIN_MOTION_DEG",
    "InvariantFit",
    "ALL_PAIRS_UP_TO",
    "RANDOM_PARTNERS",
    "pair_indices",
    "bounded_pairs",
    "pairs_used",
    "posture_medians",
    "relative_angles_deg",
    "screw_pitches",
    "relative_transforms",
    "fit_hand_eye",
    "angle_gap_deg",
]

#: Relative motions smaller than this (or this close to 180 deg) have no usable rotation axis.
MIN_MOTION_DEG = 3.0


def _pairs_of_ranks(n: int, ranks) -> np.ndarray:
    """Pairs ``(i, j)``, ``i < j``, at positions ``ranks`` of the lexicographic list of all pairs of
    ``n`` postures (the order of ``np.triu_indices``), without building that list: shape ``(m, 2)``."""
    ranks = np.asarray(ranks, dtype=np.int64)
    rows = np.arange(n - 1, dtype=np.int64)
    starts = rows * (n - 1) - rows * (rows - 1) // 2  # rank of pair (i, i + 1)
    i = np.searchsorted(starts, ranks, side="right") - 1
    return np.stack([i, ranks - starts[i] + i + 1], axis=1).astype(np.intp)


def pair_indices(n: int, max_pairs: int | None = None, seed: int = 0) -> np.ndarray:
    """Index pairs ``(i, j)``, ``i < j``, of ``n`` postures: all of them, or an even sample.

    The sample never builds the list of all ``n(n-1)/2`` pairs: memory and time grow with
    ``max_pairs``, not with ``n^2`` (it is the same sample as drawing from that list).

    Parameters
    ----------
    n : int
    max_pairs : int, optional
        At most this many pairs (a seeded random sample, the same for the same ``n``).
    seed : int

    Returns
    -------
    ndarray of int, shape (m, 2)
        Lexicographic order.
    """
    n = int(n)
    total = n * (n - 1) // 2
    if max_pairs is None or total <= max_pairs:
        i, j = np.triu_indices(n, k=1)
        return np.stack([i, j], axis=1)
    keep = np.sort(np.random.default_rng(seed).choice(total, size=int(max_pairs), replace=False))
    return _pairs_of_ranks(n, keep)


#: Up to this many posture pairs (316 postures: a guided capture stops at 255) the checks use every
#: pair, as they always did.
ALL_PAIRS_UP_TO = 50000
#: Above it, each posture is paired with its neighbour in time and at least this many random partners.
RANDOM_PARTNERS = 10


def bounded_pairs(n: int, seed: int = 0) -> np.ndarray:
    """The posture pairs the pairwise checks use: every pair up to :data:`ALL_PAIRS_UP_TO` of them;
    above, each posture ``i`` with its neighbour in time ``i + 1`` and ``k`` random partners,
    ``k = max(RANDOM_PARTNERS, ALL_PAIRS_UP_TO // n)`` (seeded: the same pairs for the same ``n``), so
    that the cost grows linearly with ``n`` and every posture takes part in ``2k + 2`` pairs or so.

    Parameters
    ----------
    n : int
    seed : int

    Returns
    -------
    ndarray of int, shape (m, 2)
        ``i < j``, lexicographic order, no pair twice; ``m = n(n-1)/2``, or ``m <= (k + 1) n``.
    """
    n = int(n)
    if n * (n - 1) // 2 <= ALL_PAIRS_UP_TO:
        return pair_indices(n)
    k = max(RANDOM_PARTNERS, ALL_PAIRS_UP_TO // n)
    first = np.repeat(np.arange(n), k + 1)
    offset = np.random.default_rng(seed).integers(1, n, size=(n, k + 1))
    offset[:, 0] = 1  # the neighbour in time
    second = (first + offset.reshape(-1)) % n
    key = np.sort(np.minimum(first, second).astype(np.int64) * n + np.maximum(first, second))
    key = key[np.r_[True, key[1:] != key[:-1]]]  # (np.unique: the same, many times slower here)
    return np.stack([key // n, key % n], axis=1).astype(np.intp)


def posture_medians(gaps: ArrayLike, pairs: ArrayLike, n: int) -> np.ndarray:
    """Per posture, the median of the (non-NaN) values ``gaps`` of the pairs it is part of, shape ``(n,)``
    (NaN for a posture in no pair): the row medians of the symmetric ``(n, n)`` matrix of the values,
    without building it.

    Parameters
    ----------
    gaps : array-like, shape (m,)
    pairs : array-like of int, shape (m, 2)
    n : int
    """
    gaps = np.asarray(gaps, dtype=float)
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    posture = np.concatenate([pairs[:, 0], pairs[:, 1]])
    values = np.concatenate([gaps, gaps])
    finite = ~np.isnan(values)
    posture, values = posture[finite], values[finite]
    order = np.lexsort((values, posture))
    values = values[order]
    counts = np.bincount(posture, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    out = np.full(n, np.nan)
    has = counts > 0
    lo, hi = starts[has] + (counts[has] - 1) // 2, starts[has] + counts[has] // 2
    out[has] = 0.5 * (values[lo] + values[hi])
    return out


def pairs_used(count: int, n: int) -> str:
    """How many posture pairs a check used, for the text that states it: ``"all 4950 posture pairs"``
    or ``"109888 of 49995000 posture pairs (neighbours in time and a fixed random sample)"``."""
    total = int(n) * (int(n) - 1) // 2
    if int(count) >= total:
        return f"all {total} posture pairs"
    return f"{int(count)} of {total} posture pairs (neighbours in time and a fixed random sample)"


def relative_angles_deg(rotations: ArrayLike, pairs: ArrayLike) -> np.ndarray:
    """Rotation angle of ``R_i^T R_j`` for each pair, degrees (the same as that of ``R_i R_j^T``).

    Parameters
    ----------
    rotations : array-like, shape (n, 3, 3) or (n, 4, 4)
    pairs : array-like of int, shape (m, 2)

    Returns
    -------
    ndarray, shape (m,)
    """
    r = np.asarray(rotations, dtype=float)[:, :3, :3]
    pairs = np.asarray(pairs, dtype=int)
    trace = np.einsum("mij,mij->m", r[pairs[:, 0]], r[pairs[:, 1]])  # trace(R_i^T R_j)
    return np.degrees(np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0)))


def angle_gap_deg(angles_a: ArrayLike, angles_b: ArrayLike) -> float:
    """Median ``|angle(A_ij) - angle(B_ij)|`` over pairs, degrees (``inf`` when there is no pair)."""
    gaps = np.abs(np.asarray(angles_a, float) - np.asarray(angles_b, float))
    return float(np.median(gaps)) if gaps.size else float("inf")


def relative_transforms(hand: ArrayLike, target2cam: ArrayLike, pairs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``A_ij = H_i^-1 H_j`` and ``B_ij = B_i B_j^-1`` for each pair, shapes ``(m, 4, 4)``: the relative
    motions as transforms of the poses (``triplets.relative_motions`` is Algorithm 1's step 2: hand
    quaternions and the compact points' rotations, of a problem)."""
    h = np.asarray(hand, dtype=float)
    b = np.asarray(target2cam, dtype=float)
    pairs = np.asarray(pairs, dtype=int)
    i, j = pairs[:, 0], pairs[:, 1]
    return invert_transforms(h[i]) @ h[j], b[i] @ invert_transforms(b[j])


def _rotvecs(transforms) -> np.ndarray:
    return Rotation.from_matrix(np.asarray(transforms)[:, :3, :3]).as_rotvec()


def screw_pitches(motions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation angle (deg) and translation along the rotation axis ``d = n . t`` of motions ``(m, 4, 4)``.

    ``d`` is the same for a motion and its inverse (the axis turns round with the translation), so
    it does not depend on which pose set is inverted either. Motions without rotation give ``d = 0``.
    """
    v = _rotvecs(motions)
    angle = np.linalg.norm(v, axis=1)
    axis = v / np.maximum(angle, 1e-12)[:, None]
    return np.degrees(angle), np.einsum("mi,mi->m", axis, np.asarray(motions)[:, :3, 3])


@dataclass(frozen=True)
class InvariantFit:
    """How well one reading of the poses fits ``H_i X B_i = G`` (all values NaN when no pair is usable).

    Attributes
    ----------
    angle_gap_deg : float
        Median ``|angle(A_ij) - angle(B_ij)|``.
    axis_deg : float
        Median rotation residual of ``R_A R_X = R_X R_B`` with ``R_X`` fitted to the rotation axes.
    translation : float
        Median translation residual of ``A X = X B`` (the poses' unit).
    motion : float
        Median translation of ``A_ij`` (the yardstick of ``translation``).
    pitch_scale : float
        Least-squares ratio of the screw pitches ``d_A / d_B`` (1 when both sides share a unit).
    pairs : int
        Pairs with a usable rotation.
    x, g : ndarray, shape (4, 4)
        The fitted ``X`` and ``G = mean H_i X B_i`` (a yardstick: not a calibration).
    pair_misfits : ndarray, shape (pairs, 3)
        Per usable pair: angle gap (deg), axis residual (deg), translation residual (the poses' unit).
    misfit_pairs : ndarray of int, shape (pairs, 2)
        The posture pairs of ``pair_misfits`` (for :func:`posture_medians`).
    """

    angle_gap_deg: float
    axis_deg: float
    translation: float
    motion: float
    pitch_scale: float
    pairs: int
    x: np.ndarray
    g: np.ndarray
    pair_misfits: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    misfit_pairs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=int))

    @property
    def translation_ratio(self) -> float:
        """``translation / motion`` (NaN without motion)."""
        return self.translation / self.motion if self.motion > 0 else float("nan")


def _nan_fit(gap: float = float("nan")) -> InvariantFit:
    nan = float("nan")
    return InvariantFit(gap, nan, nan, nan, nan, 0, np.full((4, 4), nan), np.full((4, 4), nan))


def _align(target_vectors, source_vectors) -> np.ndarray:
    """Rotation carrying ``source_vectors`` onto ``target_vectors`` (least squares), quietly."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Rotation.align_vectors(target_vectors, source_vectors)[0].as_matrix()


def fit_hand_eye(hand: ArrayLike, target2cam: ArrayLike, pairs: ArrayLike | None = None, min_motion_deg: float = MIN_MOTION_DEG) -> InvariantFit:
    """Fit ``H_i X B_i = G`` linearly and measure how well every invariant holds.

    The rotation ``R_X`` from the rotation axes (Park and Martin 1994), the translation by linear
    least squares (Tsai and Lenz 1989), ``G`` as the mean of ``H_i X B_i``. Pairs whose rotation is
    under ``min_motion_deg`` or within it of 180 deg are left out of the axis and pitch parts.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
    pairs : array-like of int, shape (m, 2), optional
        Default: every pair.

    Returns
    -------
    InvariantFit
        All NaN when a pose is not finite or no pair is given.
    """
    h = np.asarray(hand, dtype=float)
    b = np.asarray(target2cam, dtype=float)
    if pairs is None:
        pairs = pair_indices(len(h))
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    if len(pairs) == 0 or not (np.all(np.isfinite(h)) and np.all(np.isfinite(b))):
        return _nan_fit()
    rel_a, rel_b = relative_transforms(h, b, pairs)
    va, vb = _rotvecs(rel_a), _rotvecs(rel_b)
    na, nb = np.linalg.norm(va, axis=1), np.linalg.norm(vb, axis=1)
    pair_gaps = np.degrees(np.abs(na - nb))
    gap = float(np.median(pair_gaps))
    lo, hi = np.radians(min_motion_deg), np.radians(180.0 - min_motion_deg)
    ok = (na > lo) & (na < hi) & (nb > lo) & (nb < hi)
    if ok.sum() < 2:
        return _nan_fit(gap)
    rel_a, rel_b, va, vb, pair_gaps = rel_a[ok], rel_b[ok], va[ok], vb[ok], pair_gaps[ok]
    rx = _align(va, vb)
    axis_res = Rotation.from_matrix(np.einsum("mji,mjk->mik", rel_a[:, :3, :3] @ rx, rx @ rel_b[:, :3, :3]))
    pair_axis = np.degrees(axis_res.magnitude())
    axis_deg = float(np.median(pair_axis))
    lhs = (rel_a[:, :3, :3] - np.eye(3)).reshape(-1, 3)
    rhs = (rel_b[:, :3, 3] @ rx.T - rel_a[:, :3, 3]).reshape(-1)
    tx = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    residual = np.einsum("mij,j->mi", rel_a[:, :3, :3], tx) + rel_a[:, :3, 3] - rel_b[:, :3, 3] @ rx.T - tx
    d_a = np.einsum("mi,mi->m", va / np.linalg.norm(va, axis=1, keepdims=True), rel_a[:, :3, 3])
    d_b = np.einsum("mi,mi->m", vb / np.linalg.norm(vb, axis=1, keepdims=True), rel_b[:, :3, 3])
    denominator = float(np.sum(d_b**2))
    scale = float(np.sum(d_a * d_b) / denominator) if denominator > 0 else float("nan")
    x = np.eye(4)
    x[:3, :3] = rx
    x[:3, 3] = tx
    fixed = h @ x @ b
    g = np.eye(4)
    u, _, vt = np.linalg.svd(np.sum(fixed[:, :3, :3], axis=0))
    g[:3, :3] = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    g[:3, 3] = np.median(fixed[:, :3, 3], axis=0)
    pair_translation = np.linalg.norm(residual, axis=1)
    return InvariantFit(
        angle_gap_deg=gap,
        axis_deg=axis_deg,
        translation=float(np.median(pair_translation)),
        motion=float(np.median(np.linalg.norm(rel_a[:, :3, 3], axis=1))),
        pitch_scale=scale,
        pairs=int(ok.sum()),
        x=x,
        g=g,
        pair_misfits=np.stack([pair_gaps, pair_axis, pair_translation], axis=1),
        misfit_pairs=pairs[ok],
    )
