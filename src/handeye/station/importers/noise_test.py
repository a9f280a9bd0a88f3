"""Is one reading of a log worse than another beyond the data's own noise? A paired test per posture.

Two readings of the same numbers fit the X-free invariants with misfits that differ posture by
posture. The best reading's misfits are the noise of the data; another reading is *worse beyond the
noise* when its misfits exceed the best one's, posture by posture, by more than that noise lets
chance explain: a one-sided paired t-test on the per-posture medians (over the posture pairs each
posture is part of) of each misfit (angle gap, axis residual, translation residual), at
:data:`ALPHA` overall (Bonferroni over the three). A reading better than the best in one misfit
is not ruled out by another. Readings that fit identically (the same fit) never differ; with too
few postures nothing is ruled out: "equally well" then means what the data cannot tell apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from ...calibration import posture_medians

__all__ = ["ALPHA", "MISFITS", "NoiseComparison", "posture_misfits", "compare"]

#: The chance, overall, of ruling out a reading that is in truth as good as the best.
ALPHA = 1e-3
#: The misfits compared, in the order of ``InvariantFit.pair_misfits``.
MISFITS = ("angle gap", "axis residual", "translation residual")
MISFIT_UNITS = ("deg", "deg", "mm")
#: Fewer postures with a measured misfit than this: the test does not rule out.
MIN_POSTURES = 4


def posture_misfits(fit, n: int) -> np.ndarray:
    """Per posture, the median of each misfit over the usable pairs it is part of: shape ``(n, 3)``
    (NaN for a posture in no usable pair)."""
    pairs, values = np.asarray(fit.misfit_pairs), np.asarray(fit.pair_misfits, float)
    if len(pairs) == 0:
        return np.full((n, len(MISFITS)), np.nan)
    return np.stack([posture_medians(values[:, k], pairs, n) for k in range(len(MISFITS))], axis=1)


@dataclass(frozen=True)
class NoiseComparison:
    """The outcome of :func:`compare`: ``worse`` beyond the noise, the p-values and the words."""

    worse: bool
    p_worse: tuple
    p_better: tuple
    words: str


def _one_sided(d: np.ndarray) -> tuple[float, float]:
    """``(p that the mean of d is > 0, p that it is < 0)`` of a paired t-test (1.0 when undecidable)."""
    d = d[np.isfinite(d)]
    if len(d) < MIN_POSTURES or not np.any(d):
        return 1.0, 1.0
    mean, sd = float(np.mean(d)), float(np.std(d, ddof=1))
    if sd == 0.0:
        return (0.0, 1.0) if mean > 0 else (1.0, 0.0)
    t = mean / (sd / np.sqrt(len(d)))
    return float(stats.t.sf(t, len(d) - 1)), float(stats.t.cdf(t, len(d) - 1))


def compare(candidate: np.ndarray, best: np.ndarray) -> NoiseComparison:
    """Is ``candidate`` worse than ``best`` beyond the noise?

    Parameters
    ----------
    candidate, best : ndarray, shape (n, 3)
        :func:`posture_misfits` of the two readings (the same postures).

    Returns
    -------
    NoiseComparison
        ``worse`` when one misfit is larger beyond the noise (p < ALPHA / 3) and none is smaller.
    """
    level = ALPHA / len(MISFITS)
    p = [_one_sided(np.asarray(candidate, float)[:, k] - np.asarray(best, float)[:, k]) for k in range(len(MISFITS))]
    p_worse, p_better = tuple(v[0] for v in p), tuple(v[1] for v in p)
    worse = min(p_worse) < level and min(p_better) >= level
    k = int(np.argmin(p_worse))
    d = np.asarray(candidate, float)[:, k] - np.asarray(best, float)[:, k]
    diff = float(np.median(d[np.isfinite(d)])) if np.isfinite(d).any() else float("nan")
    words = (f"{MISFITS[k]} beyond the noise of the best reading (posture by posture {diff:.2g} {MISFIT_UNITS[k]} "
             f"more, p = {p_worse[k]:.1e})")
    return NoiseComparison(worse, p_worse, p_better, words)
