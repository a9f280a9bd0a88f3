"""The arm's kinematics in a calibration (``calibrate --kinematics``, the station's ``kinematics.identify``):
the identification, its JSON and its words.

The numbers are the calibration room's (``calibration.arm_identification``, ``calibration.standoff``);
here they become the result's ``kinematics`` entry and the lines of the text summary.
"""

from __future__ import annotations

import math

import numpy as np

from ..base import CalibrationError

__all__ = ["identify_outcome", "kinematics_json", "kinematics_lines", "hidden_offsets", "demo_lines"]


def identify_outcome(outcome, standoff_mm: float = 750.0):
    """The identification and the predicted stand-off error of a calibrated session (``outcome``: a
    ``CalibrationOutcome`` or an ``Assessment``, anything with the ``problem`` solved).

    Returns
    -------
    ident : ArmIdentification
    standoff : StandoffError or None
        None for eye-to-hand sessions (the stand-off is along a camera on the flange).

    Raises
    ------
    CalibrationError
        A session without joint angles of a known robot, in one line.
    """
    from ..calibration import identify_arm
    from ..calibration import EYE_IN_HAND
    from ..calibration import predicted_standoff

    problem = outcome.problem
    if problem is None or problem.joints_deg is None or problem.robot is None:
        raise CalibrationError("--kinematics needs the joint angles of every posture and the robot model in the "
                               "session: capture it with the station (it records them)")
    try:
        ident = identify_arm(problem)
    except ValueError as exc:
        raise CalibrationError(str(exc)) from None
    standoff = predicted_standoff(ident, standoff_mm=standoff_mm) if problem.setup == EYE_IN_HAND else None
    return ident, standoff


def _is_length(name: str) -> bool:
    return name[0] in "ad" and not name.startswith("alpha")


