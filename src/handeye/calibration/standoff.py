"""The error of a point at the inspection stand-off, predicted from the full covariance.

The point is ``p_c = (0, 0, L)`` in the camera frame (``L`` the stand-off, default 750 mm along the
optical axis), where the probe works. Its place in the board's frame (the work's frame: the part is
located against the board, so the base's own gauge, J1's zero and d1, does not enter) at a posture
with controller angles ``q`` is

    p = T^-1 A(q) X p_c,

with ``A`` the flange pose the station's arm model gives. A local twist ``ε`` of ``G = T^-1 A X``
moves it by ``R_G [I, -[p_c]x] ε``; ``ε = δx + Ad_{X^-1} K(q) u - Ad_{G^-1} δt`` (eye-in-hand), so

- **with the correction** (the identified arm model): the error is the spread of ``(δx, δt, u)``
  under their covariance ``Σ`` (camera, board, kinematics and the noise behind them):
  ``E|e|² = tr(J Σ J^T)``;
- **without it** (the camera-only calibration and the nominal arm): its point differs from the
  corrected one by ``b(q)``, known from the data, so its error is ``b`` plus the corrected point's own
  error: ``E|e|² = |b|² + tr(J Σ J^T)``. (Not ``|b|²`` plus the camera-only fit's covariance: that fit
  took the arm's errors as noise, so its covariance already holds them, and ``b`` holds them again.)

Both are root-mean-square over postures (the plan's, or any given). That is an expectation: one
calibration's actual RMS over many postures is one draw of ``(δx, δt, u)``, the same at every
posture, so it does not average out with more postures. :func:`predicted_standoff` also draws it
(:data:`DRAWS` draws of ``N(0, Σ)`` through the same Jacobian): the interval an actual RMS falls in
(``interval``) and where a measured one lies in that distribution (``quantile``). With ~20 fitted
parameters of very unequal weight the ratio of the expected to the actual RMS spreads by about
0.8-1.4x (5-95 %) with the correction; without it the known ``b`` dominates and it stays near 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .arm_parameters import corrected_robot, parameter_jacobian
from .noise import adjoint, skew
from ..geometry import invert_transforms

__all__ = ["DEFAULT_STANDOFF_MM", "DRAWS", "StandoffError", "predicted_standoff", "working_volume_joints", "rms_draws", "standoff_points", "flange_standoff_points",
           "measured_standoff"]

#: The inspection stand-off along the camera's optical axis, mm.
DEFAULT_STANDOFF_MM = 750.0

#: Draws of the fit's error behind the distribution of the actual RMS (fixed seed: the same prediction
#: every time).
DRAWS = 4000


@dataclass(frozen=True)
class StandoffError:
    """Predicted error of the stand-off point, per posture and RMS over them (mm).

    Attributes
    ----------
    standoff_mm : float
    corrected_mm, uncorrected_mm : ndarray, shape (n,)
        Root of the expected squared error at each posture.
    points_mm : ndarray, shape (n, 3)
        The stand-off point in base (nominal model, camera-only pose): where the map puts it.
    corrected_draws_mm, uncorrected_draws_mm : ndarray, shape (DRAWS,)
        The RMS over the postures of one calibration's actual error, drawn from the covariance (empty
        when not drawn).
    """

    standoff_mm: float
    corrected_mm: np.ndarray
    uncorrected_mm: np.ndarray
    points_mm: np.ndarray
    corrected_draws_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    uncorrected_draws_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def corrected_rms_mm(self) -> float:
        return float(np.sqrt(np.mean(self.corrected_mm ** 2)))

    @property
    def uncorrected_rms_mm(self) -> float:
        return float(np.sqrt(np.mean(self.uncorrected_mm ** 2)))

    def interval(self, level: float = 0.9, corrected: bool = True) -> tuple[float, float]:
        """The central ``level`` interval (mm) of one calibration's actual RMS over these postures."""
        draws = self.corrected_draws_mm if corrected else self.uncorrected_draws_mm
        if len(draws) == 0:
            return (float("nan"), float("nan"))
        low, high = np.quantile(draws, [0.5 - level / 2, 0.5 + level / 2])
        return float(low), float(high)

    def quantile(self, measured_mm: float, corrected: bool = True) -> float:
        """The fraction of the drawn RMS below ``measured_mm`` (uniform over calibrations when the
        prediction is right)."""
        draws = self.corrected_draws_mm if corrected else self.uncorrected_draws_mm
        return float(np.mean(draws < measured_mm)) if len(draws) else float("nan")

    def to_dict(self) -> dict:
        def _json(pair):  # null when not drawn (a JSON file holds no NaN)
            return [float(v) for v in pair] if np.all(np.isfinite(pair)) else None

        with_90, without_90 = _json(self.interval(0.9, True)), _json(self.interval(0.9, False))
        return {"standoff_mm": float(self.standoff_mm), "frame": "board (the work's frame)",
                "with_correction_rms_mm": self.corrected_rms_mm,
                "without_correction_rms_mm": self.uncorrected_rms_mm,
                "with_correction_90_interval_mm": with_90,
                "without_correction_90_interval_mm": without_90,
                "with_correction_max_mm": float(np.max(self.corrected_mm)),
                "without_correction_max_mm": float(np.max(self.uncorrected_mm)),
                "postures": int(len(self.corrected_mm)),
                "meaning": "root-mean-square predicted error of a point at the stand-off along the camera axis, in "
                           "the board's frame, over the postures, from the full covariance (camera, board, "
                           "kinematics, noise); without correction: the camera-only calibration with the nominal "
                           "arm, whose identified deviations stay in the error; 90_interval: where one "
                           "calibration's actual RMS falls 9 times in 10 (the error is one draw of the fit's, "
                           "the same at every posture)"}


