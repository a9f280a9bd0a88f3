"""The events a cell publishes: one JSON mapping per calibration, write-back, verify and quick update.

Every event has the same keys (``None`` where a kind has nothing to say), so the fleet view and a
historian read one shape::

    schema        "handeye-plant-event/1"
    kind          calibrate | writeback | verify | quick_update
    seq           the cell's sequence number (1, 2, ...: assigned by the outbox, ``station.plant.outbox``)
    cell, topic_prefix, station, robot, camera_serial, board {corners, square_mm}, tool
    session, session_hash   the session folder's name and the SHA-256 of its session.yaml and postures
    result        camera_pose {parent, position_mm, quaternion_wxyz} (calibrate, quick update, write-back)
    uncertainty   {translation_mm, rotation_deg}: one sigma
    predicted_error_mm, standoff_mm   one-sigma error of a point on the optical axis at the stand-off
    verdict       pass | fail (calibrate), written | readback_differs (write-back), ok | drift | inconclusive
    reason, diagnosis {cause, translation_mm, rotation_deg, joint} (verify), operator, time (UTC, ISO 8601)
"""

from __future__ import annotations

import getpass
import hashlib
import math
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

__all__ = ["SCHEMA", "KINDS", "base_event", "calibration_event", "writeback_event", "verify_event", "predicted_error_mm",
           "session_hash"]

SCHEMA = "handeye-plant-event/1"
KINDS = ("calibrate", "writeback", "verify", "quick_update")


def session_hash(folder) -> str | None:
    """SHA-256 (hex) of ``session.yaml`` and every file of ``postures/`` (names and bytes, in name order):
    the same measurements give the same hash, wherever the folder is. None: no ``session.yaml``."""
    folder = Path(folder)
    head = folder / "session.yaml"
    if not head.is_file():
        return None
    digest = hashlib.sha256()
    files = [head] + sorted(p for p in (folder / "postures").glob("*") if p.is_file())
    for path in files:
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def predicted_error_mm(x, covariance, standoff_mm: float) -> float | None:
    """One-sigma error (mm, RMS over x, y, z) of a point on the camera's optical axis ``standoff_mm`` in front
    of it, from the calibration's covariance.

    Parameters
    ----------
    x : array (4, 4)
        The camera pose in its parent frame (mm).
    covariance : array (6, 6)
        Of x, y, z (mm) and rotations about x, y, z (deg) of that pose (``uncertainty.covariance``).
    standoff_mm : float
    """
    if covariance is None:
        return None
    cov = np.asarray(covariance, float)
    if cov.shape != (6, 6) or not np.all(np.isfinite(cov)):
        return None
    v = np.asarray(x, float)[:3, :3] @ np.array([0.0, 0.0, float(standoff_mm)])
    skew = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    jacobian = np.hstack([np.eye(3), -skew * math.pi / 180.0])
    value = float(np.sqrt(max(np.trace(jacobian @ cov @ jacobian.T), 0.0)))
    return value if math.isfinite(value) else None


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _camera_serial(camera: dict | None) -> str | None:
    """The camera's serial (the XB3's ``guid``), or its back end when it names none (``mock``)."""
    if not isinstance(camera, dict):
        return None
    guid = camera.get("guid")
    return str(guid) if guid not in (None, "") else (f"{camera.get('backend')}" if camera.get("backend") else None)


def base_event(kind: str, plant, recorded: dict, session_folder=None) -> dict:
    """The keys every event has, from the plant settings and a station config's record (``to_dict``)."""
    target = recorded.get("target") or {}
    folder = None if session_folder is None else Path(session_folder)
    return {
        "schema": SCHEMA, "kind": kind, "seq": None, "cell": plant.cell, "topic_prefix": plant.mqtt.topic_prefix,
        "station": plant.station, "robot": recorded.get("robot"), "camera_serial": _camera_serial(recorded.get("camera")),
        "board": {"corners": target.get("corners"), "square_mm": target.get("square_mm")},
        "tool": (recorded.get("tool") or {}).get("name"),
        "session": None if folder is None else folder.resolve().name,
        "session_hash": None if folder is None else session_hash(folder),
        "result": None, "uncertainty": None, "predicted_error_mm": None, "standoff_mm": plant.standoff_mm,
        "verdict": None, "reason": None, "diagnosis": None,
        "operator": plant.operator or _login(), "time": _now(),
    }


def _login() -> str | None:
    try:
        return getpass.getuser()
    except Exception:  # noqa: BLE001 (no login name in a container: not a reason to lose the event)
        return None


def _sigma(uncertainty: dict | None) -> dict | None:
    if not uncertainty:
        return None
    return {"translation_mm": uncertainty.get("translation_mm"), "rotation_deg": uncertainty.get("rotation_deg")}


def calibration_event(plant, recorded: dict, session_folder, result, verdict=None) -> dict:
    """A ``calibrate`` event of ``result`` (``CalibrationResult``) and its verdict (``quality.Verdict`` or None)."""
    from ...geometry import pose_from_transform

    event = base_event("calibrate", plant, recorded, session_folder)
    event["result"] = {"method": result.method, "camera_pose": {"parent": result.parent, **pose_from_transform(result.x)},
                       "d_org_mm": (result.metrics or {}).get("d_org_mm")}
    event["uncertainty"] = _sigma(result.uncertainty)
    event["predicted_error_mm"] = predicted_error_mm(result.x, (result.uncertainty or {}).get("covariance"),
                                                     plant.standoff_mm)
    if verdict is not None:
        event["verdict"], event["reason"] = ("pass" if verdict.passed else "fail"), verdict.line()
    return event


def writeback_event(plant, recorded: dict, session_folder, outcome, quick_update: bool, reason: str | None) -> dict:
    """A ``writeback`` event (``quick_update`` when a check's quick update was written) of ``outcome``
    (``writeback.WritebackOutcome``)."""
    kind = "quick_update" if quick_update else "writeback"
    event = base_event(kind, plant, recorded, session_folder)
    new = outcome.new
    event["result"] = {"camera_pose": {"parent": "tool0", "position_mm": [float(v) for v in new.position_mm],
                                       "quaternion_wxyz": [float(v) for v in new.quaternion_wxyz]},
                       "mock": bool(outcome.mock)}
    event["verdict"] = "written" if outcome.readback_ok else "readback_differs"
    event["reason"] = reason
    return event


def verify_event(plant, recorded: dict, session_folder, data: dict) -> dict:
    """A ``verify`` event of ``handeye verify``'s JSON (``verify_result.outcome_json``)."""
    event = base_event("verify", plant, recorded, session_folder)
    diagnosis = data.get("diagnosis") or {}
    event["verdict"], event["reason"] = data.get("verdict"), data.get("reason")
    event["diagnosis"] = {key: diagnosis.get(key) for key in ("cause", "translation_mm", "rotation_deg", "joint")}
    update = data.get("quick_update")
    if update:
        event["result"] = {"quick_update": update.get("camera_pose")}
        event["uncertainty"] = _sigma(update.get("uncertainty"))
    event["size"] = data.get("size")
    return event
