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
- **without it** (the camera-only calibration and the nominal arm): the identified deviations stay in
  the error, as the difference between the two models' points ``b(q)``, plus the spread of the
  camera-only fit and of the identified deviations carried through it:
  ``E|e|² = |b|² + tr(J0 C0 J0^T) + tr(M Σ_uu M^T)``, ``M = J_xt H - J_u`` with ``H`` the least-squares
  map by which the camera-only fit absorbs deviations.

Both are root-mean-square over postures (the plan's, or any given).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm_parameters import corrected_robot, parameter_jacobian
from .noise import adjoint, skew
from ..geometry import invert_transforms

__all__ = ["DEFAULT_STANDOFF_MM", "StandoffError", "predicted_standoff", "standoff_points", "measured_standoff"]

#: The inspection stand-off along the camera's optical axis, mm.
DEFAULT_STANDOFF_MM = 750.0


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
    """

    standoff_mm: float
    corrected_mm: np.ndarray
    uncorrected_mm: np.ndarray
    points_mm: np.ndarray

    @property
    def corrected_rms_mm(self) -> float:
        return float(np.sqrt(np.mean(self.corrected_mm ** 2)))

    @property
    def uncorrected_rms_mm(self) -> float:
        return float(np.sqrt(np.mean(self.uncorrected_mm ** 2)))

    def to_dict(self) -> dict:
        return {"standoff_mm": float(self.standoff_mm), "frame": "board (the work's frame)",
                "with_correction_rms_mm": self.corrected_rms_mm,
                "without_correction_rms_mm": self.uncorrected_rms_mm,
                "with_correction_max_mm": float(np.max(self.corrected_mm)),
                "without_correction_max_mm": float(np.max(self.uncorrected_mm)),
                "postures": int(len(self.corrected_mm)),
                "meaning": "root-mean-square predicted error of a point at the stand-off along the camera axis, in "
                           "the board's frame, over the postures, from the full covariance (camera, board, "
                           "kinematics, noise); without correction: the camera-only calibration with the nominal "
                           "arm, whose identified deviations stay in the error"}


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
    g = invert_transforms(target)[None] @ robot.forward_transform(joints_deg) @ x[None]
    return g[:, :3, :3] @ np.array([0.0, 0.0, standoff_mm]) + g[:, :3, 3]


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


def predicted_standoff(ident, joints_deg=None, standoff_mm: float = DEFAULT_STANDOFF_MM) -> StandoffError:
    """The predicted stand-off error of an :class:`~handeye.calibration.arm_identification.ArmIdentification`
    with and without its correction, at ``joints_deg`` (default: the session's postures)."""
    from ..robot import load_robot  # noqa: PLC0415

    sol = ident.camera_only
    robot = load_robot(ident.robot)
    joints = np.asarray(ident.joints_deg if joints_deg is None else joints_deg, float)
    columns = parameter_jacobian(robot, joints)[:, :, ident.fitted]
    corrected = corrected_robot(robot, ident.values)
    jac_k = _jacobian(corrected, joints, ident.x, ident.target, columns, standoff_mm)
    var_k = np.einsum("nij,jk,nik->n", jac_k, ident.covariance, jac_k)
    # without: the camera-only pose with the nominal arm
    jac_0 = _jacobian(robot, joints, sol.fit.x, sol.fit.target, columns, standoff_mm)
    bias = (standoff_points(robot, joints, sol.fit.x, sol.fit.target, standoff_mm)
            - standoff_points(corrected, joints, ident.x, ident.target, standoff_mm))
    var_0 = np.einsum("nij,jk,nik->n", jac_0[:, :, :12], sol.fit.covariance, jac_0[:, :, :12])
    m = jac_0[:, :, :12] @ ident.absorb - jac_0[:, :, 12:]
    var_u = np.einsum("nij,jk,nik->n", m, ident.covariance[12:, 12:], m)
    points = (robot.forward_transform(joints) @ sol.fit.x)[:, :3, :] @ np.array([0.0, 0.0, standoff_mm, 1.0])
    return StandoffError(float(standoff_mm), np.sqrt(np.maximum(var_k, 0.0)),
                         np.sqrt(np.sum(bias ** 2, axis=1) + var_0 + np.maximum(var_u, 0.0)), points)


def measured_standoff(true_robot, x_true, target_true, robot, ident, joints_deg,
                      standoff_mm: float = DEFAULT_STANDOFF_MM) -> tuple[np.ndarray, np.ndarray]:
    """The actual errors ``(n,)`` of the stand-off point against a known truth, with and without correction."""
    truth = standoff_points(true_robot, joints_deg, x_true, target_true, standoff_mm)
    sol = ident.camera_only
    without = standoff_points(robot, joints_deg, sol.fit.x, sol.fit.target, standoff_mm)
    with_ = standoff_points(corrected_robot(robot, ident.values), joints_deg, ident.x, ident.target, standoff_mm)
    return np.linalg.norm(with_ - truth, axis=1), np.linalg.norm(without - truth, axis=1)
