"""Algorithm 1 of the paper, steps 2-5: a candidate ``X`` from every triplet of postures.

Deniz, C. and Cakir, M., "Solution to the hand-eye calibration in the manner of absolute
orientation problem", Industrial Robot (2018).

With hand poses ``A_i`` and compact points ``P_i`` (camera frame), the relative motions of a pair
``(i, j)`` are ``A_ij = A_i^-1 A_j`` and ``B_ij = B_i B_j^-1`` (``B`` = board in camera), so that
``A_ij X = X B_ij`` (eq. 1). In quaternions ``Q_A = Q_X * Q_B * Q̄_X`` (eq. 15), so the scalar parts
agree and ``V_A = rot(Q_X, V_B)`` (eq. 30): ``Q_X`` is the absolute orientation of the vector parts.
Every array operation below runs over all pairs or all triplets at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .absolute_orientation import rotation_between_vectors
from .invariants import pair_indices
from .problem import HandEyeProblem
from ..geometry import canonical_quaternions, matrix_from_quaternion, quaternion_conjugate, quaternion_from_matrix, quaternion_multiply

__all__ = [
    "RelativeMotions",
    "Candidates",
    "pair_indices",
    "triplet_indices",
    "relative_motions",
    "triplet_candidates",
    "PairTerms",
    "pair_terms",
    "translation_from_pairs",
    "all_postures_solution",
]

#: Triplets whose Horn eigen-gap falls below this carry (nearly) parallel rotation axes.
MIN_EIGEN_GAP = 1e-3
#: Triplets whose translation system has a reciprocal condition number below this are dropped.
MIN_TRANSLATION_RCOND = 1e-4


def triplet_indices(n: int) -> np.ndarray:
    """All triplets ``i < j < k`` of ``n`` postures, shape ``(C(n, 3), 3)``, lexicographic order."""
    if n < 3:
        return np.zeros((0, 3), dtype=np.intp)
    i, j, k = np.nonzero(np.triu(np.ones((n, n), bool), 1)[:, :, None] & np.triu(np.ones((n, n), bool), 1)[None, :, :])
    return np.stack([i, j, k], axis=1)


@dataclass(frozen=True)
class RelativeMotions:
    """Relative motions of all posture pairs (Algorithm 1, step 2).

    Attributes
    ----------
    pairs : ndarray, shape (p, 2)
        ``(i, j)`` with ``i < j``.
    pair_lookup : ndarray, shape (n, n), or None
        ``pair_lookup[i, j]`` = row of pair ``(i, j)`` (``-1`` on and below the diagonal); ``None``
        for motions of chosen pairs only (:func:`relative_motions` with ``pairs``).
    q_hand : ndarray, shape (n, 4)
        ``Q_A^i``: hand rotations, ``w >= 0``.
    rot_hand : ndarray, shape (n, 3, 3)
    pos_hand : ndarray, shape (n, 3)
    q_a, q_b : ndarray, shape (p, 4)
        ``Q_A^ij = Q̄_A^i * Q_A^j`` and ``Q_B^ij = absROT(P_j -> P_i)``, both ``w >= 0``.
    """

    pairs: np.ndarray
    pair_lookup: np.ndarray | None
    q_hand: np.ndarray
    rot_hand: np.ndarray
    pos_hand: np.ndarray
    q_a: np.ndarray
    q_b: np.ndarray

    @property
    def angle_a_deg(self) -> np.ndarray:
        return np.degrees(2.0 * np.arccos(np.clip(self.q_a[:, 0], -1.0, 1.0)))

    @property
    def angle_b_deg(self) -> np.ndarray:
        return np.degrees(2.0 * np.arccos(np.clip(self.q_b[:, 0], -1.0, 1.0)))


def relative_motions(problem: HandEyeProblem, pairs: ArrayLike | None = None) -> RelativeMotions:
    """Algorithm 1, step 2, for all pairs ``i < j``, or for the given ``pairs`` (shape ``(p, 2)``,
    ``i < j``; then without ``pair_lookup``, which the triplets need: a check of the motion, not a solve)."""
    n = problem.n
    lookup = None
    if pairs is None:
        pairs = pair_indices(n)
        lookup = -np.ones((n, n), dtype=np.intp)
        lookup[pairs[:, 0], pairs[:, 1]] = np.arange(len(pairs))
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    rot_hand = problem.hand[:, :3, :3]
    q_hand = quaternion_from_matrix(rot_hand)
    i, j = pairs[:, 0], pairs[:, 1]
    q_a = canonical_quaternions(quaternion_multiply(quaternion_conjugate(q_hand[i]), q_hand[j]))
    # Q_B^ij = absROT(P_j -> P_i) on centred compact points (eq. 24-28).
    pts = problem.compact.points
    centred = pts - pts.mean(axis=1, keepdims=True)
    q_b = rotation_between_vectors(centred[j], centred[i]).quaternion
    return RelativeMotions(pairs, lookup, q_hand, rot_hand, problem.hand[:, :3, 3], q_a, q_b)


@dataclass(frozen=True)
class Candidates:
    """One candidate ``X`` per triplet (Algorithm 1, steps 3-5).

    Attributes
    ----------
    triplets : ndarray, shape (c, 3)
    rotation : ndarray, shape (c, 3, 3)
        ``R_X`` of each candidate.
    translation : ndarray, shape (c, 3)
        ``D_X`` of each candidate, mm.
    valid : ndarray of bool, shape (c,)
        False where the triplet's rotation axes are (nearly) parallel or its translation
        system is singular: such candidates are never selected.
    """

    triplets: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    valid: np.ndarray

    def __len__(self) -> int:
        return len(self.triplets)

    def transform(self, index: int) -> np.ndarray:
        out = np.eye(4)
        out[:3, :3] = self.rotation[index]
        out[:3, 3] = self.translation[index]
        return out


@dataclass(frozen=True)
class PairTerms:
    """Per-pair pieces of the translation system (eq. 31-32), so that for any set of pairs

        sum (R_j - R_i)^T (R_j - R_i) D_X = sum h_ij + sum K_ij vec(R_X)

    where ``h_ij = (R_j - R_i)^T (p_i - p_j)`` and ``K_ij vec(R_X) = (R_j - R_i)^T (R_i R_X c_i - R_j R_X c_j)``
    (``c`` = the board centre in the camera frame, ``R, p`` = hand rotation and position).

    Attributes
    ----------
    normal : ndarray, shape (p, 3, 3)
    h : ndarray, shape (p, 3)
    k : ndarray, shape (p, 3, 9)
    """

    normal: np.ndarray
    h: np.ndarray
    k: np.ndarray


def pair_terms(motions: RelativeMotions, centres_cam: np.ndarray) -> PairTerms:
    """:class:`PairTerms` of all pairs of ``motions`` for board centres ``(n, 3)`` in the camera frame."""
    rot, pos = motions.rot_hand, motions.pos_hand
    i, j = motions.pairs[:, 0], motions.pairs[:, 1]
    d = rot[j] - rot[i]  # eq. 32: A_ij = R_j - R_i
    dt = np.swapaxes(d, 1, 2)
    normal = dt @ d
    h = np.einsum("pab,pb->pa", dt, pos[i] - pos[j])
    f = dt @ rot[i]
    g = dt @ rot[j]
    k = (f[:, :, :, None] * centres_cam[i][:, None, None, :] - g[:, :, :, None] * centres_cam[j][:, None, None, :])
    return PairTerms(normal, h, k.reshape(-1, 3, 9))


def _solve_symmetric_3x3(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``a x = b`` for stacks of symmetric positive semi-definite 3x3 matrices (adjugate).

    Returns ``x (..., 3)`` and a reciprocal condition estimate ``det / (trace/3)^3`` in [0, 1].
    """
    a00, a01, a02 = a[..., 0, 0], a[..., 0, 1], a[..., 0, 2]
    a11, a12, a22 = a[..., 1, 1], a[..., 1, 2], a[..., 2, 2]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    safe = np.where(np.abs(det) > 0, det, 1.0)
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    x = np.stack([c00 * b0 + c01 * b1 + c02 * b2, c01 * b0 + c11 * b1 + c12 * b2, c02 * b0 + c12 * b1 + c22 * b2], axis=-1)
    x = x / safe[..., None]
    scale = np.maximum((a00 + a11 + a22) / 3.0, np.finfo(float).tiny)
    return x, det / scale**3


