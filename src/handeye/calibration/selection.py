"""Algorithm 1, step 6: choosing one candidate ``X`` by a criterion, for thousands of candidates.

Every candidate ``X = (R_X, t_X)`` is written as a 12-vector ``θ = [vec(R_X) row-major, t_X]``.
The fixed-frame position of board point ``p`` seen at posture ``n`` is affine in ``θ``:

    x_np(θ) = R_n R_X q_np + R_n t_X + p_n = G_np θ + p_n        (eq. 13)

so all candidates are scored with one matrix product per chunk. The criteria (each the ``solver`` of
its row of the methods table, ``calibration.methods``; :func:`select_candidate` takes the row's name or
the function):

``mcr``  least rotational error δR (eq. 16), summed over all pairs: a quadratic form in vec(R_X).
``mct``  least translational error δt (eq. 16), summed over all pairs: a quadratic form in θ.
``mco``  least d_org (eq. 22), the mean distance to the mean point.
``mcb``  least d_back (eq. 23), the mean pairwise distance. Scoring it in full costs N/2 times d_org,
         so candidates are first screened with bounds that come with d_org: per point, with radii
         r_n = |x_n - mean| (N postures),
             N/(N-1) mean(r) <= d_back <= 2 mean(r)                   (triangle inequality)
             d_back <= sqrt(2N/(N-1) mean(r^2))                       (mean <= RMS; exact RMS)
             d_back >= N mean(r^2) / ((N-1) max(r))                   (|x_i - x_j| <= 2 max r)
         Only candidates whose lower bound is below the best upper bound are scored exactly, in order
         of their lower bound, until the next lower bound exceeds the best exact score. The result is
         the exact minimiser.
``mcy``  least mean distance to the true board points (synthetic data only).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, overload

import numpy as np

from .methods import get_method, method_names
from ..base import map_chunks
from ..geometry import matrix_from_quaternion
from .triplets import Candidates, RelativeMotions

__all__ = [
    "CandidateScorer",
    "Selection",
    "SelectionInputs",
    "select_candidate",
    "least_rotation_residual",
    "least_translation_residual",
    "least_d_org",
    "least_d_back",
    "least_truth_distance",
]

#: Candidates scored per chunk (bounds the memory: chunk * n * points * 3 doubles).
CHUNK = 4096
#: Candidates scored exactly per batch in the mcb search.
EXACT_BATCH = 128
#: Above this many candidates the first screen runs in single precision (with rigorous margins).
FAST_SCREEN_MIN = 20000


def _theta(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """``θ`` of candidates, shape ``(12, c)``."""
    return np.concatenate([rotation.reshape(-1, 9), translation], axis=1).T


@dataclass(frozen=True)
class Selection:
    """The chosen candidate and how it was found.

    Attributes
    ----------
    index : int
        Row of the chosen candidate.
    score : float
        Its criterion value (mm for d_org/d_back/mcy and δt, dimensionless for δR).
    scores : ndarray, shape (c,)
        Criterion per candidate where it was computed exactly, NaN elsewhere (mcb screens).
    exact_evaluations : int
        Number of candidates scored exactly (all of them except for mcb).
    """

    index: int
    score: float
    scores: np.ndarray
    exact_evaluations: int


@dataclass(frozen=True)
class SelectionInputs:
    """What a selection criterion may need besides the candidates.

    Attributes
    ----------
    scorer : CandidateScorer
        Built on the compact points (``p = 3``) of the problem.
    motions : RelativeMotions or None
        The posture pairs' relative motions (``mcr``, ``mct``).
    centres_cam : ndarray, shape (n, 3), or None
        The board centre per posture in the camera frame (``mct``).
    truth_points : ndarray, shape (p, 3), or None
        True fixed-frame positions of the scorer's points (``mcy``; synthetic sessions only).
    """

    scorer: "CandidateScorer"
    motions: RelativeMotions | None = None
    centres_cam: np.ndarray | None = None
    truth_points: np.ndarray | None = None


#: A selection criterion: ``criterion(theta (12, c), inputs) -> Selection`` (the ``solver`` of a paper row).
Criterion = Callable[[np.ndarray, SelectionInputs], Selection]


class CandidateScorer:
    """Scores candidates against the board points of a problem (see module docstring).

    Parameters
    ----------
    hand : ndarray, shape (n, 4, 4)
        Hand poses.
    points_cam : ndarray, shape (n, p, 3)
        Board points per posture in the camera frame (the compact points for selection).
    """

    def __init__(self, hand: np.ndarray, points_cam: np.ndarray):
        rot = hand[:, :3, :3]
        n, p, _ = points_cam.shape
        g = np.empty((n, p, 3, 12))
        # coefficient of R_X[a, b] in x_np is R_n[:, a] * q_np[b]; of t_X[c] it is R_n[:, c]
        g[..., :9] = np.einsum("nka,npb->npkab", rot, points_cam).reshape(n, p, 3, 9)
        g[..., 9:] = rot[:, None, :, :]
        self.n, self.p = n, p
        self.g = g
        self.offset = np.broadcast_to(hand[:, None, :3, 3], (n, p, 3))
        self._g_centred = (g - g.mean(axis=0)).reshape(n * p * 3, 12)
        self._offset_centred = (self.offset - self.offset.mean(axis=0)).reshape(n * p * 3, 1)
        # single-precision copies and the column bounds of their rounding error (screening)
        self._g32 = self._g_centred.astype(np.float32)
        self._offset32 = self._offset_centred.astype(np.float32)
        self._g_colmax = np.abs(self._g_centred).max(axis=0)
        self._offset_max = float(np.abs(self._offset_centred).max())

    def fixed_points(self, theta: np.ndarray) -> np.ndarray:
        """Fixed-frame points for candidates ``θ (12, c)``: shape ``(n, p, 3, c)``."""
        flat = self.g.reshape(-1, 12) @ theta + self.offset.reshape(-1, 1)
        return flat.reshape(self.n, self.p, 3, -1)

    def radius_statistics(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per candidate and point: mean, mean square and max of ``|x_n - mean_n x|``.

        Returns three arrays of shape ``(p, c)``.
        """
        dev = (self._g_centred @ theta + self._offset_centred).reshape(self.n, self.p, 3, -1)
        r2 = np.einsum("npkc,npkc->npc", dev, dev)
        r = np.sqrt(r2)
        return r.mean(axis=0), r2.mean(axis=0), r.max(axis=0)

    def radius_bounds_fast(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of d_back per candidate from single-precision radii; ``(c,), (c,)``.

        The same statistics as :meth:`radius_statistics` in float32 (half the memory traffic,
        four times the matrix speed), widened by a bound of the rounding error so they stay
        rigorous: with ``u = 2^-24`` and 12 terms per entry, every coordinate of a deviation is off
        by at most ``E = 18 u (sum_j max|G_j| |θ_j| + max|o|)``, a radius by ``sqrt(3) E``, and the
        float32 means by ``(n + 5) u`` relative.
        """
        n = self.n
        u = float(np.finfo(np.float32).eps) / 2.0
        theta32 = theta.astype(np.float32)
        dev = (self._g32 @ theta32 + self._offset32).reshape(n, self.p, 3, -1)
        r = np.sqrt(np.einsum("npkc,npkc->npc", dev, dev))
        mean_r = r.mean(axis=0, dtype=np.float64)
        max_r = r.max(axis=0).astype(np.float64)
        err = 18.0 * u * (self._g_colmax @ np.abs(theta) + self._offset_max)
        delta = np.sqrt(3.0) * err + (n + 5) * u * max_r
        ratio = n / (n - 1.0)
        lower = ratio * np.maximum(mean_r - delta, 0.0)
        upper = 2.0 * (mean_r + delta)
        return lower.mean(axis=0), upper.mean(axis=0)

    def distance_to(self, theta: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """Mean over postures and points of ``|x_np - reference_p|``; ``reference (p, 3)``; ``(c,)``."""
        dev = self.fixed_points(theta) - reference[None, :, :, None]
        return np.sqrt(np.einsum("npkc,npkc->npc", dev, dev)).mean(axis=(0, 1))

    def d_back(self, theta: np.ndarray) -> np.ndarray:
        """Exact d_back (eq. 23) averaged over points, per candidate; ``(c,)``."""
        x = self.fixed_points(theta)
        total = np.zeros(x.shape[1:2] + x.shape[3:])
        for i in range(self.n - 1):  # row by row: small temporaries, no index arrays
            diff = x[i + 1:] - x[i]
            total += np.sqrt((diff * diff).sum(axis=2)).sum(axis=0)
        return total.mean(axis=0) * 2.0 / (self.n * (self.n - 1))

    def d_back_lower_bound(self, theta: np.ndarray) -> np.ndarray:
        """A lower bound of d_back from 1-D projections, per candidate; ``(c,)``.

        For unit directions ``u_1..u_M`` and every vector ``v``, ``sum_k |v.u_k| <= c_M |v|`` with
        ``c_M = max over sign patterns |sum_k s_k u_k|``. Summed over all pairs, each 1-D sum of
        ``|a_i - a_j|`` is exact in O(n log n) by sorting (Gini mean difference), so
        ``d_back >= sum_k G_k / c_M``. With the six icosahedral axes the bound is about 0.93 of
        d_back for an isotropic spread of points.
        """
        x = self.fixed_points(theta)
        proj = np.einsum("npkc,mk->pmcn", x, _ICOSAHEDRAL_AXES)
        proj.sort(axis=-1)
        weights = 2.0 * np.arange(1, self.n + 1) - self.n - 1.0
        gini = proj @ weights  # (p, m, c): sum over pairs of |a_i - a_j| per direction
        return (gini.sum(axis=1) / _ICOSAHEDRAL_C).mean(axis=0) * 2.0 / (self.n * (self.n - 1))


def _icosahedral_axes() -> tuple[np.ndarray, float]:
    phi = (1.0 + 5.0**0.5) / 2.0
    axes = np.array([[0, 1, phi], [0, 1, -phi], [1, phi, 0], [1, -phi, 0], [phi, 0, 1], [-phi, 0, 1]], float)
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    signs = np.array(np.meshgrid(*[[1.0, -1.0]] * len(axes))).reshape(len(axes), -1).T
    c = float(np.linalg.norm(signs @ axes, axis=1).max())
    return axes, c


_ICOSAHEDRAL_AXES, _ICOSAHEDRAL_C = _icosahedral_axes()


@overload
def _chunked(fn: Callable[[np.ndarray], np.ndarray], theta: np.ndarray, chunk: int = CHUNK) -> np.ndarray: ...
@overload
def _chunked(fn: Callable[[np.ndarray], tuple[np.ndarray, ...]], theta: np.ndarray,
             chunk: int = CHUNK) -> tuple[np.ndarray, ...]: ...
def _chunked(fn: Callable, theta: np.ndarray, chunk: int = CHUNK) -> np.ndarray | tuple[np.ndarray, ...]:
    outs = map_chunks(fn, [theta[:, s:s + chunk] for s in range(0, theta.shape[1], chunk)])
    if isinstance(outs[0], tuple):
        return tuple(np.concatenate(parts, axis=-1) for parts in zip(*outs))
    return np.concatenate(outs, axis=-1)


def _rotation_form(motions: RelativeMotions, q_b_rot: np.ndarray) -> np.ndarray:
    """9x9 ``K`` with ``sum_pairs tr(R_X^T R_A^T R_X R_B) = vec(R_X)^T K vec(R_X)``."""
    m = np.swapaxes(matrix_from_quaternion(motions.q_a), 1, 2)  # R_A^T
    nb = q_b_rot
    # tr(X^T M X N) = sum X_ji X_kl M_jk N_li
    k = np.einsum("pjk,pli->jikl", m, nb).reshape(9, 9)
    return 0.5 * (k + k.T)


def _translation_form(motions: RelativeMotions, centres_cam: np.ndarray, r_b: np.ndarray):
    """Quadratic form of ``sum_pairs |R_A t + t_A - R_X t_B - t|^2`` in ``θ``: (H, g, c)."""
    i, j = motions.pairs[:, 0], motions.pairs[:, 1]
    rot, pos = motions.rot_hand, motions.pos_hand
    r_a = matrix_from_quaternion(motions.q_a)
    t_a = np.einsum("pki,pk->pi", rot[i], pos[j] - pos[i])  # A_ij = A_i^-1 A_j
    t_b = centres_cam[i] - np.einsum("pij,pj->pi", r_b, centres_cam[j])  # eq. 29
    count = len(motions.pairs)
    lin = np.zeros((count, 3, 12))
    for a in range(3):
        lin[:, a, 3 * a:3 * a + 3] = -t_b  # -R_X t_B
    lin[:, :, 9:] = r_a - np.eye(3)
    h = np.einsum("pki,pkj->ij", lin, lin)
    g = np.einsum("pki,pk->i", lin, t_a)
    c = float(np.sum(t_a * t_a))
    return h, g, c


def select_candidate(
    criterion: str | Criterion,
    candidates: Candidates,
    scorer: CandidateScorer,
    motions: RelativeMotions | None = None,
    centres_cam: np.ndarray | None = None,
    truth_points: np.ndarray | None = None,
) -> Selection:
    """Pick the valid candidate that minimises ``criterion``.

    Parameters
    ----------
    criterion : str or callable
        The name of a paper method whose row holds a criterion (``mcr``, ``mct``, ``mco``, ``mcb``,
        ``mcy`` and any plug-in's), or the criterion itself: ``criterion(theta, inputs) -> Selection``
        over the columns of ``theta (12, c)``, the valid candidates, with ``inputs`` a
        :class:`SelectionInputs`.
    candidates : Candidates
    scorer : CandidateScorer
        Built on the compact points (``p = 3``) of the problem.
    motions, centres_cam : needed by ``mcr`` and ``mct``.
    truth_points : ndarray, shape (p, 3)
        True fixed-frame positions of the scorer's points; needed by ``mcy``.

    Returns
    -------
    Selection
        ``index`` is a row of ``candidates``; ``scores`` has one entry per candidate (NaN where not scored).

    Raises
    ------
    ValueError
        No valid candidate, an unknown criterion name, or a criterion without the inputs it needs.
    """
    choose = _criterion(criterion)
    valid = np.flatnonzero(candidates.valid)
    if len(valid) == 0:
        raise ValueError("no triplet of postures gives a well-posed solution")
    theta = _theta(candidates.rotation[valid], candidates.translation[valid])
    chosen = choose(theta, SelectionInputs(scorer, motions, centres_cam, truth_points))
    scores = np.full(len(candidates), np.nan)
    scores[valid] = chosen.scores
    return Selection(int(valid[chosen.index]), float(chosen.score), scores, int(chosen.exact_evaluations))


def _criterion(criterion: str | Criterion) -> Criterion:
    """The criterion function of ``criterion`` (a function, or the name of its row in the methods table)."""
    if callable(criterion):
        return criterion
    row = get_method(criterion)
    if row is None or row.kind != "paper" or row.solver is None:
        named = method_names("paper", lambda m: m.solver is not None)
        raise ValueError(f"unknown selection criterion {criterion!r}; use one of {', '.join(named)}")
    solver = row.load()
    if solver is None:
        raise ValueError(f"selection criterion {criterion!r} has no solver")
    return solver


def _least(values: np.ndarray) -> Selection:
    """The column of the least value, every column scored."""
    best = int(np.argmin(values))
    return Selection(best, float(values[best]), values, len(values))


def least_rotation_residual(theta: np.ndarray, inputs: SelectionInputs) -> Selection:
    """``mcr``: the least rotational error δR of AX = XB (eq. 16), RMS over all pairs."""
    motions = inputs.motions
    if motions is None:
        raise ValueError("mcr needs the relative motions of the posture pairs")
    k = _rotation_form(motions, matrix_from_quaternion(motions.q_b))
    u = theta[:9]
    total = 6.0 * len(motions.pairs) - 2.0 * np.einsum("ic,ij,jc->c", u, k, u)
    return _least(np.sqrt(np.maximum(total, 0.0) / len(motions.pairs)))


def least_translation_residual(theta: np.ndarray, inputs: SelectionInputs) -> Selection:
    """``mct``: the least translational error δt of AX = XB (eq. 16), RMS over all pairs, mm."""
    motions, centres_cam = inputs.motions, inputs.centres_cam
    if motions is None or centres_cam is None:
        raise ValueError("mct needs the relative motions of the posture pairs and the board centres")
    h, g, c = _translation_form(motions, centres_cam, matrix_from_quaternion(motions.q_b))
    total = np.einsum("ic,ij,jc->c", theta, h, theta) + 2.0 * g @ theta + c
    return _least(np.sqrt(np.maximum(total, 0.0) / len(motions.pairs)))


def least_d_org(theta: np.ndarray, inputs: SelectionInputs) -> Selection:
    """``mco``: the least d_org (eq. 22), the mean distance to the mean point, mm."""
    return _least(_chunked(lambda t: inputs.scorer.radius_statistics(t)[0].mean(axis=0), theta))


def least_truth_distance(theta: np.ndarray, inputs: SelectionInputs) -> Selection:
    """``mcy``: the least mean distance to the true board points, mm (synthetic sessions only)."""
    truth_points = inputs.truth_points
    if truth_points is None:
        raise ValueError("mcy needs the true board points (synthetic sessions only)")
    return _least(_chunked(lambda t: inputs.scorer.distance_to(t, truth_points), theta))


def _stage_one(theta: np.ndarray, scorer: CandidateScorer) -> tuple[np.ndarray, np.ndarray]:
    """Lower bounds of every candidate and the rows that survive the screen (see module docstring)."""
    n = scorer.n
    ratio = n / (n - 1.0)
    survivors = None
    if theta.shape[1] > FAST_SCREEN_MIN:
        lower, upper = _chunked(scorer.radius_bounds_fast, theta)
        survivors = np.flatnonzero(lower <= upper.min() * (1.0 + 1e-12))
        if len(survivors) > theta.shape[1] // 4:  # single precision cannot separate them (noise-free data)
            survivors = None
    rows = np.arange(theta.shape[1]) if survivors is None else survivors
    mean_r, mean_r2, max_r = _chunked(scorer.radius_statistics, theta[:, rows])
    exact_lower = np.maximum(ratio * mean_r, ratio * mean_r2 / np.maximum(max_r, 1e-300)).mean(axis=0)
    exact_upper = np.minimum(2.0 * mean_r, np.sqrt(2.0 * ratio * mean_r2)).mean(axis=0)
    lower = np.full(theta.shape[1], np.inf) if survivors is None else lower
    lower[rows] = exact_lower
    keep = exact_lower <= exact_upper.min() * (1.0 + 1e-12)
    return lower, rows[keep]


def least_d_back(theta: np.ndarray, inputs: SelectionInputs) -> Selection:
    """``mcb``: the least d_back (eq. 23), mm; the exact minimiser, most candidates only bounded
    (see the module docstring); ``scores`` holds the exact values, NaN for the others."""
    scorer = inputs.scorer
    scores = np.full(theta.shape[1], np.nan)
    # Stage 1: a candidate whose lower bound exceeds some candidate's upper bound cannot win.
    lower, survivors = _stage_one(theta, scorer)
    # Stage 2: a tighter lower bound (1-D projections) for the survivors only.
    if len(survivors) > EXACT_BATCH:
        tight = _chunked(scorer.d_back_lower_bound, theta[:, survivors], CHUNK // 4)
        lower[survivors] = np.maximum(lower[survivors], tight)
    order = survivors[np.argsort(lower[survivors], kind="stable")]
    best_score, best_row, evaluated = np.inf, -1, 0
    for start in range(0, len(order), EXACT_BATCH):
        rows = order[start:start + EXACT_BATCH]
        rows = rows[lower[rows] <= best_score * (1.0 + 1e-12)]
        if len(rows) == 0:
            break
        exact = scorer.d_back(theta[:, rows])
        evaluated += len(rows)
        scores[rows] = exact
        k = int(np.argmin(exact))
        if exact[k] < best_score or (exact[k] == best_score and rows[k] < best_row):
            best_score, best_row = float(exact[k]), int(rows[k])
    return Selection(best_row, best_score, scores, evaluated)
