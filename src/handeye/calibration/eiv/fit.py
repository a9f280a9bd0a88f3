"""The maximum-likelihood fit over a set of postures: Gauss-Newton on ``X, T`` (and the arm's
kinematic deviations ``u`` as random effects) alternated with restricted maximum likelihood of the
variance components (Fisher scoring, an EM step at the boundary).

Minimises ``sum_i r_i^T S_i^-1 r_i`` with ``r_i = twist(T^-1 A_i X B_i)`` and
``S_i = Ad_i C_A,i Ad_i^T + C_B,i`` (the package docstring; ``dr/dδx = Ad_{B_i^-1}``,
``dr/dδt = -I``); :func:`fit_ml` returns an :class:`MLFit`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ..noise import VARIANCE_FLOOR, adjoint, retract, twist_between
from ...geometry import invert_transforms
from .model import Observations


#: Gauss-Newton stops when the step is below these (mm, rad).
STEP_TOL_MM = 1e-7


STEP_TOL_RAD = 1e-10


MAX_OUTER = 40


#: Largest relative change of the variance components counted as converged.
THETA_TOL = 1e-3


@dataclass(frozen=True)
class MLFit:
    """The ML solution over a set of postures.

    Attributes
    ----------
    x, target : ndarray, shape (4, 4)
        ``X`` and ``T`` (the board in the fixed frame).
    theta : ndarray, shape (k,)
        Variance components, in the order of ``Observations.components``.
    kinematic : ndarray, shape (q,)
        Estimated deviations of the robot's DH table (empty without a robot model).
    kinematic_var : ndarray, shape (2,)
        Their variance components: lengths (mm²) and angles (deg²).
    covariance : ndarray, shape (12, 12)
        Of the local twists ``(δx, δt)`` of ``X ⊕ δx``, ``T ⊕ δt`` (mm, rad), the kinematic
        deviations marginalised.
    residuals : ndarray, shape (n, 6)
        ``r_i`` of every posture of the observations (also those left out of the fit), kinematic
        deviations applied.
    mahalanobis : ndarray, shape (n,)
        ``d_i``.
    posture_cov : ndarray, shape (n, 6, 6)
        ``S_i``.
    iterations : int
    converged : bool
    loglik : float
        Restricted (REML) log-likelihood at the solution, for comparing noise models with the same
        fixed parameters ``X, T``.
    """

    x: np.ndarray
    target: np.ndarray
    theta: np.ndarray
    kinematic: np.ndarray
    kinematic_var: np.ndarray
    covariance: np.ndarray
    residuals: np.ndarray
    mahalanobis: np.ndarray
    posture_cov: np.ndarray
    iterations: int
    converged: bool
    loglik: float = float("nan")


def _residuals(obs: Observations, x, t, u=None, ju=None) -> np.ndarray:
    """``r_i = twist(T^-1 (A_i ⊕ K_i u) X B_i)`` to first order in ``u``; ``(n, 6)``."""
    r = twist_between(t, obs.hand @ x @ obs.board)
    if u is not None and len(u):
        r = r + ju @ u
    return r


def _jacobians(obs: Observations, ju=None) -> np.ndarray:
    """``d r / d(δx, δt, u)``: ``Ad_{B^-1}``, ``-I`` and ``Ad_{(X B)^-1} K_i``; ``(n, 6, 12 + q)``."""
    q = 0 if ju is None else ju.shape[2]
    jac = np.zeros((obs.n, 6, 12 + q))
    jac[:, :, :6] = adjoint(invert_transforms(obs.board))
    jac[:, :, 6:12] = -np.eye(6)
    if q:
        jac[:, :, 12:] = ju
    return jac


def _to_residual_frame(obs: Observations, x) -> np.ndarray:
    return adjoint(invert_transforms(x[None] @ obs.board))  # Ad_{(X B_i)^-1}


def _structures(obs: Observations, x) -> np.ndarray:
    """``G_ik`` in the residual frame, shape ``(k, n, 6, 6)``."""
    if not obs.components:
        return np.zeros((0, obs.n, 6, 6))
    ad = _to_residual_frame(obs, x)
    out = []
    for comp in obs.components:
        g = comp.structure
        out.append(ad @ g @ np.swapaxes(ad, 1, 2) if comp.side == "hand" else g)
    return np.array(out)


def _kinematic_jac(obs: Observations, x) -> np.ndarray | None:
    if obs.kinematic is None:
        return None
    return _to_residual_frame(obs, x) @ obs.kinematic


def _posture_cov(obs: Observations, g: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``S_i = F_i + sum_k θ_k G_ik``; ``(n, 6, 6)``."""
    s = obs.board_cov.copy()
    for value, structure in zip(theta, g):
        s += value * structure
    return 0.5 * (s + np.swapaxes(s, 1, 2))


