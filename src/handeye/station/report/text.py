"""The plain-text calibration summary an engineer reads at the station: a presenter of
``station.report.assessment.Assessment``. It formats what the assessment holds (the pose written as a
literal, quaternion and Euler angles) and never solves or judges."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ...calibration import pairs_used
from ...calibration import D_ORG_ALL_NAME, METRIC_MEANINGS
from ...rapid import pose_literal, rounded_pose
from .assessment import Assessment
from ..origin import origin_banner

__all__ = ["calibration_summary"]

_BAR = 30


def _residual_table(result) -> list[str]:
    """The posture residual of every posture as a bar (``quality_words.posture_residuals``)."""
    residuals, outliers = result.residuals_mm, result.outliers
    if not residuals:
        return []
    worst = max(residuals.values()) or 1.0
    median = float(np.median(list(residuals.values())))
    lines = ["Per-posture residual (mm):", f"  ({result.residuals_meaning})"]
    for index, value in residuals.items():
        bar = "#" * max(1, int(round(_BAR * value / worst)))
        flag = "  <- outlier" if index in outliers else ("  <- high" if value > 3 * median else "")
        lines.append(f"  {index:4d} {value:9.3f}  {bar}{flag}")
    return lines


def _origin_lines(origin: str) -> list[str]:
    banner = origin_banner(origin)
    if banner is None:
        return []
    word, text = banner
    return [f"*** {word} - {text} ***", ""]


def _quality_lines(assessment: Assessment) -> list[str]:
    r, scatter = assessment.result, assessment.d_org
    m = r.metrics
    lines = [f"  d_org   {scatter.mm:.3f} mm   {METRIC_MEANINGS['d_org']}",
             f"          {scatter.basis()}"]
    if scatter.incl_outliers_mm is not None:
        lines.append(f"  {D_ORG_ALL_NAME}  {scatter.incl_outliers_mm:.3f} mm   {METRIC_MEANINGS[D_ORG_ALL_NAME]} "
                     f"({assessment.problem.n} postures)")
    return lines + [
        f"  d_back  {m['d_back_mm']:.3f} mm   {METRIC_MEANINGS['d_back']}",
        f"  dR      {m['delta_r']:.5f}     {METRIC_MEANINGS['dR']}",
        f"  dt      {m['delta_t_mm']:.3f} mm   {METRIC_MEANINGS['dt']}",
        "  (d_back, dR and dt over the same postures as d_org" + _pairs_note(m) + ")",
    ]


def _pairs_note(metrics: dict) -> str:
    """``"; over 109888 of 49995000 posture pairs (...)"`` when a large session's pairs were sampled."""
    n, count = metrics.get("postures"), metrics.get("posture_pairs")
    if n is None or count is None or count >= n * (n - 1) // 2:
        return ""
    return f"; over {pairs_used(count, n)}"


def _closing_lines(r) -> list[str]:
    """Uncertainty, truth errors, outliers, per-posture residuals and the solve time."""
    lines = []
    if r.uncertainty is not None:
        u = r.uncertainty
        lines += ["", "Uncertainty (one sigma):",
                  "  position  x {:.3f}  y {:.3f}  z {:.3f} mm".format(*u["translation_mm"]),
                  "  rotation  about x {:.4f}  y {:.4f}  z {:.4f} deg".format(*u["rotation_deg"])]
    lines += _cross_validation_lines(r)
    if r.truth_errors is not None:
        lines += ["", "Against the synthetic truth:",
                  f"  rotation error {r.truth_errors['rotation_error_deg']:.4f} deg, "
                  f"translation error {r.truth_errors['translation_error_mm']:.3f} mm"]
    if r.outliers:
        lines += ["", f"Outlier postures (excluded from the solution): {', '.join(map(str, r.outliers))}",
                  "  check them: board partly hidden or misdetected, robot not at rest, wrong pose pairing"]
        lines += [f"  posture {i}: left out before solving: {reason}" for i, reason in r.excluded.items()]
    lines += [""] + _residual_table(r)
    d = r.details
    extra = ""
    start = d.get("start", d)
    if start.get("candidates"):
        extra = (f" ({start['candidates']} triplets, {start.get('exact_evaluations', 0)} scored exactly, "
                 f"chosen {start.get('selected_triplet')})")
    return lines + ["", f"Solve time {1000 * r.runtime_s:.1f} ms{extra}"]


