"""The history of a station's checks: ``history.jsonl`` beside the sessions, one record per check.

Each ``handeye verify`` appends one JSON line (time, station, session, verdict, diagnosis, sizes);
``handeye writeback`` of a check's quick update appends a ``writeback`` record. The file is never
rewritten in place: an append writes the old lines and the new one to a temporary file that replaces
the old one atomically (``calibration.files.write_text_atomic``), so a kill leaves the old history or
the new one, never half a line. :func:`trend_png` draws it: the diagnosed change in mm and deg over
time against the quality thresholds, one marker per check, recalibrations marked.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from ..calibration.errors import OutputError
from ..calibration.files import read_text_file, write_text_atomic

__all__ = ["HISTORY_FILE", "append_record", "history_path", "read_history", "history_lines", "trend_png"]

HISTORY_FILE = "history.jsonl"


def history_path(session_dir) -> Path:
    """The history of the sessions beside ``session_dir``."""
    return Path(session_dir).resolve().parent / HISTORY_FILE


def read_history(path) -> list[dict]:
    """The records of a history file (none when it does not exist); a damaged line is skipped."""
    path = Path(path)
    if not path.is_file():
        return []
    out = []
    for line in read_text_file(path, "verify history", OutputError).splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if isinstance(record, dict):
            out.append(record)
    return out


def append_record(path, record: dict) -> dict:
    """Append ``record`` (with ``time`` added when missing) as one line; returns it."""
    path = Path(path)
    record = {"time": time.strftime("%Y-%m-%dT%H:%M:%S"), **record}
    old = read_text_file(path, "verify history", OutputError) if path.is_file() else ""
    if old and not old.endswith("\n"):
        old += "\n"
    write_text_atomic(path, old + json.dumps(record, sort_keys=False) + "\n")
    return record


def check_record(data: dict, station: str) -> dict:
    """The history record of a check (``verify_result.outcome_json``)."""
    d = data["diagnosis"]
    return {"kind": "verify", "station": station, "session": data["session"], "check_session": data["check_session"],
            "verdict": data["verdict"], "cause": d["cause"], "joint": d.get("joint"),
            "translation_mm": d["translation_mm"], "rotation_deg": d["rotation_deg"],
            "p_value": None if data["test"] is None else data["test"]["p_value"], "postures": data["postures"]}


def history_lines(records: list[dict]) -> list[str]:
    """One line per record, oldest first."""
    out = []
    for r in records:
        if r.get("kind") == "writeback":
            out.append(f"{r.get('time', '?')}  WRITEBACK     {r.get('session', '?')}  ({r.get('what', '')})")
            continue
        cause = r.get("cause", "?") + (f" {r['joint']}" if r.get("joint") else "")
        out.append(f"{r.get('time', '?')}  {str(r.get('verdict', '?')).upper():12s}  {Path(str(r.get('session', '?'))).name}"
                   f"  {cause:10s} {float(r.get('translation_mm') or 0):.3f} mm  {float(r.get('rotation_deg') or 0):.4f} deg")
    return out or ["no checks recorded yet"]


def trend_png(records: list[dict], limit_mm: float, limit_deg: float) -> bytes:
    """The trend: change in mm and deg per check over time, thresholds dashed, recalibrations (a new
    session, or a written quick update) as vertical lines."""
    from datetime import datetime

    from .report_figures import BLUE, GREY, RED, new_figure, style_axes, to_png

    fig = new_figure(8.0, 4.2, "constrained")
    axes = fig.subplots(2, 1, sharex=True)
    checks = [r for r in records if r.get("kind", "verify") == "verify"]
    when = [datetime.fromisoformat(r["time"]) for r in checks]
    colour = {"ok": BLUE, "drift": RED, "inconclusive": GREY}
    for ax, key, limit, unit in ((axes[0], "translation_mm", limit_mm, "mm"), (axes[1], "rotation_deg", limit_deg, "deg")):
        ax.plot(when, [float(r.get(key) or 0.0) for r in checks], color=GREY, linewidth=0.8)
        for t, r in zip(when, checks):
            ax.plot([t], [float(r.get(key) or 0.0)], marker="o", color=colour.get(r.get("verdict"), GREY))
        ax.axhline(limit, color=RED, linestyle="--", linewidth=1.0, label=f"threshold {limit:g} {unit}")
        ax.set_ylabel(f"change ({unit})")
        style_axes(ax)
    sessions = None
    for r in records:
        new_session = sessions is not None and r.get("session") != sessions
        if r.get("kind") == "writeback" or new_session:
            for ax in axes:
                ax.axvline(datetime.fromisoformat(r["time"]), color=GREY, linestyle=":", linewidth=1.2)
        sessions = r.get("session", sessions)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[0].set_title("checks: dot colour = verdict (blue ok, red drift, grey inconclusive); dotted = recalibration")
    return to_png(fig)
