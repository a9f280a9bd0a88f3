"""The fleet table: one row per cell from the history, with what is due and the alarms.

A row: the cell (its topic prefix) and station, the last calibration (time, session, verdict,
predicted error at the stand-off), the last verify (time, verdict, cause), the drift trend (the size
of each verify's change, mm, oldest first: the page's sparkline), when the next verify is due
(``verify_interval_h`` after the last verify, or the last calibration), and the alarms:

- ``drift``: the last verify says drift, or its change exceeds ``drift_alarm_mm``;
- ``camera serial changed``: an event after the last calibration names another camera serial;
- ``tooldata mismatch``: the last verify found another tooldata in the controller, or the last
  write-back did not read back what was written;
- ``verify overdue``: past its due time;
- ``stopped reporting``: nothing from the cell for ``stale_after_h``.
"""

from __future__ import annotations

import time
from datetime import datetime

__all__ = ["fleet_table", "cell_row"]


def _epoch(text) -> float | None:
    try:
        return datetime.fromisoformat(str(text).replace("Z", "+00:00")).timestamp()
    except ValueError:
        return None


def _last(events, *kinds):
    found = [e for e in events if e.get("kind") in kinds]
    return found[-1] if found else None


def _drift_mm(event) -> float:
    size = event.get("size") or {}
    diagnosis = event.get("diagnosis") or {}
    value = size.get("translation_mm", diagnosis.get("translation_mm"))
    return float(value) if isinstance(value, (int, float)) else 0.0


def _alarms(events, fleet, now: float, due: float | None) -> list[str]:
    alarms = []
    verify = _last(events, "verify")
    calibration = _last(events, "calibrate")
    if verify is not None and (verify.get("verdict") == "drift" or _drift_mm(verify) > fleet.drift_alarm_mm):
        alarms.append(f"drift: {_drift_mm(verify):.3f} mm ({(verify.get('diagnosis') or {}).get('cause') or 'cause unknown'})")
    if calibration is not None:
        after = events[events.index(calibration) + 1:]
        other = [e.get("camera_serial") for e in after if e.get("camera_serial") not in (None, calibration.get("camera_serial"))]
        if other:
            alarms.append(f"camera serial changed: {calibration.get('camera_serial')} -> {other[-1]} since the last calibration")
    writeback = _last(events, "writeback", "quick_update")
    if (verify is not None and (verify.get("diagnosis") or {}).get("cause") == "tooldata") or \
            (writeback is not None and writeback.get("verdict") == "readback_differs"):
        alarms.append("tooldata mismatch: the controller holds another camera tooldata than the calibration")
    if due is not None and now > due:
        alarms.append(f"verify overdue by {(now - due) / 3600:.1f} h")
    last_seen = max(e["_received"] for e in events)
    if now - last_seen > fleet.stale_after_h * 3600:
        alarms.append(f"stopped reporting: nothing for {(now - last_seen) / 3600:.1f} h")
    return alarms


def cell_row(cell: str, events: list[dict], fleet, now: float | None = None) -> dict:
    """The row of ``cell`` from its ``events`` (``History.events``: by seq, each with ``_received``)."""
    now = time.time() if now is None else now
    calibration, verify = _last(events, "calibrate"), _last(events, "verify")
    anchor = verify or calibration
    start = None if anchor is None else (_epoch(anchor.get("time")) or anchor["_received"])
    due = None if start is None else start + fleet.verify_interval_h * 3600
    last = events[-1]
    return {
        "cell": cell, "station": last.get("station"), "events": len(events), "last_seq": last.get("seq"),
        "camera_serial": last.get("camera_serial"),
        "last_calibration": None if calibration is None else {
            "time": calibration.get("time"), "session": calibration.get("session"), "verdict": calibration.get("verdict"),
            "predicted_error_mm": calibration.get("predicted_error_mm"), "standoff_mm": calibration.get("standoff_mm")},
        "last_verify": None if verify is None else {
            "time": verify.get("time"), "verdict": verify.get("verdict"),
            "cause": (verify.get("diagnosis") or {}).get("cause")},
        "drift_trend_mm": [round(_drift_mm(e), 4) for e in events if e.get("kind") == "verify"][-30:],
        "predicted_error_mm": None if calibration is None else calibration.get("predicted_error_mm"),
        "verify_due": None if due is None else datetime.fromtimestamp(due).astimezone().isoformat(timespec="minutes"),
        "verify_due_in_h": None if due is None else round((due - now) / 3600, 2),
        "alarms": _alarms(events, fleet, now, due),
    }


def fleet_table(history, fleet, now: float | None = None) -> dict:
    """``{"cells": [row, ...], "alarms": count, "time": ...}`` for every cell of ``history`` with events."""
    rows = []
    for cell in history.cells():
        events = history.events(cell)
        if events:
            rows.append(cell_row(cell, events, fleet, now))
    return {"schema": "handeye-plant-fleet/1", "cells": rows, "alarms": sum(len(r["alarms"]) for r in rows),
            "time": datetime.now().astimezone().isoformat(timespec="seconds")}
