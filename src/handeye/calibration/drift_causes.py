"""What changed since a calibration: competing explanations of the discrepancies, fitted and compared.

Each explanation is a change of the world with a few parameters ``p`` whose first-order effect on the
discrepancies is ``J_H p`` (``verification.hypothesis_jacobians``): ``camera`` (a rigid change of
``X``, 6 parameters), ``board`` (a rigid change of the board in base, 6), ``joint k`` (one zero
offset, 1), and ``none`` (0). Each is fitted by generalised least squares,

    p̂ = (J^T Σ^-1 J)^-1 J^T Σ^-1 d,      χ²_H = (d - J p̂)^T Σ^-1 (d - J p̂),

and compared by the Bayesian information criterion ``BIC_H = χ²_H + p_H ln m`` (``-2 ln L`` up to a
constant, penalised for the parameter count; ``m = 6 K``). The likelihood ratio of the best to the next
is ``exp((BIC_next - BIC_best) / 2)``.

Explanations these data cannot tell apart are named together: another explanation whose fit is
within :data:`SAME_EFFECT_CHI2` of the best's ``χ²`` predicts the same discrepancies (a joint-1 zero
shift turns the board about base z, a joint-6 zero shift turns the camera about the flange axis;
found from the data, not from a list).

The quick update (:func:`quick_update`): when the camera moved, the revisited postures with the
session's board, kinematics and noise as prior give an updated ``X`` with its covariance (the
covariance of the old ``X`` left out: it is replaced).
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass, replace

import numpy as np

from .noise import retract
from .verification import Baseline, Discrepancy, discrepancy, hypothesis_jacobians

if TYPE_CHECKING:
    from ..robot import RobotModel
    from .eiv.model import Observations

__all__ = ["SAME_EFFECT_CHI2", "Explanation", "QuickUpdate", "explain", "likelihood_ratio", "quick_update", "same_effect"]

#: Two explanations whose fits differ by less than this in χ² (the 5 % point of a chi-square with
#: one degree of freedom) predict the same discrepancies within the noise.
SAME_EFFECT_CHI2 = 3.84


@dataclass(frozen=True)
class Explanation:
    """One explanation fitted to the discrepancies.

    Attributes
    ----------
    cause : str
        ``none``, ``camera``, ``board`` or ``joint``.
    joint : int or None
        1-based axis of a ``joint`` explanation.
    parameters : ndarray, shape (p,)
        ``p̂``: a local twist (mm, rad) of X or of the board, or the zero offset (deg).
    covariance : ndarray, shape (p, p)
    chi2 : float
    bic : float
    shift_mm, turn_deg : ndarray, shape (3,)
        The change in the parent frame (tool0 for the camera, base for the board); for a joint the
        turn is ``(0, 0, angle)`` about the axis and the shift zero.
    """

    cause: str
    joint: int | None
    parameters: np.ndarray
    covariance: np.ndarray
    chi2: float
    bic: float
    shift_mm: np.ndarray
    turn_deg: np.ndarray

    @property
    def name(self) -> str:
        return f"joint {self.joint}" if self.cause == "joint" else self.cause

    @property
    def translation_mm(self) -> float:
        return float(np.linalg.norm(self.shift_mm))

    @property
    def rotation_deg(self) -> float:
        return float(np.linalg.norm(self.turn_deg))


def _fit(jac: np.ndarray, d: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """GLS fit of ``d ≈ J p``: ``p̂``, its covariance and ``χ²`` of what is left."""
    if jac.shape[1] == 0:
        return np.zeros(0), np.zeros((0, 0)), float(d @ w @ d)
    normal = jac.T @ w @ jac
    cov = np.linalg.inv(normal)
    p = cov @ (jac.T @ w @ d)
    left = d - jac @ p
    return p, 0.5 * (cov + cov.T), float(left @ w @ left)


def _in_parent(frame: np.ndarray, twist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A local twist ``(ρ, φ)`` of a pose as the shift (mm) and turn (deg) in the pose's parent frame."""
    rot = frame[:3, :3]
    return rot @ twist[:3], np.degrees(rot @ twist[3:])


