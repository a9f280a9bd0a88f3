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
    but within the tolerance is no cause (``none``); its size is the JSON's ``size``. A controller tooldata
    other than SESSION's is ``tooldata`` (its difference and whether it is beyond the tolerance); it is
    the cause, with the difference as its size and the board check's diagnosis as ``board_check``, only
    beyond the tolerance."""
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
    tool = outcome.tool_finding
    if tool is None:
        return out
    found = {"held": _tool_values(tool["held"]), "session": _tool_values(tool["session"]), **tool["difference"].to_json()}
    if not tool["difference"].beyond:  # within the tolerance: said, and no cause
        return {**out, "tooldata": found}
    measured = dict(out)
    return {"cause": "tooldata", "joint": None, "translation_mm": found["translation_mm"],
            "rotation_deg": found["rotation_deg"], "alternatives": measured["alternatives"],
            "indistinguishable": [], "likelihood_ratio": None, "board_check": measured, "tooldata": found,
            "held": found["held"], "session": found["session"]}


def advice(outcome, diag: dict, session: str, config_arg: str) -> list[str]:
    """What to do, one line per finding."""
    if outcome.verdict == INCONCLUSIVE:
        return [f"inconclusive: {outcome.reason}"]
    lines = []
    cause = diag["cause"]
    tool = diag.get("tooldata")
    if tool is not None:
        apart = f"{_size(tool)} apart; the tolerance {outcome.tolerance.text()}"
        if tool["beyond_tolerance"]:
            reference = (outcome.tool_finding or {}).get("reference")
            lines.append(f"{_tooldata_advice(reference, tool, session, config_arg)} ({apart})")
        else:
            held = tool["held"]
            lines.append(f"the robot holds a different tHeCamera than {session} ({apart}): held {held['position_mm']} "
                         f"{held['quaternion_wxyz']}: within the tolerance, nothing to write")
    if cause == "tooldata":
        diag = diag["board_check"]
        cause = diag["cause"]
    if outcome.size is not None and not outcome.size.beyond:
        return lines + [f"ok: a change is statistically detectable ({outcome.size.text()}) but within the tolerance "
                        f"{outcome.tolerance.text()} ({outcome.tolerance.source}; verify.tolerance_mm / tolerance_deg of "
                        "the station config set it): nothing to do; its trend shows in the history (--history)"]
    if outcome.test is None or not outcome.test.drift or cause == "none":
        ok = "ok: the calibration still predicts the board within its noise; nothing to do"
        return lines if tool is not None and tool["beyond_tolerance"] else lines + [ok]
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


def _tooldata_advice(reference, diag: dict, session: str, config_arg: str) -> str:
    """The tooldata finding's line: restore the latest deliberate write-back, never undo one
    (``station.verify.reference``)."""
    held = f"held {diag['held']['position_mm']} {diag['held']['quaternion_wxyz']}"
    kind = getattr(reference, "kind", "session")
    if kind == "other":
        record = reference.record
        if _same_tool(record.get("tool"), diag["held"]):
            return (f"the robot holds the tool data written from {record['session']} at {record.get('time', '?')} (the "
                    f"latest write-back in the history), not {session}'s: check that calibration instead (handeye "
                    f"verify --against {record.get('of') or record['session']} {config_arg}); nothing to restore")
        return (f"the robot holds a tHeCamera ({held}) that neither {session} nor the latest write-back in the history "
                f"({record['session']} at {record.get('time', '?')}) wrote: restore that one (handeye writeback "
                f"{record['session']} {config_arg})")
    source = reference.folder if kind == "update" else session
    what = "the quick update written from " + source if kind == "update" else session
    return (f"the robot holds a different tHeCamera than {what}: {held}, {what} {diag['session']['position_mm']} "
            f"{diag['session']['quaternion_wxyz']}: restore it (handeye writeback {source} {config_arg})"
            + ("" if kind == "update" else " unless a later calibration was written on purpose"))


def _same_tool(tool, held: dict) -> bool:
    """The record's tool frame equals the held one to the controller's last digit (0.001 mm, 1e-6)."""
    try:
        return (np.max(np.abs(np.subtract(tool["position_mm"], held["position_mm"]))) <= 1.5e-3
                and np.max(np.abs(np.subtract(tool["quaternion_wxyz"], held["quaternion_wxyz"]))) <= 1.5e-6)
    except (KeyError, TypeError, ValueError):
        return False


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
        "reference": _reference_json(outcome),
        "simulated_robot_time_s": outcome.motion_s,  # the plan's motion model, on every station
        "capture_robot_time_s": outcome.capture_motion_s,
        "standoff": getattr(outcome, "standoff", None),  # against calibrate --kinematics's prediction
    }


def _reference_json(outcome) -> dict:
    """What the check compared against: ``{"kind": "session"|"update"|"other", "written_from", "written_at"}``."""
    reference = getattr(outcome, "reference", None)
    record = getattr(reference, "record", None) or {}
    return {"kind": getattr(reference, "kind", "session"), "written_from": record.get("session"),
            "written_at": record.get("time")}


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
    from .standoff_check import standoff_line

    standoff = standoff_line(data.get("standoff"))
    return lines + ([standoff] if standoff else []) + advice_lines


def _size(d: dict) -> str:
    return f"{d['translation_mm']:.3f} mm / {d['rotation_deg']:.4f} deg"


def _name(e: dict) -> str:
    return f"joint {e['joint']}" if e["cause"] == "joint" else e["cause"]