def calibration_summary(assessment: Assessment) -> str:
    """Human-readable report of one calibration.

    Parameters
    ----------
    assessment : Assessment
        When it holds a failed verdict, the tframe literal is marked as not to be written into the robot.
    """
    r = assessment.result
    position, quaternion = rounded_pose(r.x)
    euler = Rotation.from_matrix(r.x[:3, :3]).as_euler("ZYX", degrees=True)
    frame = "tool0 (RAPID tooldata.tframe)" if r.parent == "tool0" else "base (camera fixed beside the robot)"
    literal = pose_literal(r.x)
    if assessment.verdict is not None and not assessment.verdict.passed:
        literal = f"FAIL - do not write this into the robot (verdict below): {literal}"
    lines = _origin_lines(assessment.origin) + [
        f"Session {assessment.session_path}: {len(r.residuals_mm)} postures"
        + (f" ({r.metrics['postures']} used)" if r.outliers else "") + f", {r.setup}, method {r.method}",
        "",
        f"Camera pose in {frame}:",
        f"  {literal}",
        f"  position  x {position[0]:.3f}  y {position[1]:.3f}  z {position[2]:.3f} mm",
        f"  rotation  q1..q4 {quaternion[0]:.6f} {quaternion[1]:.6f} {quaternion[2]:.6f} {quaternion[3]:.6f}"
        f"   (EulerZYX z {euler[0]:.4f}  y {euler[1]:.4f}  x {euler[2]:.4f} deg)",
        "",
        "Quality (lower is better):",
    ]
    scope = [""] + [assessment.verdict_scope] if assessment.verdict_scope else []
    return "\n".join(lines + _quality_lines(assessment) + _closing_lines(r) + _comparison_lines(assessment) + scope)


def _comparison_lines(assessment: Assessment) -> list[str]:
    """The method comparison, ranked by the held-out error, and why d_org may rank otherwise."""
    rows = assessment.comparison
    if not rows:
        return []
    lines = ["", "Method comparison (ranked by the held-out error; d_org in-sample, over the same postures):",
             "  method        held-out mm  d_org mm  d_pos mm  d_rot deg"]
    for row in rows:
        held_out = "n/a" if row["held_out_mm"] is None else f"{row['held_out_mm']:.3f}"
        name = row["method"] + (" *" if row["chosen"] else "")
        lines.append(f"  {name:<12}  {held_out:>11}  {row['d_org_mm']:8.3f}  {row['d_position_mm']:8.3f}  "
                     f"{row['d_rotation_deg']:9.4f}")
    lines.append("  (* = the chosen result)")
    if assessment.comparison_note:
        lines.append(f"  {assessment.comparison_note}")
    if assessment.rank_note:
        lines.append(f"  {assessment.rank_note}")
    lines += [f"  not compared: {reason}" for reason in assessment.comparison_failures.values()]
    return lines


def _cross_validation_lines(r) -> list[str]:
    """The default estimator's held-out accuracy, systematic-error verdict and estimated noise."""
    cv = r.cross_validation
    if not cv:
        return []
    lines = ["", f"Cross-validated accuracy ({cv['folds']}-fold, held-out postures):",
             f"  board points land {cv['rms_mm']:.3f} mm RMS from where the other postures put them"
             + (f" (the noise model predicts {cv['predicted_rms_mm']:.3f} mm)" if "predicted_rms_mm" in cv else "")]
    if cv.get("systematic"):
        lines.append(f"  SYSTEMATIC: {cv.get('advice', '')}")
    noise = r.details.get("noise", {})
    camera, robot = noise.get("camera", {}), noise.get("robot", {})
    parts = []
    if "corner_rms_mm" in camera:
        parts.append(f"camera corners {camera['corner_rms_mm']:.3f} mm RMS (stereo {camera.get('stereo_pixel_px', 0):.3f} px)")
    if "joint_deg" in robot:
        parts.append(f"robot joints {robot['joint_deg']:.4f} deg")
    if "flange_position_rms_mm" in robot:
        parts.append(f"flange {robot['flange_position_rms_mm']:.3f} mm RMS")
    if parts:
        lines.append("  estimated noise: " + ", ".join(parts))
    return lines