def _point_rows(rotation: np.ndarray, point: np.ndarray) -> np.ndarray:
    """``R [I, -[p]x]``: point displacement per local twist ``(ρ, φ)``; ``(n, 3, 6)``."""
    n = rotation.shape[0]
    block = np.zeros((n, 3, 6))
    block[:, :, :3] = np.eye(3)
    block[:, :, 3:] = -skew(np.broadcast_to(point, (n, 3)))
    return rotation @ block


def _point_rows_at(points: np.ndarray) -> np.ndarray:
    """``[I, -[p_n]x]`` per point ``(n, 3)``: ``(n, 3, 6)``."""
    block = np.zeros((len(points), 3, 6))
    block[:, :, :3] = np.eye(3)
    block[:, :, 3:] = -skew(points)
    return block


def standoff_points(robot, joints_deg, x, target, standoff_mm: float = DEFAULT_STANDOFF_MM) -> np.ndarray:
    """The stand-off point in the board's frame, ``(n, 3)``, for an arm model, a camera and a board pose."""
    return flange_standoff_points(robot.forward_transform(joints_deg), x, target, standoff_mm)


def flange_standoff_points(flange: ArrayLike, x: ArrayLike, target: ArrayLike,
                           standoff_mm: float = DEFAULT_STANDOFF_MM) -> np.ndarray:
    """The stand-off point in the board's frame, ``(n, 3)``: ``standoff_mm`` along the axis of the camera ``x``
    (4, 4; in tool0) on the flange poses ``flange`` (n, 4, 4; tool0 in base), the board at ``target`` (4, 4; in base)."""
    g = invert_transforms(np.asarray(target, float))[None] @ np.asarray(flange, float) @ np.asarray(x, float)[None]
    return g[:, :3, :3] @ np.array([0.0, 0.0, float(standoff_mm)]) + g[:, :3, 3]


def _jacobian(robot, joints, x, target, columns, standoff_mm) -> np.ndarray:
    """``d p / d(δx, δt, u)`` of the stand-off point in the board frame, ``(n, 3, 12 + q)``."""
    g = invert_transforms(target)[None] @ robot.forward_transform(joints) @ x[None]
    pc = np.array([0.0, 0.0, standoff_mm])
    rows = _point_rows(g[:, :3, :3], pc)
    p_t = g[:, :3, :3] @ pc + g[:, :3, 3]
    n = len(joints)
    jac = np.zeros((n, 3, 12 + columns.shape[2]))
    jac[:, :, :6] = rows
    jac[:, :, 6:12] = -_point_rows_at(p_t)  # (T ⊕ δt)^-1 = exp(-δt) T^-1
    jac[:, :, 12:] = rows @ adjoint(invert_transforms(x))[None] @ columns
    return jac


