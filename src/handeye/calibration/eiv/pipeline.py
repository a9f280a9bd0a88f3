"""The default estimator from start to result (:func:`solve_eiv`): start, ML fit with the outlier
loop, the kinematic-deviation and board-centre tests, covariance and cross-validation."""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass

import numpy as np

from ..problem import MIN_POSTURES, HandEyeProblem
from .centre import _centre_test
from .cross_validation import ml_cross_validation
from .fit import MLFit, fit_ml, initial_board_pose
from .model import Observations, observations
from .outliers import _outlier_flags
from .start import _compact_residuals, _start, board_pose_angle_gaps_deg

if TYPE_CHECKING:
    from collections.abc import Callable


@dataclass(frozen=True)
class EivSolution:
    """What :func:`solve_eiv` returns: the answer and everything the result reports.

    ``x``, ``outliers`` and ``residuals_mm`` as in :class:`~handeye.calibration.robust.RobustSolution`
    (what every ``estimator`` method returns), the residuals measured against the fitted board ``T``
    (:func:`~handeye.calibration.eiv.start._compact_residuals`).

    Attributes
    ----------
    fit : MLFit
        Over the inliers.
    observations : Observations
    uncertainty : dict
    details : dict
    cross_validation : dict or None
        ``CrossValidation.to_dict`` with the systematic-error verdict: the ratio test, or the
        arm's kinematic deviations found by the likelihood-ratio test.
    cv : CrossValidation or None
    """

    x: np.ndarray
    outliers: np.ndarray
    residuals_mm: np.ndarray
    fit: MLFit
    observations: Observations
    uncertainty: dict
    details: dict
    cross_validation: dict | None
    cv: object | None = None


def _parent_covariance(fit: MLFit) -> np.ndarray:
    """Covariance of (δt mm, δθ deg) of ``X`` in its parent frame (``t + R ρ``, ``exp(Rφ) R``)."""
    rot = fit.x[:3, :3]
    block = np.zeros((6, 6))
    block[:3, :3] = rot
    block[3:, 3:] = rot
    cov = block @ fit.covariance[:6, :6] @ block.T
    scale = np.array([1.0, 1.0, 1.0, 180.0 / np.pi, 180.0 / np.pi, 180.0 / np.pi])
    return cov * np.outer(scale, scale)


def _noise_report(obs: Observations, fit: MLFit) -> dict:
    """The estimated noise levels, in the units an operator reads."""
    out: dict = {"camera": {}, "robot": {}}
    if obs.corner is not None:
        out["camera"]["corner_isotropic_mm"] = float(np.sqrt(obs.corner.isotropic_mm2))
        out["camera"]["stereo_pixel_px"] = float(np.sqrt(obs.corner.pixel_px2))
        if obs.point_cov is None:
            raise ValueError("corner observations without corner covariances (eiv.model.observations sets both)")
        out["camera"]["corner_rms_mm"] = float(np.sqrt(np.mean(np.trace(obs.point_cov, axis1=-2, axis2=-1))))
        out["camera"]["degrees_of_freedom"] = int(obs.corner.dof)
    board_cov = obs.board_cov.copy()
    if "camera_centre_mm" in obs.notes:  # tilt and spin turn the board about this board point
        out["camera"]["rotation_centre_mm"] = [float(v) for v in obs.notes["camera_centre_mm"]]
    for comp, theta in zip(obs.components, fit.theta):
        if comp.name == "joint":
            out["robot"]["joint_deg"] = float(np.sqrt(theta))
        elif comp.name == "flange_rotation":
            out["robot"]["flange_rotation_deg"] = float(np.degrees(np.sqrt(theta)))
        elif comp.name == "flange_translation":
            out["robot"]["flange_translation_mm"] = float(np.sqrt(theta))
        elif comp.name == "camera_tilt":
            out["camera"]["board_tilt_deg"] = float(np.degrees(np.sqrt(theta)))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "camera_spin":
            out["camera"]["board_spin_deg"] = float(np.degrees(np.sqrt(theta)))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "camera_depth":
            out["camera"]["board_depth_mm"] = float(np.sqrt(theta))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "position":
            out["position_mm"] = float(np.sqrt(theta))
            out["position_note"] = "isotropic position noise of the flange or of the board: the data cannot tell which"
            board_cov = board_cov + theta * comp.structure
    hand = sum((theta * comp.structure for comp, theta in zip(obs.components, fit.theta) if comp.side == "hand"),
               np.zeros((obs.n, 6, 6)))
    out["robot"]["flange_position_rms_mm"] = float(np.sqrt(np.mean(np.trace(hand[:, :3, :3], axis1=1, axis2=2))))
    out["robot"]["flange_rotation_rms_deg"] = float(np.degrees(np.sqrt(np.mean(np.trace(hand[:, 3:, 3:], axis1=1, axis2=2)))))
    out["camera"]["board_position_rms_mm"] = float(np.sqrt(np.mean(np.trace(board_cov[:, :3, :3], axis1=1, axis2=2))))
    out["camera"]["board_rotation_rms_deg"] = float(np.degrees(np.sqrt(np.mean(np.trace(board_cov[:, 3:, 3:], axis1=1, axis2=2)))))
    return out