def _prior(obs: Observations, lam: np.ndarray) -> np.ndarray:
    """Prior precision of ``(δx, δt, u)``: none on ``X, T``; ``Λ^-1`` on the DH deviations."""
    q = 0 if obs.kinematic is None else obs.kinematic.shape[2]
    prior = np.zeros((12 + q, 12 + q))
    if q:
        prior[12:, 12:] = np.diag(1.0 / lam[obs.kinematic_kinds])
    return prior


def _initial_theta(obs: Observations, g: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Each component alone explaining its share of the residual, block by block (rotation, translation)."""
    k = len(g)
    if k == 0:
        return np.zeros(0)
    excess = np.maximum(np.einsum("ni,nj->nij", r, r) - obs.board_cov, 0.0)
    theta = np.empty(k)
    for c in range(k):
        ratios = []
        for block in (slice(0, 3), slice(3, 6)):
            trace_g = np.trace(g[c][:, block, block], axis1=1, axis2=2).sum()
            if trace_g > 0:
                ratios.append(np.trace(excess[:, block, block], axis1=1, axis2=2).sum() / trace_g)
        theta[c] = max(min(ratios) / k, VARIANCE_FLOOR) if ratios else VARIANCE_FLOOR
    return theta


def _sum_t(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``sum_n a_n^T b_n`` for stacks ``(..., n, r, p)`` and ``(..., n, r, s)``: ``(..., p, s)``.

    Small per-posture products summed, rather than one tall matrix product: a tall product goes
    to a multi-threaded BLAS, which stalls when the machine's cores are busy.
    """
    return (np.swapaxes(a, -1, -2) @ b).sum(axis=-3)


def _normal(jac: np.ndarray, w: np.ndarray, prior: np.ndarray) -> np.ndarray:
    return _sum_t(jac, w @ jac) + prior


def _gauss_newton(obs: Observations, x, t, u, w: np.ndarray, prior: np.ndarray, steps: int):
    """Gauss-Newton on ``sum_i ρ_i^T W_i ρ_i + u^T Λ^-1 u``, ``ρ_i = r_i + J_u,i u`` (mixed-model equations)."""
    step = np.zeros(12)
    for _ in range(steps):
        ju = _kinematic_jac(obs, x)
        jac = _jacobians(obs, ju)
        rho = _residuals(obs, x, t, u, ju)
        p = jac.shape[2]
        wj = w @ jac
        normal = _sum_t(jac, wj) + prior
        grad = _sum_t(wj, rho[..., None])[:, 0]
        if p > 12:
            grad = grad + prior[:, 12:] @ u
        step = -np.linalg.solve(normal, grad)
        x = retract(x, step[:6])
        t = retract(t, step[6:12])
        u = u + step[12:]
        if _small(step):
            break
    return x, t, u, step


def _small(step) -> bool:
    return bool(np.all(np.abs(step[[0, 1, 2, 6, 7, 8]]) < STEP_TOL_MM) and np.all(np.abs(step[[3, 4, 5, 9, 10, 11]]) < STEP_TOL_RAD)
                and np.all(np.abs(step[12:]) < STEP_TOL_MM))


def _reml_score_information(g, wg, wj, a, m, quad, tr_pg, weight, theta, lam, u, kinds, kinds_present, pz, ztpz):
    """Score and Fisher information of the restricted likelihood in ``(θ, λ[kinds_present])``.

    The terms of :func:`_variance_step` (Henderson's form): ``½ (ρ^T S^-1 G_k S^-1 ρ - tr(P G_k))`` and
    ``½ (û_c^T û_c / λ_c² - tr(Z_c^T P Z_c))`` for the scores, ``½ tr(P V_a P V_b)`` for the information,
    with the boundary-avoiding prior's terms on the block components (``weight``).

    Returns
    -------
    score : ndarray, shape (k + c,)
    info : ndarray, shape (k + c, k + c)
    """
    k = len(theta)
    size = k + len(kinds_present)
    score = np.empty(size)
    info = np.empty((size, size))
    score[:k] = 0.5 * (quad - tr_pg) + 0.5 * weight / theta  # with the boundary-avoiding prior's score
    for i in range(k):
        for j in range(i, k):
            term1 = np.sum(wg[i] * np.swapaxes(wg[j], 1, 2))
            b = _sum_t(wj, g[i] @ (wg[j] @ wj))  # C^T S^-1 G_i S^-1 G_j S^-1 C
            term2 = np.trace(m @ b)
            term3 = np.trace(m @ a[i] @ m @ a[j])
            info[i, j] = info[j, i] = 0.5 * (term1 - 2.0 * term2 + term3)
        info[i, i] += 0.5 * weight[i] / theta[i] ** 2
    for ci, c in enumerate(kinds_present):
        sel = kinds == c
        score[k + ci] = 0.5 * (np.sum(u[sel] ** 2) / lam[c] ** 2 - np.trace(ztpz[np.ix_(sel, sel)]))
        for i in range(k):  # ½ tr(Z_c^T P G_i P Z_c)
            info[i, k + ci] = info[k + ci, i] = 0.5 * np.sum(pz[:, :, sel] * (g[i] @ pz[:, :, sel]))
        for di, d in enumerate(kinds_present):
            info[k + ci, k + di] = 0.5 * np.sum(ztpz[np.ix_(sel, kinds == d)] ** 2)
    return score, info


def _variance_step(g: np.ndarray, w: np.ndarray, theta: np.ndarray, rho: np.ndarray, jac: np.ndarray,
                   prior: np.ndarray, u: np.ndarray, lam: np.ndarray, kinds, fisher_scoring: bool,
                   boundary_prior: float = 0.0):
    """One REML update of the block components ``θ`` and the DH-deviation variances ``λ``, jointly.

    Henderson's mixed-model form: with ``C = [J_X, J_T, Z]`` (``Z = J_u``), ``M = (C^T S^-1 C + Π)^-1``
    (``Π`` the prior precision ``Λ^-1`` of the DH deviations), ``P = S^-1 - S^-1 C M C^T S^-1`` and
    ``P y = S^-1 ρ``, ``Z^T P y = Λ^-1 û``. Scores: ``½ (ρ^T S^-1 G_k S^-1 ρ - tr(P G_k))`` for a block
    component, ``½ (û_c^T û_c / λ_c² - tr(Z_c^T P Z_c))`` for a kind of DH entry; the information is
    ``½ tr(P V_a P V_b)`` for every pair (``V = G_k`` or ``Z_c Z_c^T``), all reduced to per-posture
    6x6 products and ``(12 + q)``-square sums. The first iterations take the positive fixed point
    (EM), then scale-free Fisher scoring with an active set at zero.

    Returns
    -------
    theta, lam : ndarray
    m : ndarray, shape (12 + q, 12 + q)
        ``M`` at the current values.
    """
    k = len(theta)
    p = jac.shape[2]
    q = p - 12
    wj = w @ jac                                      # (n, 6, p)
    m = np.linalg.inv(_sum_t(jac, wj) + prior)
    kinds_present = [c for c in range(len(lam)) if q and np.any(kinds == c)]
    if k == 0 and not kinds_present:
        return theta, lam, m
    wg = w[None] @ g                                  # S^-1 G_k, (k, n, 6, 6)
    wr = w @ rho[..., None]                           # (n, 6, 1)
    quad = np.sum((g @ wr[None]) * wr[None], axis=(1, 2, 3))
    gwj = g @ wj[None]                                # G_k S^-1 C, (k, n, 6, p)
    a = _sum_t(wj[None], gwj)                         # C^T S^-1 G_k S^-1 C, (k, p, p)
    tr_wg = np.trace(wg, axis1=2, axis2=3).sum(axis=1)  # tr(S^-1 G_k)
    tr_pg = tr_wg - np.sum(m[None] * np.swapaxes(a, 1, 2), axis=(1, 2))
    # A component whose effect the fixed parameters absorb (tr(P G) ~ 0 against tr(S^-1 G)) gets no
    # information from the restricted likelihood: it keeps its value, and the prior (improper,
    # rate -> 0) is not applied to it, as it would push it up without bound.
    informed = tr_pg > 1e-9 * tr_wg
    weight = np.where(informed, boundary_prior, 0.0)
    if q:
        z = jac[:, :, 12:]
        pz = w @ z - wj @ (m @ _sum_t(jac, w @ z))   # P Z, per posture (n, 6, q)
        ztpz = _sum_t(z, pz)                          # Z^T P Z, (q, q)
    if not fisher_scoring:
        return (*_em_update(theta, quad, tr_pg, weight, informed, lam, u, m, kinds, kinds_present), m)
    score, info = _reml_score_information(g, wg, wj, a, m, quad, tr_pg, weight, theta, lam, u, kinds, kinds_present,
                                          pz if q else None, ztpz if q else None)
    size = len(score)
    values = np.concatenate([theta, lam[kinds_present]])
    if not (np.all(np.isfinite(score)) and np.all(np.isfinite(info))):  # noise-free data: nothing to learn
        return theta, lam, m
    # scale-free step: in relative units δv / v; components pinned at the floor with a negative score
    # left out (active set); a component driven below zero stops at a hundredth of its value
    active = ~((values <= 10.0 * VARIANCE_FLOOR) & (score <= 0.0))
    rel = np.zeros(size)
    if active.any():
        scaled = info[np.ix_(active, active)] * np.outer(values[active], values[active])
        rhs = values[active] * score[active]
        if not (np.all(np.isfinite(scaled)) and np.all(np.isfinite(rhs))):
            return theta, lam, m
        rel[active] = np.linalg.lstsq(scaled, rhs, rcond=1e-12)[0]
    values = np.maximum(values * (1.0 + np.maximum(rel, -0.99)), VARIANCE_FLOOR)
    new_lam = lam.copy()
    new_lam[kinds_present] = values[k:]
    return values[:k], new_lam, m


#: Weight of the boundary-avoiding prior on the variance components in the outlier test's fits:
#: ``log p(σ_k) = BOUNDARY_PRIOR log σ_k``, a gamma(2, rate -> 0) prior on each standard deviation
#: (Chung, Rabe-Hesketh, Dorie, Gelman and Liu, Psychometrika 78, 2013), i.e. the restricted likelihood
#: plus ``½ BOUNDARY_PRIOR log θ_k``. With few postures a component the data hardly determine is
#: otherwise estimated at exactly zero (18 of 60 clean six-pose sets of OpenCV's model), and a
#: posture is then tested against a covariance that calls its ordinary error in that direction
#: impossible. The estimate of ``X`` keeps the plain restricted likelihood: where a noise source is
#: truly absent (a simulated robot without noise) the prior's pull off zero costs accuracy.
BOUNDARY_PRIOR = 1.0


def _em_update(theta, quad, tr_pg, weight, informed, lam, u, m, kinds, kinds_present) -> tuple[np.ndarray, np.ndarray]:
    """The EM (positive fixed point) update of the block components and the DH-deviation variances.

    Block components: the fixed point of the score ``½ (quad - tr(P G)) + weight / (2 θ)``; the
    components the restricted likelihood does not inform keep their values.
    """
    new_theta = np.where(informed, (theta * quad + weight) / np.where(informed, tr_pg, 1.0), theta)
    new_lam = lam.copy()
    for c in kinds_present:
        sel = kinds == c
        m_uu = m[12:, 12:][np.ix_(sel, sel)]
        new_lam[c] = max((np.sum(u[sel] ** 2) + np.trace(m_uu)) / sel.sum(), VARIANCE_FLOOR)
    return np.maximum(new_theta, VARIANCE_FLOOR), new_lam


#: Start of the DH-deviation variances (mm², deg²): a start for EM, which takes it from here.
KINEMATIC_START = np.array([0.1**2, 0.01**2])


def _damped(theta, lam, new, new_lam, last_delta):
    """The variance step, damped: alternating with the fit, confounded components can overshoot back
    and forth, so a component's step is halved when it turns against the previous one. Returns the
    new ``theta``, the new kinematic variances and the step taken."""
    delta = np.concatenate([new - theta, new_lam - lam])
    flip = delta * last_delta < 0
    if flip.any():
        delta = np.where(flip, 0.5 * delta, delta)
        new, new_lam = theta + delta[:len(theta)], lam + delta[len(theta):]
    return new, new_lam, delta


def fit_ml(obs: Observations, x0: np.ndarray, t0: np.ndarray | None = None, theta0: np.ndarray | None = None,
           estimate_theta: bool = True, keep: ArrayLike | None = None, kinematic0: ArrayLike | None = None, kinematic_var0: ArrayLike | None = None,
           kinematic: bool = True, boundary_prior: float = 0.0) -> MLFit:
    """The ML solution over the postures ``keep`` (default all), from a start ``x0``.

    Parameters
    ----------
    obs : Observations
    x0 : ndarray, shape (4, 4)
    t0 : ndarray, shape (4, 4), optional
        Start for ``T``; default :func:`initial_board_pose`.
    theta0 : ndarray, shape (k,), optional
        Start (or, with ``estimate_theta=False``, fixed values) of the variance components.
    keep : array-like of bool, shape (n,), optional
        Postures taking part; residuals and ``d_i`` are returned for all.
    kinematic0, kinematic_var0 : ndarray, optional
        Start of the DH deviations and (fixed with ``estimate_theta=False``) of their variances.
    kinematic : bool
        Model the arm's DH deviations (when the observations have them); ``False``: the robot's
        errors are independent from posture to posture.
    boundary_prior : float
        Weight of the boundary-avoiding prior on the variance components (:data:`BOUNDARY_PRIOR`);
        0, the default, is the plain restricted likelihood.
    """
    keep = np.ones(obs.n, bool) if keep is None else np.asarray(keep, bool)
    if not kinematic and obs.kinematic is not None:
        obs = replace(obs, kinematic=None, kinematic_kinds=None)
    sub = obs.subset(keep)
    q = 0 if sub.kinematic is None else sub.kinematic.shape[2]
    x = np.array(x0, float)
    t = initial_board_pose(sub, x) if t0 is None else np.array(t0, float)
    u = np.zeros(q) if kinematic0 is None or q == 0 else np.array(kinematic0, float)
    lam = KINEMATIC_START.copy() if kinematic_var0 is None else np.array(kinematic_var0, float)
    prior = _prior(sub, lam)
    g = _structures(sub, x)
    if theta0 is None:  # rough weights (1 mm, 1 mrad) for a first fit, then a start per component
        w0 = np.linalg.inv(_posture_cov(sub, g, np.zeros(len(g))) + _unit_floor())
        x, t, u, _ = _gauss_newton(sub, x, t, u, w0, prior, 3)
        theta = _initial_theta(sub, g, _residuals(sub, x, t, u, _kinematic_jac(sub, x)))
    else:
        theta = np.array(theta0, float)
    converged = False
    outer = 0
    last_delta = np.zeros(len(theta) + len(lam))
    for outer in range(1, MAX_OUTER + 1):
        g = _structures(sub, x)
        w = np.linalg.inv(_posture_cov(sub, g, theta))
        x, t, u, step = _gauss_newton(sub, x, t, u, w, prior, 2)
        if not estimate_theta or (len(theta) == 0 and q == 0):
            if _small(step):
                converged = True
                break
            continue
        ju = _kinematic_jac(sub, x)
        jac = _jacobians(sub, ju)
        rho = _residuals(sub, x, t, u, ju)
        new, new_lam, _ = _variance_step(g, w, theta, rho, jac, prior, u, lam, sub.kinematic_kinds,
                                         fisher_scoring=outer > 3, boundary_prior=boundary_prior)
        new, new_lam, last_delta = _damped(theta, lam, new, new_lam, last_delta)
        change = np.max(np.abs(new - theta) / np.maximum(theta, VARIANCE_FLOOR)) if len(theta) else 0.0
        if q:
            change = max(change, np.max(np.abs(new_lam - lam) / lam))
            lam = new_lam
            prior = _prior(sub, lam)
        theta = new
        if change < THETA_TOL and _small(step):
            converged = True
            break
    return _finished_fit(obs, sub, x, t, u, theta, lam, prior, outer, converged)


def _finished_fit(obs: Observations, sub: Observations, x, t, u, theta, lam, prior, outer: int,
                  converged: bool) -> MLFit:
    """The :class:`MLFit` of a converged fit over ``sub``: the covariance of X, the REML
    log-likelihood, and residuals with Mahalanobis distances for every posture of ``obs``."""
    g = _structures(sub, x)
    s = _posture_cov(sub, g, theta)
    ju = _kinematic_jac(sub, x)
    jac = _jacobians(sub, ju)
    w = np.linalg.inv(s)
    mme = _normal(jac, w, prior)
    cov = np.linalg.inv(mme)[:12, :12]
    loglik = _reml_loglik(sub, s, w, mme, _residuals(sub, x, t, u, ju), u, lam)
    g_all = _structures(obs, x)
    s_all = _posture_cov(obs, g_all, theta)
    r_all = _residuals(obs, x, t, u, _kinematic_jac(obs, x))
    d = np.sqrt(np.maximum(np.einsum("ni,ni->n", r_all, np.linalg.solve(s_all, r_all[..., None])[..., 0]), 0.0))
    return MLFit(x, t, theta, u, lam, 0.5 * (cov + cov.T), r_all, d, s_all, outer, converged, loglik)


def _reml_loglik(obs: Observations, s, w, mme, rho, u, lam) -> float:
    """``-½ (log det R + log det Λ + log det MME + ρ^T R^-1 ρ + u^T Λ^-1 u)``, constants dropped.

    The restricted likelihood of the mixed model in Henderson's form: ``R`` the block-diagonal
    posture covariances, ``Λ`` the DH-deviation variances, ``MME = C^T R^-1 C + Π``.
    """
    logdet_r = float(np.sum(np.linalg.slogdet(s)[1]))
    logdet_m = float(np.linalg.slogdet(mme)[1])
    quad = float(np.einsum("ni,nij,nj->", rho, w, rho))
    logdet_l = 0.0
    if obs.kinematic is not None and len(u):
        var = lam[obs.kinematic_kinds]
        logdet_l = float(np.sum(np.log(var)))
        quad += float(np.sum(u * u / var))
    return -0.5 * (logdet_r + logdet_l + logdet_m + quad)


def _unit_floor() -> np.ndarray:
    return np.diag([1.0, 1.0, 1.0, 1e-6, 1e-6, 1e-6])  # 1 mm and 1 mrad: the start's weights only


def initial_board_pose(obs: Observations, x: np.ndarray) -> np.ndarray:
    """``T`` from ``X``: the chordal mean of ``A_i X B_i`` (rotation by SVD, translation by the mean)."""
    chain = obs.hand @ x @ obs.board
    u, _, vt = np.linalg.svd(chain[:, :3, :3].mean(axis=0))
    rot = u @ vt
    if np.linalg.det(rot) < 0:
        rot = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = chain[:, :3, 3].mean(axis=0)
    return out
