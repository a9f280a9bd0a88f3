"""The history of a station's checks: ``history.jsonl`` beside the sessions, one record per check.

Each ``handeye verify`` appends one JSON line (time, station, session, verdict, diagnosis, sizes);
every ``handeye writeback`` (a calibration or a check's quick update) appends a ``writeback`` record
(``station.verify.reference``: the latest is what a check follows). The file is never
rewritten in place: an append writes the old lines and the new one to a temporary file that replaces
the old one atomically (``base.files.write_text_atomic``), so a kill leaves the old history or
the new one, never half a line; the read-add-rename holds an exclusive lock (``station.verify.file_lock``,
``history.jsonl.lock``), so checks and write-backs appending at once all keep their records.
A damaged record (not JSON, a line cut short, a time that is not an ISO date-time, a size that is not
a number) is skipped by :func:`load_history` and counted with its line number, never fatal: the
check's verdict and its report stand. :func:`trend_png` draws the history: the diagnosed change in mm
and deg over time against the quality thresholds, one marker per check, recalibrations marked.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from ...base import OutputError
from ...base import read_text_file, write_text_atomic
from .file_lock import exclusive_lock

__all__ = ["HISTORY_FILE", "History", "append_record", "history_path", "load_history", "read_history", "history_lines",
           "record_problem", "record_time", "trend_png"]

HISTORY_FILE = "history.jsonl"


def history_path(session_dir) -> Path:
    """The history of the sessions beside ``session_dir``."""
    return Path(session_dir).resolve().parent / HISTORY_FILE


@dataclass(frozen=True)
class History:
    """A history file as read: its sound records and the damaged lines skipped.

    Attributes
    ----------
    records : list of dict
        The sound records, in file order (oldest first).
    skipped : list of (int, str)
        ``(line number, counted from 1, what is wrong with it)`` of each damaged line.
    path : Path or None
    """

    records: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    path: Path | None = None

    def skipped_line(self) -> str | None:
        """One line naming the damaged records skipped (``None`` when there are none)."""
        if not self.skipped:
            return None
        n = len(self.skipped)
        shown = "; ".join(f"line {line}: {why}" for line, why in self.skipped[:5])
        more = f"; and {n - 5} more" if n > 5 else ""
        return (f"skipped {n} damaged record{'s' if n != 1 else ''} of {self.path or HISTORY_FILE} ({shown}{more}); "
                "the other records are shown: fix or delete those lines to keep them")


def record_time(value) -> datetime:
    """The time of a record (ISO 8601, ``Z`` allowed) as a naive local datetime.

    Raises
    ------
    ValueError
        ``value`` is not a string holding an ISO date-time.
    """
    if not isinstance(value, str):
        raise ValueError(f"time {value!r} is not a date-time string")
    when = datetime.fromisoformat(value[:-1] + "+00:00" if value.endswith("Z") else value)
    return when.astimezone().replace(tzinfo=None) if when.tzinfo is not None else when


def _is_size(value) -> bool:
    return value is None or (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value))


def record_problem(record) -> str | None:
    """What makes ``record`` unusable by the history's readers (``None`` when it is sound)."""
    if not isinstance(record, dict):
        return f"not a record (a JSON {type(record).__name__})"
    try:
        record_time(record.get("time"))
    except ValueError:
        return f"time {record.get('time')!r} is not an ISO date-time"
    kind = record.get("kind", "verify")
    if kind not in ("verify", "writeback"):
        return f"kind {kind!r} is neither verify nor writeback"
    texts = ("session", "what") if kind == "writeback" else ("session", "verdict", "cause")
    for key in texts:
        if key in record and record[key] is not None and not isinstance(record[key], str):
            return f"{key} {record[key]!r} is not text"
    if kind == "verify":
        for key in ("translation_mm", "rotation_deg", "p_value"):
            if not _is_size(record.get(key)):
                return f"{key} {record[key]!r} is not a number"
        if record.get("joint") is not None and (isinstance(record["joint"], bool) or not isinstance(record["joint"], int)):
            return f"joint {record['joint']!r} is not an axis number"
    return None