def _uncertainty(fit: MLFit, kinematic: bool) -> dict:
    """The result's ``uncertainty`` entry: one-sigma values and the covariance of X in its parent frame."""
    cov = _parent_covariance(fit)
    return {
        "translation_mm": [float(v) for v in np.sqrt(np.maximum(np.diag(cov)[:3], 0.0))],
        "rotation_deg": [float(v) for v in np.sqrt(np.maximum(np.diag(cov)[3:], 0.0))],
        "covariance": [[float(v) for v in row] for row in cov],
        "covariance_units": "x, y, z (mm) and rotations about x, y, z (deg) of the camera pose in its parent frame",
        "level": "one sigma from the maximum-likelihood covariance with noise levels estimated from the data"
                 + ("; includes the uncertainty of the arm's kinematic deviations (details.kinematics)" if kinematic
                    else "; the robot's errors modelled as independent from posture to posture")
                 + "; cross_validation checks it on held-out postures",
    }


def solve_eiv(problem: HandEyeProblem, progress: Callable[[int, int, str], object] | None = None, folds: int | None = None) -> EivSolution:
    """The default estimator: robust start, ML fit with outlier loop, covariance and cross-validation.

    Parameters
    ----------
    problem : HandEyeProblem
    progress : callable, optional
        ``progress(done, total, label)`` after each stage (start, each fit round, each fold).
    folds : int, optional
        Cross-validation folds (default ``crossval.DEFAULT_FOLDS``; 0 skips the cross-validation).
    """
    from ..crossval import DEFAULT_FOLDS  # noqa: PLC0415
    from ..refine import ANGLE_GAP_FLOOR_DEG, RESIDUAL_FLOOR_MM, at_most_half, keep_majority, robust_outliers  # noqa: PLC0415

    folds = DEFAULT_FOLDS if folds is None else folds
    n = problem.n
    report = progress or (lambda done, total, label: None)
    total = 3 + folds
    obs = observations(problem)
    gaps = board_pose_angle_gaps_deg(obs.hand, obs.board)
    gap_flags = keep_majority(robust_outliers(gaps, ANGLE_GAP_FLOOR_DEG), MIN_POSTURES)
    x, start = _start(problem, obs, gap_flags)
    report(1, total, f"start: {start['method']} on {start['postures']} postures")
    # gross outliers of the start: point residuals far out of the others' spread
    start_target = initial_board_pose(obs.subset(~gap_flags), x)
    start_res = _compact_residuals(problem, x, start_target)
    flags = at_most_half(gap_flags | robust_outliers(start_res, RESIDUAL_FLOOR_MM), start_res)
    fit = None
    rounds = 0
    kinematic = False  # posture-independent robot errors until the test below says otherwise
    tested = obs.kinematic is None
    lr = centre = None
    for rounds in range(1, MAX_ROUNDS + 2):
        keep = ~flags
        if fit is None:
            fit = fit_ml(obs, x, keep=keep, kinematic=kinematic)
        else:  # warm start from the previous round
            fit = fit_ml(obs, x, fit.target, fit.theta, keep=keep, kinematic=kinematic, kinematic0=fit.kinematic,
                         kinematic_var0=fit.kinematic_var)
        if not tested:
            # Kinematic deviations of the arm (the same at every posture): kept only when they raise
            # the restricted likelihood significantly (likelihood ratio above KINEMATIC_LR).
            tested = True
            kin_fit = fit_ml(obs, fit.x, fit.target, fit.theta, keep=keep, kinematic=True)
            lr = 2.0 * (kin_fit.loglik - fit.loglik)
            if lr > KINEMATIC_LR:
                fit, kinematic = kin_fit, True
        if centre is None:  # board poses only: the board's rotation noise about a fitted centre (CENTRE_LR)
            obs, fit, centre = _centre_test(obs, fit, keep, kinematic)
        x = fit.x
        new_flags = _outlier_flags(problem, obs, fit, keep, kinematic, gaps, gap_flags)
        report(1 + rounds, total + rounds, f"ML fit, round {rounds}: {int(new_flags.sum())} outlier postures")
        if n - new_flags.sum() < MIN_POSTURES or np.array_equal(new_flags, flags) or rounds > MAX_ROUNDS:
            break
        flags = new_flags
    if fit is None or centre is None:  # the loop runs at least once and sets both
        raise RuntimeError("the ML fit ran no round")
    keep = ~flags
    residual_mm = _compact_residuals(problem, fit.x, fit.target)
    uncertainty = _uncertainty(fit, kinematic)
    cv = cv_dict = None
    if folds and keep.sum() >= max(2 * MIN_POSTURES, folds):
        cv = ml_cross_validation(obs, fit, keep, folds, kinematic)
        cv_dict = cv.to_dict(problem.posture_ids)
        if kinematic:
            cv_dict["systematic"] = True
            cv_dict["advice"] = KINEMATIC_ADVICE + ("; " + cv_dict["advice"] if "advice" in cv_dict else "")
        report(total + rounds, total + rounds, "cross-validation done")
    details = _details(problem, obs, fit, start, rounds, _kinematic_report(obs, fit, kinematic, lr), centre, gaps)
    return EivSolution(fit.x, flags, residual_mm, fit, obs, uncertainty, details, cv_dict, cv)


