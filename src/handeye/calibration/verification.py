"""A calibration checked again: revisited postures against the prediction of the calibration's fit.

The maximum-likelihood fit of a session (``calibration.eiv``) holds everything a prediction needs:
``X`` (``cam2tool0``), ``T`` (the board in base), the arm's kinematic deviations ``u`` when they were
modelled, the noise levels ``θ`` (camera, robot) and the covariance ``C`` of ``(δx, δt, u)`` (the
inverse of the mixed-model normal matrix). At a revisited posture ``j`` with the measured flange
pose ``A_j`` and board pose ``B_j`` the discrepancy is the posture residual of the fit,

    d_j = twist(T^-1 (A_j ⊕ K_j u) X B_j)                               (calibration.eiv, eq. 13)

and, when nothing changed since the calibration, ``d ~ N(0, Σ)`` with

    Σ = blockdiag(S_j) + J C J^T,     S_j = F_j + sum_k θ_k G_jk,

``F_j`` the camera covariance of the new board fit, ``G_jk`` the robot's and camera's variance
structures at the new postures and ``J = d d / d(δx, δt, u)``. The test statistic is
``q = d^T Σ^-1 d``; with ``θ`` estimated from ``ν`` residual degrees of freedom of the calibration,
``q / m`` (``m = 6 K``) is referred to ``F(m, ν)`` (as the fit's own deleted-posture test does), so
the stated level is the false-alarm rate.

:class:`Baseline` is what a session's fit gives the check; :func:`drift_test` runs it on the
observations of the revisited postures; ``calibration.drift_causes`` explains a drift.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import f as f_dist

from .noise import adjoint, flange_jacobian, retract, twist_between
from ..geometry import invert_transforms

if TYPE_CHECKING:
    from ..robot import RobotModel
    from .eiv.model import Observations
    from .eiv.pipeline import EivSolution

__all__ = ["DEFAULT_LEVEL", "LEVEL_RANGE", "MIN_VERIFY_POSTURES", "Baseline", "Discrepancy", "DriftTest", "baseline_from_solution",
           "discrepancy", "drift_test", "hypothesis_jacobians"]

#: Default false-alarm rate of the check.
DEFAULT_LEVEL = 0.01
#: The false-alarm rates a check may be asked for: below 1e-6 (about five sigma) a test passes changes
#: of millimetres (at 1e-300 a 1 mm camera shift); above 0.2 one check in five raises a false alarm.
LEVEL_RANGE = (1e-6, 0.2)
#: Fewest revisited postures the check and its diagnosis need: with two, a camera move and a board move
#: (six parameters each) are told apart only by one relative rotation; three give the joints' pattern.
MIN_VERIFY_POSTURES = 3


@dataclass(frozen=True)
class Baseline:
    """What the check takes from a session's maximum-likelihood fit.

    Attributes
    ----------
    x : ndarray, shape (4, 4)
        ``cam2tool0`` of the calibration.
    target : ndarray, shape (4, 4)
        The board in base (``target2base``).
    theta : ndarray, shape (k,)
        Variance components, named by ``components``.
    components : tuple of str
    kinematic : ndarray, shape (q,)
        The arm's DH deviations of the fit (empty: not modelled).
    covariance : ndarray, shape (12 + q, 12 + q)
        Of ``(δx, δt, u)`` (mm, rad, DH units).
    dof : int
        Residual degrees of freedom of the noise levels: ``6 n - 12 - k``.
    """

    x: np.ndarray
    target: np.ndarray
    theta: np.ndarray
    components: tuple
    kinematic: np.ndarray
    covariance: np.ndarray
    dof: int

    @property
    def q(self) -> int:
        return int(len(self.kinematic))


def baseline_from_solution(solution: EivSolution) -> Baseline:
    """The :class:`Baseline` of an ``eiv.EivSolution`` (its fit over the inliers).

    The covariance is the inverse of the mixed-model normal matrix over the inliers with the kinematic
    deviations kept (the fit's own ``covariance`` marginalises them); a revisited posture sees them.
    """
    from dataclasses import replace  # noqa: PLC0415

    from .eiv import fit as ml_fit  # noqa: PLC0415 (the fit's internals: the normal matrix)

    fit, obs = solution.fit, solution.observations
    keep = ~np.asarray(solution.outliers, bool)
    kinematic = len(fit.kinematic) > 0
    if not kinematic and obs.kinematic is not None:
        obs = replace(obs, kinematic=None, kinematic_kinds=None)
    sub = obs.subset(keep)
    g = ml_fit._structures(sub, fit.x)
    w = np.linalg.inv(ml_fit._posture_cov(sub, g, fit.theta))
    ju = ml_fit._kinematic_jac(sub, fit.x)
    prior = ml_fit._prior(sub, fit.kinematic_var)
    cov = np.linalg.inv(ml_fit._normal(ml_fit._jacobians(sub, ju), w, prior))
    return Baseline(fit.x, fit.target, np.asarray(fit.theta, float), tuple(c.name for c in obs.components),
                    np.asarray(fit.kinematic, float), 0.5 * (cov + cov.T),
                    int(6 * keep.sum() - 12 - len(fit.theta)))


@dataclass(frozen=True)
class Discrepancy:
    """The revisited postures against the baseline's prediction.

    Attributes
    ----------
    d : ndarray, shape (6 K,)
        Stacked ``d_j`` (mm, rad; board frame).
    noise : ndarray, shape (6 K, 6 K)
        ``blockdiag(S_j)``: the new measurements' noise.
    estimate : ndarray, shape (6 K, 12 + q)
        ``J``: how the baseline's errors ``(δx, δt, u)`` move ``d``.
    covariance : ndarray, shape (6 K, 6 K)
        ``Σ = noise + J C J^T``.
    hand : ndarray, shape (K, 4, 4)
        The flange poses, kinematic deviations applied.
    board : ndarray, shape (K, 4, 4)
        The measured board poses ``B_j``.
    joints_deg : ndarray, shape (K, dof) or None
    """

    d: np.ndarray
    noise: np.ndarray
    estimate: np.ndarray
    covariance: np.ndarray
    hand: np.ndarray
    board: np.ndarray
    joints_deg: np.ndarray | None

    @property
    def postures(self) -> int:
        return int(len(self.board))


def _block_diagonal(blocks: np.ndarray) -> np.ndarray:
    n = len(blocks)
    out = np.zeros((6 * n, 6 * n))
    for j, block in enumerate(blocks):
        out[6 * j:6 * j + 6, 6 * j:6 * j + 6] = block
    return out


def discrepancy(baseline: Baseline, obs: Observations, joints_deg: ArrayLike | None = None) -> Discrepancy:
    """``d``, ``Σ`` and ``J`` of the revisited postures (an ``eiv.Observations`` of them, and their
    controller angles ``joints_deg`` (K, dof) for the joints' hypotheses).

    Raises
    ------
    ValueError
        The observations do not have the baseline's noise components (another kind of session).
    """
    from .eiv import fit as ml_fit  # noqa: PLC0415 (the fit's internals: the posture covariance, the Jacobians)

    names = tuple(c.name for c in obs.components)
    if names != baseline.components:
        raise ValueError(f"the revisited postures have the noise components {names}, the calibration {baseline.components}")
    hand = obs.hand
    if baseline.q:
        if obs.kinematic is None:
            raise ValueError("the calibration modelled the arm's kinematic deviations; the revisited postures hold no joints")
        hand = retract(obs.hand, obs.kinematic @ baseline.kinematic)  # A_j ⊕ K_j u
    x, t = baseline.x, baseline.target
    d = twist_between(t, hand @ x @ obs.board).reshape(-1)
    s = ml_fit._posture_cov(obs, ml_fit._structures(obs, x), baseline.theta)
    jac = np.zeros((6 * obs.n, 12 + baseline.q))
    est = ml_fit._jacobians(obs, ml_fit._kinematic_jac(obs, x) if baseline.q else None)
    for j in range(obs.n):
        jac[6 * j:6 * j + 6] = est[j]
    noise = _block_diagonal(s)
    cov = noise + jac @ baseline.covariance @ jac.T
    return Discrepancy(d, noise, jac, 0.5 * (cov + cov.T), hand, obs.board,
                       None if joints_deg is None else np.asarray(joints_deg, float))


@dataclass(frozen=True)
class DriftTest:
    """The outcome of :func:`drift_test`.

    Attributes
    ----------
    statistic : float
        ``q = d^T Σ^-1 d``.
    degrees : int
        ``m = 6 K``.
    p_value : float
        ``P(F(m, ν) > q / m)``.
    level : float
    drift : bool
        ``p_value < level``.
    """

    statistic: float
    degrees: int
    p_value: float
    level: float
    drift: bool


def drift_test(disc: Discrepancy, baseline: Baseline, level: float = DEFAULT_LEVEL) -> DriftTest:
    """The check at the false-alarm rate ``level`` (see the module docstring)."""
    q = float(disc.d @ np.linalg.solve(disc.covariance, disc.d))
    m = int(len(disc.d))
    p = float(f_dist.sf(q / m, m, max(baseline.dof, 1)))
    return DriftTest(q, m, p, float(level), p < level)


def hypothesis_jacobians(disc: Discrepancy, x: np.ndarray, robot: RobotModel | None = None) -> dict:
    """How each change of the world moves ``d`` (first order): name -> ``(6 K, p)``.

    - ``camera``: the camera moved on the flange, ``X' = X ⊕ p``: ``d_j`` moves by ``-Ad_{B_j^-1} p``;
    - ``board``: the board moved in base, ``T' = T ⊕ p``: ``d_j`` moves by ``p``;
    - ``joint k``: controller angle ``k`` reads ``δ`` less than the axis stands (its zero moved): the
      flange stands at ``A_j ⊕ J_j,k δ`` (``noise.flange_jacobian``, per degree), so ``d_j`` moves by
      ``-Ad_{(X B_j)^-1} J_j,k δ``.

    Parameters
    ----------
    disc : Discrepancy
    x : ndarray, shape (4, 4)
    robot : RobotModel, optional
        The joints' hypotheses need it and the joints.
    """
    n = disc.postures
    out = {"camera": np.concatenate(list(-adjoint(invert_transforms(disc.board))), axis=0),
           "board": np.tile(np.eye(6), (n, 1))}
    if robot is not None and disc.joints_deg is not None:
        flange = flange_jacobian(robot, disc.joints_deg)  # (K, 6, dof), per degree
        to_residual = adjoint(invert_transforms(x[None] @ disc.board))
        moved = -(to_residual @ flange)  # (K, 6, dof)
        for k in range(robot.dof):
            out[f"joint {k + 1}"] = moved[:, :, k].reshape(6 * n, 1)
    return out