def explain(disc: Discrepancy, baseline: Baseline, robot: RobotModel | None = None) -> list[Explanation]:
    """Every explanation fitted, best (lowest BIC) first; ``none`` among them.

    Parameters
    ----------
    disc : Discrepancy
    baseline : Baseline
    robot : RobotModel, optional
        For the joints' explanations (with the revisited postures' joints).
    """
    w = np.linalg.inv(disc.covariance)
    m = len(disc.d)
    out = []
    candidates = {"none": np.zeros((m, 0)), **hypothesis_jacobians(disc, baseline.x, robot)}
    for name, jac in candidates.items():
        p, cov, chi2 = _fit(jac, disc.d, w)
        cause, _, axis = name.partition(" ")
        if cause == "camera":
            shift, turn = _in_parent(baseline.x, p)
        elif cause == "board":
            shift, turn = _in_parent(baseline.target, p)
        else:
            shift, turn = np.zeros(3), np.array([0.0, 0.0, float(p[0]) if len(p) else 0.0])
        out.append(Explanation(cause, int(axis) if axis else None, p, cov, chi2, chi2 + len(p) * np.log(m),
                               shift, turn))
    return sorted(out, key=lambda e: e.bic)


def same_effect(explanations: list[Explanation], best: Explanation) -> list[Explanation]:
    """The explanations (other than ``best`` and ``none``) that fit these data as well as ``best``."""
    return [e for e in explanations if e is not best and e.cause != "none" and e.chi2 - best.chi2 < SAME_EFFECT_CHI2]


def likelihood_ratio(best: Explanation, other: Explanation) -> float:
    """``exp((BIC_other - BIC_best) / 2)``: how much more likely ``best`` is (capped at 1e12)."""
    return float(np.exp(min((other.bic - best.bic) / 2.0, np.log(1e12))))


@dataclass(frozen=True)
class QuickUpdate:
    """An updated camera frame from the revisited postures (:func:`quick_update`).

    Attributes
    ----------
    x : ndarray, shape (4, 4)
    covariance : ndarray, shape (6, 6)
        Of ``(shift mm, turn deg)`` of ``x`` in tool0 (as ``uncertainty.covariance`` of a calibration).
    sigma_translation_mm, sigma_rotation_deg : ndarray, shape (3,)
    reduced_chi2 : float
        ``χ² / (6 K - 6)`` of the update's own residuals; the covariance is scaled by it when above 1.
    """

    x: np.ndarray
    covariance: np.ndarray
    sigma_translation_mm: np.ndarray
    sigma_rotation_deg: np.ndarray
    reduced_chi2: float = 1.0


def quick_update(baseline: Baseline, obs: Observations, joints_deg: np.ndarray | None = None, iterations: int = 3) -> QuickUpdate:
    """The camera's new ``X`` from the revisited postures, the session's board and arm as prior.

    Gauss-Newton on the camera explanation: ``X_(k+1) = X_k ⊕ p̂`` with ``p̂`` the GLS fit of
    ``d ≈ J_camera p`` under ``Σ' = blockdiag(S_j) + J_(t,u) C_(t,u) J_(t,u)^T`` (the board's and the
    kinematics' uncertainty kept, the old X's dropped).

    The covariance ``(J^T Σ'^-1 J)^-1`` holds only if ``Σ'`` (the session's noise levels) describes
    the revisited postures. When the update's own residuals say otherwise (``χ² / (6 K - 6) > 1``:
    the arm's unmodelled errors at these postures, or a change the camera explanation does not hold
    entirely), the covariance is scaled by that reduced chi-square (never shrunk below 1), so a
    quick update never claims more certainty than its own fit shows; its thresholds then ask for a
    recapture sooner. What no revisit can show stays at the session's prior: a deviation of the arm's
    last link (its DH row) is one rigid change with the camera mount, bounded only by the kinematic
    prior the calibration estimated (``C_(u)``).

    Parameters
    ----------
    baseline : Baseline
    obs : eiv.Observations
        The K revisited postures.
    joints_deg : ndarray, shape (K, dof), optional
    iterations : int

    Returns
    -------
    QuickUpdate
    """
    x = np.array(baseline.x, float)
    cov, chi2, dof = np.eye(6), 0.0, 1
    for _ in range(iterations):
        disc = discrepancy(replace(baseline, x=x), obs, joints_deg)
        rest = disc.estimate[:, 6:]
        sigma = disc.noise + rest @ baseline.covariance[6:, 6:] @ rest.T
        jac = hypothesis_jacobians(disc, x)["camera"]
        p, cov, chi2 = _fit(jac, disc.d, np.linalg.inv(sigma))
        dof = max(len(disc.d) - jac.shape[1], 1)
        x = retract(x, p)
    reduced = chi2 / dof
    cov = cov * max(reduced, 1.0)
    block = np.zeros((6, 6))
    block[:3, :3] = block[3:, 3:] = x[:3, :3]
    scale = np.r_[np.ones(3), np.full(3, 180.0 / np.pi)]
    parent = (block @ cov @ block.T) * np.outer(scale, scale)
    sig = np.sqrt(np.maximum(np.diag(parent), 0.0))
    return QuickUpdate(x, parent, sig[:3], sig[3:], float(reduced))