def _details(problem: HandEyeProblem, obs: Observations, fit: MLFit, start: dict, rounds: int, kinematics: dict,
             centre: dict, gaps: np.ndarray) -> dict:
    """The result's ``details`` entry of the default estimator."""
    return {
        "estimator": "maximum likelihood, errors in variables (calibration/eiv/)",
        "start": start,
        "outlier_rounds": rounds,
        "fit": {"iterations": int(fit.iterations), "converged": bool(fit.converged), "mode": obs.mode,
                "components": {c.name: float(t) for c, t in zip(obs.components, fit.theta)}},
        "kinematics": kinematics,
        "camera_centre": centre,
        "noise": _noise_report(obs, fit),
        "mahalanobis": {str(int(i)): float(d) for i, d in zip(problem.posture_ids, fit.mahalanobis)},
        "angle_gap_deg": {str(int(i)): float(g) for i, g in zip(problem.posture_ids, gaps)},
        "target_pose": {"position_mm": [float(v) for v in fit.target[:3, 3]],
                        "rotation_matrix": [[float(v) for v in row] for row in fit.target[:3, :3]]},
    }


MAX_ROUNDS = 5


KINEMATIC_ADVICE = (
    "the robot's errors are systematic: its kinematics differ from the nominal model (a likelihood-ratio test "
    "finds DH deviations, details.kinematics). They were estimated with the camera pose and their uncertainty is "
    "in the one-sigma values; positions the controller computes with its nominal model keep these errors: calibrate "
    "the robot, or measure in postures near the calibration postures")


#: Likelihood ratio above which the arm's kinematic deviations enter the model (chi-square with two
#: degrees of freedom: p = 0.001).
KINEMATIC_LR = 13.8


def _kinematic_report(obs: Observations, fit: MLFit, used: bool, lr) -> dict:
    if obs.kinematic is None:
        if "joint_mismatch" in obs.notes:
            return {"modelled": False, "reason": f"{obs.notes['joint_mismatch']}: the robot's noise is modelled on "
                                                 "the flange poses instead of the joints"}
        return {"modelled": False, "reason": "no joint angles with a known robot model in the session"}
    out = {"modelled": bool(used), "likelihood_ratio": None if lr is None else float(lr), "threshold": KINEMATIC_LR}
    if used:
        out["sigma_length_mm"] = float(np.sqrt(fit.kinematic_var[0]))
        out["sigma_angle_deg"] = float(np.sqrt(fit.kinematic_var[1]))
        names = [f"{p}{axis + 1}" for axis in range(len(fit.kinematic) // 4) for p in ("d", "a", "alpha", "theta")]
        out["dh_deviation"] = {name: float(v) for name, v in zip(names, fit.kinematic)}
        out["note"] = ("the arm differs from its nominal kinematics; deviations that are the same at every posture "
                       "are estimated with the camera pose and their uncertainty is in the one-sigma values")
    return out
