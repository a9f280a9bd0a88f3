"""The board's rotation centre of sessions of board poses only.

A board pose measured by one camera is best determined at the middle of what the camera sees, so
its tilt turns the board about that point and moves a corner origin with it (``ρ = ρ_c + c x φ``):
the point ``c`` (board frame) is found by restricted maximum likelihood (:func:`board_centre`) and
kept when the likelihood ratio exceeds :data:`CENTRE_LR` (chi-square, 3 degrees of freedom,
p = 0.001), so poses whose rotation and position errors are independent keep the origin model.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from ..noise import skew
from .fit import MLFit, _jacobians, _structures, _sum_t, fit_ml
from .model import Observations


#: Board-frame rotation components of sessions of board poses, per unit variance about the board origin.
_ROTATION_BASES = {"camera_tilt": np.diag([0.0, 0.0, 0.0, 1.0, 1.0, 0.0]), "camera_spin": np.diag([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])}


#: Likelihood ratio above which the board's rotation noise is modelled about a fitted centre (chi-square,
#: 3 degrees of freedom, p = 0.001).
CENTRE_LR = 16.27


#: Lower bound of the variances while the centre is searched (mm², rad²): keeps every ``S_i`` invertible.
CENTRE_THETA_FLOOR = 1e-12


#: The centre search of a larger session runs on this many of its postures, evenly spread in capture
#: order (the fits that follow use them all): its cost no longer grows with a stream's length.
CENTRE_POSTURES = 2000


def _lever(centre) -> np.ndarray:
    """``[[I, [c]x], [0, I]]``: a twist about the board point ``c`` as a twist about the board origin."""
    out = np.eye(6)
    out[:3, 3:] = skew(np.asarray(centre, float))
    return out


def centred(obs: "Observations", centre: ArrayLike) -> "Observations":
    """Observations whose board rotation noise (tilt, spin) turns the board about the board point ``centre``.

    A board pose measured by one camera is best determined at the middle of what the camera sees:
    its tilt error turns the board about that point, so the board origin (a corner) moves with the
    tilt, ``ρ = ρ_c + c x φ``. ``centre`` is that point in the board frame (mm).
    """
    lever = _lever(centre)
    comps = tuple(replace(c, structure=np.broadcast_to(lever @ _ROTATION_BASES[c.name] @ lever.T, (obs.n, 6, 6)).copy())
                  if c.side == "board" and c.name in _ROTATION_BASES else c for c in obs.components)
    return replace(obs, components=comps, notes={**obs.notes, "camera_centre_mm": np.asarray(centre, float)})


def _centre_nll(params, r, jac, g, rotation) -> tuple[float, np.ndarray]:
    """Minus the restricted log-likelihood at fixed ``X, T`` (constants dropped) of the variance
    components ``θ = CENTRE_THETA_FLOOR + exp(params[3:])`` (never below the floor, so every ``S_i``
    stays invertible), the board rotation components about the centre ``params[:3]``, and its
    gradient: ``½ (tr(W D) - tr(M C^T W D W C) - r^T W D W r)`` for ``D = dS/dp``."""
    lever = _lever(params[:3])
    with np.errstate(over="ignore"):  # a trial step of the optimiser far out: an infinite cost
        scale = np.exp(params[3:])
    if not np.all(np.isfinite(scale)):
        return float("inf"), np.zeros(len(params))
    theta = CENTRE_THETA_FLOOR + scale
    moved = np.array([lever @ gk @ lever.T if about else gk for gk, about in zip(g, rotation)])
    s = np.tensordot(theta, moved, axes=1)
    sign, logdet = np.linalg.slogdet(s)
    if np.any(sign <= 0):
        return float("inf"), np.zeros(len(params))
    w = np.linalg.inv(s)
    wj = w @ jac
    normal = _sum_t(jac, wj)
    sign_m, logdet_m = np.linalg.slogdet(normal)
    if sign_m <= 0:
        return float("inf"), np.zeros(len(params))
    wr = (w @ r[..., None])[..., 0]
    # every derivative D of S enters as sum_i <P_i, D_i>, P_i = W_i - (W C M C^T W)_i - W_i r_i r_i^T W_i
    p = w - wj @ np.linalg.inv(normal) @ np.swapaxes(wj, 1, 2) - wr[:, :, None] * wr[:, None, :]
    grad = np.empty(len(params))
    grad[3:] = (moved.reshape(len(moved), -1) @ p.reshape(-1)) * scale  # d / d params[3 + k]
    # d / dc_a: dS = sum_k θ_k (E_a G_k L^T + L G_k E_a^T), E_a = dL/dc_a, so <P, dS> = 2 <E_a, sum θ_k P L G_k>
    plg = np.sum(p @ lever @ np.tensordot(theta[rotation], g[rotation], axes=1), axis=0)
    grad[:3] = 2.0 * np.array([np.sum(skew(np.eye(3)[a]) * plg[:3, 3:]) for a in range(3)])
    value = 0.5 * float(np.sum(logdet) + logdet_m + np.einsum("ni,ni->", r, wr))
    return value, 0.5 * grad


def board_centre(obs: "Observations", fit: "MLFit", keep: ArrayLike, start: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The board point about which the board's rotation noise acts, by restricted maximum likelihood.

    ``obs`` holds the rotation components about the board origin; the residuals of ``fit`` (its
    ``X, T``) are held, the centre and the variance components (bounded below by
    :data:`CENTRE_THETA_FLOOR`) searched together (BFGS), over at most :data:`CENTRE_POSTURES` of
    the postures ``keep``. Returns the centre (mm) and the variance components, ``None`` when the
    search fails.
    """
    from scipy.optimize import minimize  # noqa: PLC0415

    keep = np.asarray(keep, bool)
    if keep.sum() > CENTRE_POSTURES:
        kept = np.flatnonzero(keep)
        keep = np.zeros_like(keep)
        keep[kept[np.linspace(0, len(kept) - 1, CENTRE_POSTURES).round().astype(int)]] = True
    sub = obs.subset(keep)
    rotation = np.array([c.side == "board" and c.name in _ROTATION_BASES for c in sub.components])
    start_theta = np.log(np.maximum(fit.theta - CENTRE_THETA_FLOOR, CENTRE_THETA_FLOOR))
    try:
        found = minimize(_centre_nll, np.concatenate([start, start_theta]), method="BFGS", jac=True,
                         args=(fit.residuals[keep], _jacobians(sub), _structures(sub, fit.x), rotation))
    except (np.linalg.LinAlgError, ValueError):
        return None
    if not (np.all(np.isfinite(found.x)) and np.isfinite(found.fun)):
        return None
    return found.x[:3], CENTRE_THETA_FLOOR + np.exp(found.x[3:])