def load_history(path) -> History:
    """The history file at ``path`` (empty when it does not exist): each line a record, a damaged line
    (:func:`record_problem`, not JSON, a last line cut short) skipped and counted."""
    path = Path(path)
    if not path.is_file():
        return History(path=path)
    text = read_text_file(path, "verify history", OutputError)
    lines = text.splitlines()
    records, skipped = [], []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError:
            cut = number == len(lines) and not text.endswith("\n")
            skipped.append((number, "cut short (no line end: an append interrupted?)" if cut else "not JSON"))
            continue
        problem = record_problem(record)
        if problem is None:
            records.append(record)
        else:
            skipped.append((number, problem))
    return History(records, skipped, path)


def read_history(path) -> list[dict]:
    """The sound records of a history file (:func:`load_history`; damaged lines left out)."""
    return load_history(path).records


def append_record(path, record: dict) -> dict:
    """Append ``record`` (with ``time`` added when missing) as one line; returns it.

    The old lines are kept as they are (a damaged one too: it stays visible and counted); another
    process appending at the same time waits for the lock (``station.verify.file_lock``).
    """
    path = Path(path)
    record = {"time": time.strftime("%Y-%m-%dT%H:%M:%S"), **record}
    line = json.dumps(record, sort_keys=False) + "\n"
    try:
        with exclusive_lock(path):
            old = read_text_file(path, "verify history", OutputError) if path.is_file() else ""
            if old and not old.endswith("\n"):
                old += "\n"
            write_text_atomic(path, old + line)
    except OSError as exc:
        raise OutputError(f"cannot lock {path} for the new record ({exc.strerror or exc}): check that the folder is "
                          "writable") from None
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
        cause = str(r.get("cause") or "?") + (f" {r['joint']}" if r.get("joint") else "")
        out.append(f"{r.get('time', '?')}  {str(r.get('verdict', '?')).upper():12s}  {Path(str(r.get('session', '?'))).name}"
                   f"  {cause:10s} {float(r.get('translation_mm') or 0):.3f} mm  {float(r.get('rotation_deg') or 0):.4f} deg")
    return out or ["no checks recorded yet"]


def trend_png(records: list[dict], limit_mm: float, limit_deg: float) -> bytes:
    """The trend: change in mm and deg per check over time, thresholds dashed, recalibrations (a new
    session, or a written quick update) as vertical lines."""
    from ..report.figures import BLUE, GREY, RED, new_figure, style_axes, to_png

    fig = new_figure(8.0, 4.2, "constrained")
    axes = fig.subplots(2, 1, sharex=True)
    checks = [r for r in records if r.get("kind", "verify") == "verify"]
    when = [record_time(r["time"]) for r in checks]
    colour = {"ok": BLUE, "drift": RED, "inconclusive": GREY}
    for ax, key, limit, unit in ((axes[0], "translation_mm", limit_mm, "mm"), (axes[1], "rotation_deg", limit_deg, "deg")):
        ax.plot(when, [float(r.get(key) or 0.0) for r in checks], color=GREY, linewidth=0.8)
        for t, r in zip(when, checks):
            ax.plot([t], [float(r.get(key) or 0.0)], marker="o", color=colour.get(str(r.get("verdict")), GREY))
        ax.axhline(limit, color=RED, linestyle="--", linewidth=1.0, label=f"threshold {limit:g} {unit}")
        ax.set_ylabel(f"change ({unit})")
        style_axes(ax)
    sessions = None
    for r in records:
        new_session = sessions is not None and r.get("session") != sessions
        if r.get("kind") == "writeback" or new_session:
            for ax in axes:
                ax.axvline(record_time(r["time"]), color=GREY, linestyle=":", linewidth=1.2)
        sessions = r.get("session", sessions)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[0].set_title("checks: dot colour = verdict (blue ok, red drift, grey inconclusive); dotted = recalibration")
    return to_png(fig)
