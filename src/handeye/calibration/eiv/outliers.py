"""Outlier postures of a maximum-likelihood fit: a robust z-score on the Mahalanobis distances,
confirmed by the deleted distance (:func:`deleted_mahalanobis`, an F test with a Bonferroni bound),
and the postures that break the angle invariant (eq. 30) when the fit confirms them; never more
than half of the postures.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import f as f_dist

from ..problem import HandEyeProblem
from .fit import BOUNDARY_PRIOR, MLFit, _jacobians, fit_ml
from .model import Observations
from .start import _compact_residuals


def _outlier_flags(problem: HandEyeProblem, obs: Observations, fit: MLFit, keep: np.ndarray, kinematic: bool,
                   gaps: np.ndarray, gap_flags: np.ndarray) -> np.ndarray:
    """The outlier postures after a fit, shape (n,) of bool.

    The ML's own test decides: the angle-gap and start flags only kept postures out of the start, and
    a posture must also be unlikely under the noise model fitted WITHOUT it (:func:`deleted_mahalanobis`,
    F distribution, Bonferroni over the postures), so small clean sets keep every posture. A posture
    that breaks the X-free angle invariant stays out when the fit confirms it (5 % shared among the
    flagged postures) and its angle gap is also three times what the fitted rotation noise explains:
    the median of |N(0, v_i + v_j)| is 0.674 sqrt(v_i + v_j).
    """
    from ..refine import RESIDUAL_FLOOR_MM, at_most_half, robust_outliers  # noqa: PLC0415

    n = problem.n
    residual_mm = _compact_residuals(problem, fit.x, fit.target)
    level = GAP_CONFIRM_P / max(int(gap_flags.sum()), 1)
    v = np.trace(fit.posture_cov[:, 3:, 3:], axis1=1, axis2=2) / 3.0  # rad² per axis
    expected = np.degrees(0.674 * np.sqrt(v + np.median(v)))
    suspects = robust_outliers(fit.mahalanobis) & (residual_mm > RESIDUAL_FLOOR_MM)
    breaking = gap_flags & (gaps > GAP_CONFIRM_Z * expected) & (residual_mm > RESIDUAL_FLOOR_MM)
    flags = np.zeros(n, bool)
    for i in np.flatnonzero(suspects | breaking):
        d2, nu = deleted_mahalanobis(obs, fit, keep, int(i), kinematic)
        if nu > 0:
            flags[i] = (suspects[i] and d2 > 6.0 * f_dist.ppf(1.0 - OUTLIER_P / n, 6, nu)) or \
                       (breaking[i] and d2 > 6.0 * f_dist.ppf(1.0 - level, 6, nu))
    return at_most_half(flags, fit.mahalanobis)


def deleted_mahalanobis(obs: Observations, fit: MLFit, keep: np.ndarray, i: int, kinematic: bool) -> tuple[float, int]:
    """Posture ``i`` against the fit of the other postures: ``d²_(i)`` and its residual degrees of freedom.

    ``d²_(i) = r_i^T (S_i + J_i C J_i^T)^-1 r_i`` with ``X, T``, the noise levels ``θ`` and ``C`` (the
    covariance of ``X, T``) all from the postures ``keep`` without ``i``: the externally studentised
    distance of regression diagnostics, which an outlier cannot hide by inflating the noise it is
    measured against. The noise levels of this fit carry the boundary-avoiding prior
    (:data:`BOUNDARY_PRIOR`), so that no component the other postures hardly determine is zero.

    With the noise levels estimated from ``ν = 6 n' - 12 - k`` residual degrees of freedom (``n'``
    postures, ``k`` components), ``d²_(i) / 6`` follows an ``F(6, ν)`` distribution (exact for one
    component, Hotelling), not a chi-square: with few postures the estimated noise levels are
    themselves uncertain, and a chi-square test flags clean postures far more often than its level.
    """
    others = np.asarray(keep, bool).copy()
    others[i] = False
    fit = fit_ml(obs, fit.x, fit.target, fit.theta, keep=others, kinematic0=fit.kinematic,
                 kinematic_var0=fit.kinematic_var, kinematic=kinematic, boundary_prior=BOUNDARY_PRIOR)
    jac = _jacobians(obs.subset(np.array([i])))[0, :, :12]
    cov = fit.posture_cov[i] + jac @ fit.covariance @ jac.T
    r = fit.residuals[i]
    return float(r @ np.linalg.solve(cov, r)), int(6 * others.sum() - 12 - len(fit.theta))


#: Probability that a clean posture set loses a posture to the outlier test (chi-square part).
OUTLIER_P = 1e-3


#: Level at which the fit confirms the postures that break the angle invariant (eq. 30), shared
#: among them (Bonferroni).
GAP_CONFIRM_P = 0.05


GAP_CONFIRM_Z = 3.0