def _centred_fit(obs: "Observations", centre, current: "MLFit", theta0, keep, kinematic: bool, fit: "MLFit"):
    """The ML fit about ``centre`` from the variance start ``theta0`` (``None``: the usual start), or
    ``None`` when it breaks down: on a few postures a start from the centre search can send a variance
    component off to infinity (the posture covariances become singular); that start is then no candidate."""
    try:
        found = fit_ml(centred(obs, centre), current.x, current.target, theta0, keep=keep, kinematic=kinematic,
                       kinematic0=fit.kinematic, kinematic_var0=fit.kinematic_var)
    except np.linalg.LinAlgError:
        return None
    return found if np.isfinite(found.loglik) and np.all(np.isfinite(found.theta)) else None


def _centre_test(obs: Observations, fit: MLFit, keep: np.ndarray, kinematic: bool) -> tuple[Observations, MLFit, dict]:
    """Board rotation noise about a fitted centre (sessions of board poses), kept when the likelihood
    ratio of the restricted likelihoods exceeds :data:`CENTRE_LR`; the centre and the fit are found
    alternately (twice). Returns the observations and the fit to go on with, and the report."""
    rotation = [c.name for c in obs.components if c.side == "board" and c.name in _ROTATION_BASES]
    if obs.mode != "poses" or not rotation or 6 * int(np.sum(keep)) - 12 <= len(obs.components) + 3:
        return obs, fit, {"modelled": False, "reason": "board poses fitted to corners, or too few postures"}
    centre, current = np.zeros(3), fit
    for _ in range(2):
        found = board_centre(obs, current, keep, centre)
        if found is None:
            break
        centre = found[0]
        # the restricted likelihood can have more than one maximum (a component pinned at its floor):
        # from the search's components and from the usual start of every fit, the higher one
        fits = [_centred_fit(obs, centre, current, theta0, keep, kinematic, fit) for theta0 in (found[1], None)]
        fits = [f for f in fits if f is not None]
        if not fits:
            break
        current = max(fits, key=lambda f: f.loglik)
    lr = 2.0 * (current.loglik - fit.loglik)
    report = {"modelled": bool(lr > CENTRE_LR), "likelihood_ratio": float(lr), "threshold": CENTRE_LR}
    if not report["modelled"]:
        return obs, fit, report
    report["centre_mm"] = [float(v) for v in centre]
    return centred(obs, centre), current, report
