"""Identify the arm's kinematic deviations with the camera pose and the board (``calibrate --kinematics``).

The default estimator (``eiv``) fits ``A_i X B_i = T`` with the arm's errors as noise. Here the arm's
deviations ``u`` from its DH table (:mod:`~handeye.calibration.arm_parameters`: ``d_i, a_i, alpha_i``
and the controller zero of every axis) are fixed effects with a Gaussian prior from the robot file,
estimated together with ``X`` and ``T``: the residual of posture ``i`` becomes (to first order in ``u``)

    r_i = twist(T^-1 A_i X B_i) + Ad_{(X B_i)^-1} K_i u,       u ~ N(0, diag(prior²)),

minimised as ``sum_i r_i^T S_i^-1 r_i + u^T P^-1 u`` by Gauss-Newton, alternated with the restricted
maximum likelihood of the noise components of ``S_i`` (the same machinery, ``eiv.fit``), so the
noise the arm's errors inflated in the camera-only fit shrinks back to the arm's repeatability.

Identifiability, from the whitened Jacobian at the data's postures (columns scaled by the prior):
a parameter whose column the camera and board poses reproduce exactly is **absorbed** (never seen:
``zero1``, ``d1``, ``zero6``, ``d6``, ``a6``, ``alpha6`` on any arm; the words in
``arm_parameters.ABSORBED``); one that a combination of the parameters taken before it and of the
poses reproduces is **degenerate** (``d3`` with ``d2`` on an arm whose axes 2 and 3 are parallel:
only their sum is seen), named with its partners. Both are left out of the fit (the poses absorb
them). The rest is fitted; a parameter whose posterior one-sigma is more than
:data:`WEAK_FRACTION` of its prior (the data hardly add to what the robot file already says) is
**weak**: kept in the model, never reported as a value.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .arm_parameters import parameter_jacobian, parameter_kinds, parameter_names, robot_prior, why_absorbed
from .eiv.fit import (
    MAX_OUTER,
    THETA_TOL,
    _damped,
    _gauss_newton,
    _jacobians,
    _kinematic_jac,
    _normal,
    _posture_cov,
    _residuals,
    _small,
    _structures,
    _variance_step,
)
from .eiv.model import Observations
from .noise import VARIANCE_FLOOR

__all__ = ["WEAK_FRACTION", "ArmIdentification", "identify_arm", "fit_arm"]

#: A fitted parameter is reported only when its one-sigma is at most this fraction of its prior.
WEAK_FRACTION = 0.5

#: Relative size of what is left of a parameter's whitened column after the poses (and the parameters
#: taken before it) explain it, below which the data cannot see it. Not rounding level: the pose
#: Jacobians are taken at the fit, where the residuals (noise, the arm's errors) are ~1e-4 of the
#: poses, so an exactly absorbed column keeps that much.
ABSORBED_TOL = 2e-3


@dataclass(frozen=True)
class ArmIdentification:
    """The arm's identified deviations with the camera and board poses.

    Attributes
    ----------
    names : list of str, length p
        All parameters (``arm_parameters.parameter_names``).
    values, sigma : ndarray, shape (p,)
        Estimate and posterior one-sigma (mm or deg); 0 and nan for those left out.
    prior_sigma : ndarray, shape (p,)
    status : list of str, length p
        ``identified``, ``weak``, ``absorbed`` or ``degenerate``.
    reasons : dict of str to str
        Words for every parameter that is not ``identified``.
    fitted : ndarray of int, shape (q,)
        Indices of the parameters in the fit.
    x, target : ndarray, shape (4, 4)
        Camera and board poses of the fit with the deviations.
    covariance : ndarray, shape (12 + q, 12 + q)
        Of ``(δx, δt, u_fitted)`` (mm, rad; mm, deg).
    theta : ndarray
        Noise components (``Observations.components``) of the fit.
    camera_only : object
        The default estimator's solution it started from (``eiv.EivSolution``).
    keep : ndarray of bool, shape (n,)
        The postures of the fit (the camera-only fit's inliers).
    correlations : list of (str, str, float)
        Pairs of fitted parameters correlated beyond 0.95.
    robot : str
        The robot model.
    joints_deg : ndarray, shape (n, k)
        The session's postures (the plan).
    """

    names: list
    values: np.ndarray
    sigma: np.ndarray
    prior_sigma: np.ndarray
    status: list
    reasons: dict
    fitted: np.ndarray
    x: np.ndarray
    target: np.ndarray
    covariance: np.ndarray
    theta: np.ndarray
    camera_only: object
    keep: np.ndarray
    correlations: list
    robot: str = ""
    joints_deg: np.ndarray | None = None

    def identified(self, name: str) -> bool:
        return self.status[self.names.index(name)] == "identified"

    def reported_values(self) -> np.ndarray:
        """``values`` with nan where the parameter is not ``identified``."""
        ok = np.array([s == "identified" for s in self.status])
        return np.where(ok, self.values, np.nan)


def _whitened(obs: Observations, x, theta, columns: np.ndarray) -> np.ndarray:
    """The stacked whitened Jacobian ``L_i^-1 [J_x, J_T, J_u]`` of every posture, ``(6 n, 12 + p)``."""
    obs_k = replace(obs, kinematic=columns, kinematic_kinds=np.full(columns.shape[2], -1))
    g = _structures(obs_k, x)
    s = _posture_cov(obs_k, g, theta)
    jac = _jacobians(obs_k, _kinematic_jac(obs_k, x))
    chol = np.linalg.cholesky(s)
    return np.linalg.solve(chol, jac).reshape(-1, jac.shape[2])


def classify(whitened: np.ndarray, names: list, tol: float = ABSORBED_TOL) -> tuple[np.ndarray, dict, list]:
    """Which parameters the data can see: a greedy column selection after the 12 pose columns.

    Parameters
    ----------
    whitened : ndarray, shape (m, 12 + p)
        Whitened Jacobian, the parameter columns scaled by their prior sigmas.
    names : list of str, length p

    Returns
    -------
    fitted : ndarray of int
        The parameters taken, in order.
    reasons : dict
        Name to words for each parameter left out.
    status : list of str, length p
        ``fitted``, ``absorbed`` or ``degenerate``.
    """
    poses = whitened[:, :12]
    basis = np.linalg.qr(poses)[0]
    status, reasons, fitted = [], {}, []
    for j, name in enumerate(names):
        col = whitened[:, 12 + j]
        norm = np.linalg.norm(col)
        rest_pose = col - basis @ (basis.T @ col)
        if norm == 0 or np.linalg.norm(rest_pose) <= tol * norm:
            status.append("absorbed")
            reasons[name] = why_absorbed(name)
            continue
        if fitted:
            taken = whitened[:, [12 + i for i in fitted]]
            both = np.hstack([poses, taken])
            coef, *_ = np.linalg.lstsq(both, col, rcond=None)
            rest = col - both @ coef
            if np.linalg.norm(rest) <= tol * norm:
                partners = [names[i] for i, c in zip(fitted, coef[12:]) if abs(c) > 1e-3]
                status.append("degenerate")
                reasons[name] = why_absorbed(name, partners)
                continue
        status.append("fitted")
        fitted.append(j)
    return np.array(fitted, int), reasons, status


def fit_arm(obs: Observations, columns: np.ndarray, prior_sigma: np.ndarray, x0, t0, theta0,
            estimate_theta: bool = True):
    """Gauss-Newton on ``X, T, u`` with the prior on ``u``, alternated with REML of the noise components.

    Parameters
    ----------
    obs : Observations
        The postures of the fit (a subset already).
    columns : ndarray, shape (n, 6, q)
        Hand-local flange twist per unit of each fitted parameter.
    prior_sigma : ndarray, shape (q,)
    x0, t0 : ndarray, shape (4, 4)
    theta0 : ndarray
        Start of the noise components.

    Returns
    -------
    x, t, u, theta, covariance
        ``covariance``: ``(12 + q, 12 + q)`` of ``(δx, δt, u)``.
    """
    q = columns.shape[2]
    obs_k = replace(obs, kinematic=columns, kinematic_kinds=np.full(q, -1))
    prior = np.zeros((12 + q, 12 + q))
    prior[12:, 12:] = np.diag(1.0 / np.asarray(prior_sigma, float) ** 2)
    x, t, u = np.array(x0, float), np.array(t0, float), np.zeros(q)
    theta = np.array(theta0, float)
    lam = np.ones(2)  # unused: the parameters are fixed effects (no variance of theirs is estimated)
    last = np.zeros(len(theta) + 2)
    for outer in range(1, MAX_OUTER + 1):
        g = _structures(obs_k, x)
        w = np.linalg.inv(_posture_cov(obs_k, g, theta))
        x, t, u, step = _gauss_newton(obs_k, x, t, u, w, prior, 3)
        if not estimate_theta or len(theta) == 0:
            if _small(step):
                break
            continue
        ju = _kinematic_jac(obs_k, x)
        jac = _jacobians(obs_k, ju)
        rho = _residuals(obs_k, x, t, u, ju)
        new, _, _ = _variance_step(g, w, theta, rho, jac, prior, u, lam, obs_k.kinematic_kinds,
                                   fisher_scoring=outer > 3)
        new, _, last = _damped(theta, lam, new, lam, last)
        change = np.max(np.abs(new - theta) / np.maximum(theta, VARIANCE_FLOOR))
        theta = new
        if change < THETA_TOL and _small(step):
            break
    g = _structures(obs_k, x)
    w = np.linalg.inv(_posture_cov(obs_k, g, theta))
    normal = _normal(_jacobians(obs_k, _kinematic_jac(obs_k, x)), w, prior)
    cov = np.linalg.inv(normal)
    return x, t, u, theta, 0.5 * (cov + cov.T)


def _correlations(cov: np.ndarray, names: list, limit: float = 0.95) -> list:
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    out = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > limit:
                out.append((names[i], names[j], float(corr[i, j])))
    return out


def identify_arm(problem, solution=None, prior: dict | None = None) -> ArmIdentification:
    """The arm's deviations, the camera and the board, from a session with joint angles.

    Parameters
    ----------
    problem : HandEyeProblem
        With ``joints_deg`` and ``robot``.
    solution : EivSolution, optional
        The default estimator's solution (computed when omitted, without cross-validation).
    prior : dict, optional
        ``length_mm``, ``angle_deg``: one-sigma prior (default: the robot file's ``kinematic_prior``).

    Raises
    ------
    ValueError
        A session without joint angles of a known robot (one line, what to do).
    """
    from .eiv import solve_eiv  # noqa: PLC0415
    from ..robot import load_robot  # noqa: PLC0415

    if problem.joints_deg is None or problem.robot is None:
        raise ValueError("the arm's kinematics need the joint angles of every posture and the robot model in the "
                         "session: capture with the station (it records them)")
    sol = solve_eiv(problem, folds=0) if solution is None else solution
    obs = sol.observations
    if obs.kinematic is None:
        raise ValueError(obs.notes.get("joint_mismatch", "the session's joints do not match its robot model")
                         + ": the arm's kinematics cannot be identified")
    robot = load_robot(problem.robot)
    keep = ~np.asarray(sol.outliers, bool)
    sub = obs.subset(keep)
    names = parameter_names(robot.dof)
    prior = robot_prior(problem.robot) if prior is None else prior
    prior_sigma = np.where(parameter_kinds(robot.dof) == 0, prior["length_mm"], prior["angle_deg"])
    columns = parameter_jacobian(robot, problem.joints_deg[keep], sub.kinematic)
    whitened = _whitened(sub, sol.fit.x, sol.fit.theta, columns * prior_sigma)
    fitted, reasons, status = classify(whitened, names)
    x, t, u, theta, cov = fit_arm(sub, columns[:, :, fitted], prior_sigma[fitted], sol.fit.x, sol.fit.target,
                                  sol.fit.theta)
    values = np.zeros(len(names))
    sigma = np.full(len(names), np.nan)
    values[fitted] = u
    sigma[fitted] = np.sqrt(np.diag(cov)[12:])
    for j in fitted:
        if sigma[j] > WEAK_FRACTION * prior_sigma[j]:
            status[j] = "weak"
            unit = "mm" if parameter_kinds(robot.dof)[j] == 0 else "deg"
            reasons[names[j]] = (f"its one-sigma {sigma[j]:.3g} {unit} is more than {WEAK_FRACTION:g} of the robot "
                                 f"file's {prior_sigma[j]:.3g} {unit}: the data hardly see it at these postures")
        else:
            status[j] = "identified"
    corr = _correlations(cov[12:, 12:], [names[j] for j in fitted])
    return ArmIdentification(names, values, sigma, prior_sigma, status, reasons, fitted, x, t, cov, theta, sol, keep,
                             corr, str(problem.robot), np.asarray(problem.joints_deg, float))