def _value(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def kinematics_json(ident, standoff=None) -> dict:
    """The result's ``kinematics`` entry.

    ``joint_zero_deg`` / ``sigma_deg``: the six controller zero offsets and their one-sigmas, null where
    not identified; ``links_mm``: the identified DH lengths (value and sigma), ``link_twists_deg`` the
    identified DH twists; ``not_identifiable``: every parameter the data cannot see (or see too weakly),
    with why.
    """
    reported = ident.reported_values()
    names = ident.names
    zeros = [names.index(f"zero{i}") for i in range(1, len(names) // 4 + 1)]
    out = {
        "joint_zero_deg": [_value(reported[j]) for j in zeros],
        "sigma_deg": [_value(ident.sigma[j]) if ident.status[j] == "identified" else None for j in zeros],
        "links_mm": {names[j]: {"value": float(ident.values[j]), "sigma": float(ident.sigma[j])}
                     for j in range(len(names)) if ident.status[j] == "identified" and _is_length(names[j])},
        "link_twists_deg": {names[j]: {"value": float(ident.values[j]), "sigma": float(ident.sigma[j])}
                            for j in range(len(names))
                            if ident.status[j] == "identified" and names[j].startswith("alpha")},
        "not_identifiable": [{"parameter": names[j], "status": ident.status[j], "reason": ident.reasons[names[j]]}
                             for j in range(len(names)) if ident.status[j] != "identified"],
        "correlated": [{"parameters": [a, b], "correlation": c} for a, b, c in ident.correlations],
        "camera_pose_change": _pose_change(ident),
        "consistent_with_zero": _zero_test(ident),
        "prior": {"length_mm": float(ident.prior_sigma[0]), "angle_deg": float(ident.prior_sigma[3])},
        "postures": int(ident.keep.sum()),
        "meaning": "deviations of the arm from its DH table, estimated with the camera and board poses: zero offsets "
                   "of the controller axes (the axis stands this much further than its angle) and DH lengths and "
                   "twists; one sigma; null: not identified (not_identifiable says why)",
    }
    if standoff is not None:
        out["standoff_error"] = standoff.to_dict()
    return out


#: Level of the chi-square tests of the kinematics entry (offsets against zero, the camera's change).
TEST_LEVEL = 0.01


def _zero_test(ident) -> dict:
    """Whether the identified offsets together are consistent with an exact arm: ``u^T Σ_uu^-1 u``
    against the chi-square quantile (``TEST_LEVEL``, one degree of freedom per identified parameter)."""
    from scipy.stats import chi2

    ok = [i for i, j in enumerate(ident.fitted) if ident.status[j] == "identified"]
    if not ok:
        return {"consistent": True, "statistic": 0.0, "limit": 0.0, "parameters": 0,
                "statement": "consistent with zero: no parameter identified"}
    u = ident.values[ident.fitted][ok]
    cov = ident.covariance[12:, 12:][np.ix_(ok, ok)]
    stat = float(u @ np.linalg.solve(cov, u))
    limit = float(chi2.ppf(1.0 - TEST_LEVEL, len(ok)))
    consistent = stat <= limit
    words = (f"consistent with zero: chi-square {stat:.1f} <= {limit:.1f} ({len(ok)} parameters, 1 % level)"
             if consistent else
             f"not consistent with zero: chi-square {stat:.1f} > {limit:.1f} ({len(ok)} parameters, 1 % level): "
             "the arm deviates from its DH table")
    return {"consistent": consistent, "statistic": stat, "limit": limit, "parameters": len(ok), "statement": words,
            "meaning": "the identified offsets together against an exact arm (chi-square, 1 % level): true means the "
                       "data show no deviation from the DH table"}


def _pose_change(ident) -> dict:
    """How far the camera pose moved from the camera-only fit, against its one-sigma."""
    from ..calibration import twist_between

    x0 = ident.camera_only.fit.x
    delta = twist_between(x0, ident.x)
    rot = x0[:3, :3]
    shift = rot @ delta[:3]
    turn = np.degrees(rot @ delta[3:])
    cov = ident.covariance[:6, :6]
    sigma_t = np.sqrt(np.diag(rot @ cov[:3, :3] @ rot.T))
    sigma_r = np.degrees(np.sqrt(np.diag(rot @ cov[3:, 3:] @ rot.T)))
    from scipy.stats import chi2

    distance = float(delta @ np.linalg.solve(cov, delta))
    in_sigma = float(np.sqrt(np.mean(delta ** 2 / np.diag(cov))))
    return {"translation_mm": [float(v) for v in shift], "rotation_deg": [float(v) for v in turn],
            "sigma_translation_mm": [float(v) for v in sigma_t], "sigma_rotation_deg": [float(v) for v in sigma_r],
            "rms_in_sigmas": in_sigma,
            "mahalanobis_squared": distance, "within_uncertainty": distance <= float(chi2.ppf(1.0 - TEST_LEVEL, 6)),
            "meaning": "the camera pose with the kinematics minus the camera-only one (tool0 axes), against the "
                       "one-sigma of the pose with the kinematics; rms_in_sigmas: the root-mean-square of the six "
                       "components over their one-sigmas; within_uncertainty: chi-square, 6 degrees of freedom, 1 % "
                       "level"}


def kinematics_lines(ident, standoff=None) -> list[str]:
    """The text summary's lines."""
    lines = ["Arm kinematics (identified with the camera; one sigma):"]
    for axis in range(1, len(ident.names) // 4 + 1):
        j = ident.names.index(f"zero{axis}")
        if ident.status[j] == "identified":
            lines.append(f"  J{axis} zero  {ident.values[j]:+.4f} deg  ± {ident.sigma[j]:.4f}")
        else:
            lines.append(f"  J{axis} zero  not identifiable: {ident.reasons[ident.names[j]]}")
    links = [f"{n} {ident.values[j]:+.3f} ± {ident.sigma[j]:.3f} mm" for j, n in enumerate(ident.names)
             if ident.status[j] == "identified" and _is_length(n)]
    if links:
        lines.append("  links  " + ", ".join(links))
    twists = [f"{n} {ident.values[j]:+.4f} ± {ident.sigma[j]:.4f} deg" for j, n in enumerate(ident.names)
              if ident.status[j] == "identified" and n.startswith("alpha")]
    if twists:
        lines.append("  twists " + ", ".join(twists))
    other = [n for j, n in enumerate(ident.names) if ident.status[j] != "identified" and not n.startswith("zero")]
    if other:
        lines.append("  not identifiable here: " + ", ".join(other) + " (details in the JSON's kinematics)")
    lines.append("  offsets " + _zero_test(ident)["statement"])
    change = _pose_change(ident)
    lines.append(f"  camera pose moved by {change['rms_in_sigmas']:.2f} of its one-sigma (RMS over the six components) "
                 "against the camera-only calibration")
    if standoff is not None:
        lines.append(f"  point at the {standoff.standoff_mm:g} mm stand-off (board frame, RMS over the postures): "
                     f"{standoff.corrected_rms_mm:.3f} mm with the correction, {standoff.uncorrected_rms_mm:.3f} mm "
                     "without")
        low, high = standoff.interval(0.9, True)
        if math.isfinite(low):
            lines.append(f"    one calibration's actual RMS with the correction: {low:.3f}-{high:.3f} mm (9 times in 10; "
                         "the fit's error is the same at every posture)")
    return lines


def hidden_offsets(dh_deviation) -> dict:
    """The mock arm's hidden deviations (true minus nominal DH table ``(k, 4)``) as the identification
    names them: controller zero offsets (through the IRB 1400's coupling: serial 3 = controller 3 - 2)
    and DH lengths."""
    from ..robot import load_robot

    delta = np.asarray(dh_deviation, float)
    robot = load_robot("IRB1400") if delta.shape[0] == 6 else None
    theta = delta[:, 3]
    zeros = np.linalg.solve(robot.coupling, theta) if robot is not None else theta
    links = {f"{kind}{i + 1}": float(delta[i, c]) for i in range(len(delta)) for c, kind in ((0, "d"), (1, "a"))
             if delta[i, c] != 0}
    return {"joint_zero_deg": [float(v) for v in zeros], "links_mm": links,
            "twists_deg": {f"alpha{i + 1}": float(v) for i, v in enumerate(delta[:, 2]) if v != 0}}


def demo_lines(entry: dict) -> list[str]:
    """The demo's table: identified joint zeros (one sigma) next to the mock arm's hidden ones."""
    hidden = entry.get("hidden") or {}
    lines = ["", "Arm kinematics   identified (deg)         hidden (deg)"]
    for axis in range(6):
        value, sigma = entry["joint_zero_deg"][axis], entry["sigma_deg"][axis]
        shown = f"{value:+.4f} ± {sigma:.4f}" if value is not None else "not identifiable"
        true = hidden.get("joint_zero_deg", [None] * 6)[axis]
        lines.append(f"  J{axis + 1} zero       {shown:<24s} " + ("" if true is None else f"{true:+.4f}"))
    for name, item in entry["links_mm"].items():
        true = hidden.get("links_mm", {}).get(name, 0.0)
        lines.append(f"  {name:<14s} {item['value']:+.3f} ± {item['sigma']:.3f} mm{'':<6s} {true:+.3f} mm")
    if "standoff_error" in entry:
        s = entry["standoff_error"]
        lines.append(f"  point at {s['standoff_mm']:g} mm: predicted {s['with_correction_rms_mm']:.3f} mm with the "
                     f"correction, {s['without_correction_rms_mm']:.3f} mm without")
    return lines
