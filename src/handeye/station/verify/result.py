"""A check's outcome as the operator reads it: the diagnosis, what to do, the JSON and the text.

Presenters only: everything here formats what ``station.verify.check.VerifyOutcome`` holds.
"""

from __future__ import annotations

import numpy as np

from ...calibration import likelihood_ratio, same_effect
from .check import DRIFT, INCONCLUSIVE
from .tolerance import explained

__all__ = ["diagnosis", "advice", "outcome_json", "outcome_lines", "update_json"]


def _explanation(e, best=None) -> dict:
    out = {"cause": e.cause, "joint": e.joint, "translation_mm": round(e.translation_mm, 4),
           "rotation_deg": round(e.rotation_deg, 5), "shift_mm": [round(float(v), 4) for v in e.shift_mm],
           "turn_deg": [round(float(v), 5) for v in e.turn_deg], "chi2": round(e.chi2, 3), "bic": round(e.bic, 3)}
    if best is not None:
        out["likelihood_ratio_of_best"] = likelihood_ratio(best, e)
    return out


def _tool_values(tool) -> dict:
    return {"position_mm": [float(v) for v in tool.position_mm], "quaternion_wxyz": [float(v) for v in tool.quaternion_wxyz]}


def diagnosis(outcome) -> dict:
    """The ``diagnosis`` of the JSON: ``cause``, ``joint``, sizes, ``alternatives`` (best first),
    ``indistinguishable`` (explanations these data cannot tell from the cause). A change the test finds
    but within the tolerance is no cause (``none``); its size is the JSON's ``size``."""
    ranked = [e for e in outcome.explanations if e.cause != "none"]
    out = {"cause": "none", "joint": None, "translation_mm": 0.0, "rotation_deg": 0.0, "alternatives": [],
           "indistinguishable": [], "likelihood_ratio": None}
    if outcome.beyond_tolerance and ranked:
        best = ranked[0]
        out.update(_explanation(best))
        out["alternatives"] = [_explanation(e, best) for e in ranked[1:]]
        out["likelihood_ratio"] = likelihood_ratio(best, ranked[1]) if len(ranked) > 1 else None
        out["indistinguishable"] = [e.name for e in same_effect(ranked, best)]
        out["explained"] = explained(best, outcome.test)
    elif outcome.explanations:
        out["alternatives"] = [_explanation(e) for e in ranked[:3]]
    if outcome.tool_finding is not None:
        measured = dict(out)
        out = {"cause": "tooldata", "joint": None, "translation_mm": measured["translation_mm"],
               "rotation_deg": measured["rotation_deg"], "alternatives": measured["alternatives"],
               "indistinguishable": [], "likelihood_ratio": None, "board_check": measured,
               "held": _tool_values(outcome.tool_finding["held"]),
               "session": _tool_values(outcome.tool_finding["session"])}
    return out


def advice(outcome, diag: dict, session: str, config_arg: str) -> list[str]:
    """What to do, one line per finding."""
    if outcome.verdict == INCONCLUSIVE:
        return [f"inconclusive: {outcome.reason}"]
    lines = []
    cause = diag["cause"]
    if cause == "tooldata":
        lines.append(f"the robot holds a different tHeCamera than {session}: held {diag['held']['position_mm']} "
                     f"{diag['held']['quaternion_wxyz']}, {session} {diag['session']['position_mm']} "
                     f"{diag['session']['quaternion_wxyz']}: restore it (handeye writeback {session} {config_arg}) "
                     "unless a later calibration was written on purpose")
        diag = diag["board_check"]
        cause = diag["cause"]
    if outcome.size is not None and not outcome.size.beyond:
        return lines + [f"ok: a change is statistically detectable ({outcome.size.text()}) but within the tolerance "
                        f"{outcome.tolerance.text()} ({outcome.tolerance.source}; verify.tolerance_mm / tolerance_deg of "
                        "the station config set it): nothing to do; its trend shows in the history (--history)"]
    if outcome.test is None or not outcome.test.drift or cause == "none":
        return lines or ["ok: the calibration still predicts the board within its noise; nothing to do"]
    also = f" (these data cannot tell it from: {', '.join(diag['indistinguishable'])})" if diag["indistinguishable"] else ""
    size = f"{diag['translation_mm']:.3f} mm, {diag['rotation_deg']:.4f} deg"
    if cause == "board":
        lines.append(f"the board moved ({size}){also}: the tooldata is still right: nothing to write")
    elif cause == "camera":
        folder = outcome.folder
        lines.append(f"the camera moved on the flange ({size}){also}: recalibrate (handeye capture), or accept the quick "
                     f"update: handeye writeback {folder} {config_arg}")
    elif cause == "joint":
        lines.append(f"the zero of joint {diag['joint']} moved by {diag['turn_deg'][2]:+.4f} deg{also}: check the "
                     "revolution counters / calibrate the axis; do not write tooldata")
    if not diag.get("explained", True):
        lines.append("no single explanation accounts for all of the discrepancy: more than one thing changed? "
                     "recalibrate")
    return lines


