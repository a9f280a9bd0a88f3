"""What the import says about its reading: the conventions in words, the record kept in the
session (``session.yaml`` under ``import:``) and the table of candidate readings it prints."""

from __future__ import annotations

import numpy as np

from .readings import POSE_WORDS, Reading, Side, SideReading

__all__ = ["side_words", "reading_words", "table_rows", "inference_record", "format_table"]

def table_rows(readings: list, chosen: Reading) -> list:
    """The candidates shown: the chosen rotation pair's eight readings, then the best of every other."""
    same = [r for r in readings if (r.robot, r.camera) == (chosen.robot, chosen.camera)]
    others = {}
    for r in readings:
        key = (r.robot, r.camera)
        if key == (chosen.robot, chosen.camera):
            continue
        if key not in others or (r.consistent, -r.axis_deg if np.isfinite(r.axis_deg) else -np.inf) > (
                others[key].consistent, -others[key].axis_deg if np.isfinite(others[key].axis_deg) else -np.inf):
            others[key] = r
    rest = sorted(others.values(), key=lambda r: (not r.consistent, r.gap_deg))[:6]
    return [chosen] + [r for r in same if r is not chosen] + rest


def inference_record(robot: Side, camera: Side, chosen: Reading, table: list, decided_by: set) -> dict:
    """The ``conventions`` (in words) and ``inference`` (figures, candidates) parts of the import record."""
    rr, cr = robot.readings[chosen.robot], camera.readings[chosen.camera]
    how = {"invariants": "the X-free invariants of AX = XB", "plausibility": "plausibility (which object rides on "
           "the flange, where the board is seen)", "declarations": "what the file declares",
           "flags": "the flags given"}
    return {
        "robot": side_words(robot, rr, chosen.robot_pose, chosen.units[0]),
        "camera": side_words(camera, cr, chosen.camera_pose, chosen.units[1]),
        "setup": chosen.setup,
        "decided_by": [how[k] for k in ("invariants", "plausibility", "declarations", "flags") if k in decided_by],
        "scores": {"angle_gap_deg": _round(chosen.gap_deg), "axis_misfit_deg": _round(chosen.axis_deg),
                   "translation_misfit": _round(chosen.translation), "pitch_ratio": _round(chosen.scale),
                   f"{chosen.flange_object}_from_flange_mm": _round(chosen.flange_offset_mm)},
        "candidates": [_row_record(robot, camera, r) for r in table],
    }


def _round(v, digits: int = 4):
    return round(float(v), digits) if v is not None and np.isfinite(v) else None


def _row_record(robot: Side, camera: Side, r: Reading) -> dict:
    return {
        "robot": f"{robot.readings[r.robot].short}, {POSE_WORDS[r.robot_pose]}, {r.units[0]}",
        "camera": f"{camera.readings[r.camera].short}, {POSE_WORDS[r.camera_pose]}, {r.units[1]}",
        "setup": r.setup,
        "angle_gap_deg": _round(r.gap_deg, 3),
        "axis_misfit_deg": _round(r.axis_deg, 3),
        "translation_misfit": _round(r.translation, 4),
        "flange_object_mm": _round(r.flange_offset_mm, 1),
        "view_spread_deg": _round(r.view_spread_deg, 1),
        "verdict": r.verdict,
    }


def format_table(record: dict) -> list:
    """The candidates of an import record as text lines (the table ``handeye import`` prints)."""
    rows = record.get("candidates") or []
    if not rows:
        return []
    head = ("robot", "camera", "set-up", "gap deg", "axis deg", "transl.", "on flange", "view", "verdict")
    body = []
    for r in rows:
        tr = r["translation_misfit"]
        body.append((r["robot"], r["camera"], r["setup"], _fmt(r["angle_gap_deg"], 2), _fmt(r["axis_misfit_deg"], 2),
                     "-" if tr is None else f"{100 * tr:.1f} %", _fmt(r["flange_object_mm"], 0) + " mm",
                     _fmt(r["view_spread_deg"], 0) + " deg", r["verdict"]))
    widths = [max(len(str(x[k])) for x in [head] + body) for k in range(len(head))]
    lines = ["  ".join(str(x[k]).ljust(widths[k]) for k in range(len(head))).rstrip() for x in [head] + body]
    return lines


def _fmt(v, digits: int) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def side_words(side: Side, reading: SideReading, direction: str, unit: str) -> str:
    """``robot poses read as flange in base, position in m converted to mm, Euler ZYX ...``."""
    position = "position in mm" if unit == "mm" else "position in m converted to mm"
    return f"{side.name} poses read as {POSE_WORDS[direction]}, {position}, {reading.words}"


def reading_words(robot: Side, camera: Side, r: Reading) -> str:
    rr, cr = robot.readings[r.robot], camera.readings[r.camera]
    return (f"{r.setup}, robot {POSE_WORDS[r.robot_pose]} ({rr.short}, {r.units[0]}), "
            f"camera {POSE_WORDS[r.camera_pose]} ({cr.short}, {r.units[1]})")