def translation_from_pairs(terms: PairTerms, rotation_x: np.ndarray, pair_rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``D_X`` from the stacked system ``(R_j - R_i) D_X = P̂_i - P̂_j`` (eq. 31-32), batched.

    Algorithm 1 step 4 gives ``P̂_i = P_tool0^i + rot(Q_tool0^i * Q_X, P^i)``; step 5 solves for
    ``D_X`` in least squares over the pairs of each candidate (normal equations).

    Parameters
    ----------
    terms : PairTerms
    rotation_x : ndarray, shape (c, 3, 3)
        Candidate ``R_X``.
    pair_rows : ndarray of int, shape (c, k)
        For each candidate the rows (into ``terms``) of the pairs stacked into its system.

    Returns
    -------
    translation : ndarray, shape (c, 3)
    rcond : ndarray, shape (c,)
        ``det / (trace/3)^3`` of the normal matrix: 1 for a perfectly conditioned system, 0 singular.
    """
    normal = terms.normal[pair_rows[:, 0]]
    h = terms.h[pair_rows[:, 0]]
    k = terms.k[pair_rows[:, 0]]
    for column in range(1, pair_rows.shape[1]):  # sums of gathered rows (cheaper than gather + reduce)
        rows = pair_rows[:, column]
        normal = normal + terms.normal[rows]
        h = h + terms.h[rows]
        k = k + terms.k[rows]
    rhs = h + np.einsum("cij,cj->ci", k, rotation_x.reshape(-1, 9))
    return _solve_symmetric_3x3(normal, rhs)


def triplet_candidates(problem: HandEyeProblem, motions: RelativeMotions | None = None) -> Candidates:
    """Algorithm 1, steps 3-5: ``Q_X`` and ``D_X`` from every triplet ``i < j < k``."""
    motions = motions if motions is not None else relative_motions(problem)
    triplets = triplet_indices(problem.n)
    lookup = motions.pair_lookup
    if lookup is None:
        raise ValueError("triplet candidates need the motions of all pairs (relative_motions without pairs)")
    i, j, k = triplets[:, 0], triplets[:, 1], triplets[:, 2]
    pair_rows = np.stack([lookup[i, j], lookup[i, k], lookup[j, k]], axis=1)  # (c, 3)
    v_a = motions.q_a[pair_rows, 1:]
    v_b = motions.q_b[pair_rows, 1:]
    # Step 3, eq. 30: Q_X = absROT(V_B, V_A).
    fit = rotation_between_vectors(v_b, v_a)
    rotation = matrix_from_quaternion(fit.quaternion)
    # Steps 4-5, eq. 31-32, on the three pairs of the triplet.
    terms = pair_terms(motions, problem.compact.points[:, 0, :])
    translation, rcond = translation_from_pairs(terms, rotation, pair_rows)
    valid = (fit.eigen_gap > MIN_EIGEN_GAP) & (rcond > MIN_TRANSLATION_RCOND) & np.all(np.isfinite(translation), axis=1)
    return Candidates(triplets, rotation, translation, valid)


def all_postures_solution(problem: HandEyeProblem, motions: RelativeMotions | None = None) -> np.ndarray:
    """The paper's ``MC``: Horn's least squares over the vector parts of all pairs, then ``D_X``
    from all pairs at once (no selection). Returns ``X`` as a 4x4 matrix."""
    motions = motions if motions is not None else relative_motions(problem)
    fit = rotation_between_vectors(motions.q_b[:, 1:], motions.q_a[:, 1:])
    rotation = matrix_from_quaternion(fit.quaternion)
    terms = pair_terms(motions, problem.compact.points[:, 0, :])
    translation, _ = translation_from_pairs(terms, rotation[None], np.arange(len(motions.pairs))[None])
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = translation[0]
    return out