def update_json(update, thresholds) -> dict | None:
    """The quick update's entry: the new camera pose, its one-sigma values, and whether they pass."""
    if update is None:
        return None
    from ...geometry import pose_from_transform

    passed = bool(np.max(update.sigma_translation_mm) <= thresholds.max_sigma_translation_mm
                  and np.max(update.sigma_rotation_deg) <= thresholds.max_sigma_rotation_deg)
    return {"camera_pose": {"parent": "tool0", **pose_from_transform(update.x)},
            "uncertainty": {"translation_mm": [float(v) for v in update.sigma_translation_mm],
                            "rotation_deg": [float(v) for v in update.sigma_rotation_deg],
                            "covariance": [[float(v) for v in row] for row in update.covariance],
                            "reduced_chi2": round(float(update.reduced_chi2), 4)},
            "within_thresholds": passed,
            "advice": "write it with handeye writeback" if passed else
            "its uncertainty is above the quality thresholds: recapture (handeye capture) and calibrate"}


def outcome_json(outcome, session: str, thresholds) -> dict:
    """The JSON of ``handeye verify --json``."""
    diag = diagnosis(outcome)
    test = outcome.test
    return {
        "verdict": outcome.verdict,
        "reason": outcome.reason,
        "session": session,
        "check_session": None if outcome.folder is None else str(outcome.folder),
        "postures": len(outcome.postures),
        "revisited": outcome.postures,
        "measured": outcome.measured,
        "test": None if test is None else {"statistic": test.statistic, "degrees_of_freedom": test.degrees,
                                           "p_value": test.p_value, "level": test.level,
                                           "statistically_detectable": bool(test.drift)},
        "tolerance": None if outcome.tolerance is None else outcome.tolerance.to_json(),
        "size": None if outcome.size is None else outcome.size.to_json(),
        "beyond_tolerance": None if test is None else outcome.beyond_tolerance,
        "diagnosis": diag,
        "quick_update": update_json(outcome.update, thresholds),
        "simulated_robot_time_s": outcome.motion_s,  # the plan's motion model, on every station
        "capture_robot_time_s": outcome.capture_motion_s,
    }


def outcome_lines(data: dict, advice_lines: list[str]) -> list[str]:
    """The text summary."""
    d = data["diagnosis"]
    lines = [f"verdict: {data['verdict'].upper()} ({data['reason']})"]
    if data["verdict"] == DRIFT and d["cause"] != "none":
        lr = d.get("likelihood_ratio")
        lines.append(f"most likely: {d['cause']}" + (f" {d['joint']}" if d.get("joint") else "")
                     + f", {d['translation_mm']:.3f} mm / {d['rotation_deg']:.4f} deg"
                     + (f", {lr:.3g} times more likely than the next ({_name(d['alternatives'][0])})" if lr else ""))
    q = data.get("quick_update")
    if q is not None:
        s = q["uncertainty"]
        lines.append(f"quick update: camera at {np.round(q['camera_pose']['position_mm'], 3).tolist()} mm, one sigma "
                     f"{max(s['translation_mm']):.3f} mm / {max(s['rotation_deg']):.4f} deg: {q['advice']}")
    return lines + advice_lines


def _name(e: dict) -> str:
    return f"joint {e['joint']}" if e["cause"] == "joint" else e["cause"]