def predicted_standoff(ident, joints_deg=None, standoff_mm: float = DEFAULT_STANDOFF_MM,
                       draws: int = DRAWS) -> StandoffError:
    """The predicted stand-off error of an :class:`~handeye.calibration.arm_identification.ArmIdentification`
    with and without its correction, at ``joints_deg`` (default: the session's postures); ``draws``: of
    the actual RMS's distribution (0: none, for a map of many postures)."""
    from ..robot import load_robot  # noqa: PLC0415

    sol = ident.camera_only
    robot = load_robot(ident.robot)
    joints = np.asarray(ident.joints_deg if joints_deg is None else joints_deg, float)
    columns = parameter_jacobian(robot, joints)[:, :, ident.fitted]
    corrected = corrected_robot(robot, ident.values)
    jac_k = _jacobian(corrected, joints, ident.x, ident.target, columns, standoff_mm)
    var_k = np.einsum("nij,jk,nik->n", jac_k, ident.covariance, jac_k)
    # without: the camera-only pose with the nominal arm, off the corrected point by the known b
    bias = (standoff_points(robot, joints, sol.fit.x, sol.fit.target, standoff_mm)
            - standoff_points(corrected, joints, ident.x, ident.target, standoff_mm))
    var_k = np.maximum(var_k, 0.0)
    points = (robot.forward_transform(joints) @ sol.fit.x)[:, :3, :] @ np.array([0.0, 0.0, standoff_mm, 1.0])
    draws_k, draws_0 = rms_draws(jac_k, ident.covariance, bias, draws)
    return StandoffError(float(standoff_mm), np.sqrt(var_k), np.sqrt(np.sum(bias ** 2, axis=1) + var_k), points,
                         draws_k, draws_0)


def rms_draws(jac: np.ndarray, cov: np.ndarray, bias: np.ndarray, draws: int = DRAWS,
              seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """One calibration's RMS error over the postures, drawn: the fit's error ``δ ~ N(0, cov)`` is the
    same at every posture.

    Parameters
    ----------
    jac : ndarray, shape (n, 3, p)
        Point displacement per parameter at each posture.
    cov : ndarray, shape (p, p)
    bias : ndarray, shape (n, 3)
        The known offset of the uncorrected point.

    Returns
    -------
    corrected, uncorrected : ndarray, shape (draws,)
        RMS of ``J δ`` and of ``b + J δ`` over the postures, mm.
    """
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    root = vecs * np.sqrt(np.maximum(vals, 0.0))
    z = np.random.default_rng(seed).standard_normal((root.shape[1], draws))
    err = np.einsum("nip,pd->ndi", jac @ root[None], z)                  # (n, draws, 3)
    corrected = np.sqrt(np.mean(np.sum(err ** 2, axis=2), axis=0))
    uncorrected = np.sqrt(np.mean(np.sum((err + bias[:, None, :]) ** 2, axis=2), axis=0))
    return corrected, uncorrected


def measured_standoff(true_robot, x_true, target_true, robot, ident, joints_deg,
                      standoff_mm: float = DEFAULT_STANDOFF_MM) -> tuple[np.ndarray, np.ndarray]:
    """The actual errors ``(n,)`` of the stand-off point against a known truth, with and without correction."""
    truth = standoff_points(true_robot, joints_deg, x_true, target_true, standoff_mm)
    sol = ident.camera_only
    without = standoff_points(robot, joints_deg, sol.fit.x, sol.fit.target, standoff_mm)
    with_ = standoff_points(corrected_robot(robot, ident.values), joints_deg, ident.x, ident.target, standoff_mm)
    return np.linalg.norm(with_ - truth, axis=1), np.linalg.norm(without - truth, axis=1)


def working_volume_joints(robot, x, count: int = 600, seed: int = 0, margin_deg: float = 5.0,
                          max_draws: int = 20) -> np.ndarray:
    """Postures ``(<= count, k)`` spread over the arm's working volume: controller angles uniform inside
    the joint limits (``margin_deg`` in from each), kept where every point of the chain and the camera
    (tool0 times ``x``) is above the plane of the base (a cheap clearance: the floor under the base;
    the cell's own bodies are not checked). Fixed ``seed``: the same map every time."""
    rng = np.random.default_rng(seed)
    low = robot.joint_limits_deg[:, 0] + margin_deg
    high = robot.joint_limits_deg[:, 1] - margin_deg
    kept = []
    for _ in range(max_draws):
        joints = rng.uniform(low, high, (count, robot.dof))
        chain = robot.chain_points(joints)[:, 1:, 2]
        camera = (robot.forward_transform(joints) @ np.asarray(x, float))[:, 2, 3]
        kept.append(joints[np.all(chain > 0.0, axis=1) & (camera > 0.0)])
        if sum(len(k) for k in kept) >= count:
            break
    return np.vstack(kept)[:count]
