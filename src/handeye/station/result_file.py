"""``SESSION/result.yaml``: the one calibration result on disk (``handeye-result/1``).

``handeye calibrate`` writes it atomically after every solve; ``handeye writeback`` and
``handeye verify`` read it instead of solving again, so the tool data written is the pose the report
showed (same method, same code). It holds the camera pose (``camera_pose``: ``parent`` tool0 or
base, ``position_mm``, ``quaternion_wxyz`` scalar first with ``w >= 0``, as in CONVENTIONS.md), its
one-sigma uncertainty, what the verdict needs to judge it again without solving (metrics, outliers,
posture residuals), the method, the code version, the time, and the postures it was solved from:
their ids and a SHA-256 over the posture files (``postures/NNN.yaml``: names and bytes).

A result whose hash no longer matches the session's posture files (postures added, removed or
edited after it was written; mtimes are not used) is refused by :func:`current_outcome` with one
line: run ``handeye calibrate SESSION``. A session without ``result.yaml`` (calibrated before the
file existed, or never) is solved there and then with the recommended method, the output says so,
and the result is saved: what is written or checked is always what is on disk.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base import HandEyeError, OutputError
from ..base import parse_yaml, read_text_file
from ..calibration import Session, write_yaml_atomic
from ..calibration import CalibrationResult, problem_from_session
from ..geometry import transform_from_pose
from .calibrate import CalibrationOutcome

__all__ = ["RESULT_FILE", "RESULT_FORMAT", "ResultError", "SavedResult", "current_outcome", "postures_hash",
           "read_result", "refuse_stale_result", "result_record", "save_result"]

RESULT_FILE = "result.yaml"
RESULT_FORMAT = "handeye-result/1"


class ResultError(HandEyeError):
    """``result.yaml`` cannot be used: damaged, older than the postures, another method or unit."""


@dataclass(frozen=True)
class SavedResult:
    """A ``result.yaml`` as read.

    Attributes
    ----------
    result : CalibrationResult
        Pose, uncertainty, metrics, outliers and residuals as calibrate found them (no details).
    data : dict
        The file's mapping (``postures``, ``code_version``, ``calibrated_at``, ``units``, ...).
    path : Path
    """

    result: CalibrationResult
    data: dict
    path: Path

    def describe(self) -> str:
        """``method ml, calibrated 2026-12-06T21:00:00Z by handeye 0.4``."""
        return (f"method {self.result.method}, calibrated {self.data.get('calibrated_at', '?')} by handeye "
                f"{self.data.get('code_version', '?')}")


def postures_hash(session_dir) -> str:
    """SHA-256 (hex) over the session's posture files, sorted by name: each name, a NUL, its bytes.

    Any posture added, removed or edited (a byte of it) gives another hash; touching a file does not.
    """
    digest = hashlib.sha256()
    folder = Path(session_dir) / "postures"
    for path in sorted(folder.glob("*.yaml")) if folder.is_dir() else ():
        digest.update(path.name.encode() + b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def _code_version() -> str:
    from .. import __version__

    return __version__


def result_record(outcome: CalibrationOutcome, units: str = "mm") -> dict:
    """The mapping ``result.yaml`` holds for a solved session (plain numbers only)."""
    from ..geometry import pose_from_transform

    r = outcome.result
    session = outcome.session
    data = {
        "format": RESULT_FORMAT,
        "method": r.method,
        "setup": r.setup,
        "camera_pose": {"parent": r.parent, **pose_from_transform(r.x)},
        "uncertainty": r.uncertainty,
        "metrics": r.metrics,
        "outliers": [int(i) for i in r.outliers],
        "excluded_before_solve": {int(i): str(why) for i, why in r.excluded.items()},
        "posture_residuals_mm": {int(k): float(v) for k, v in r.residuals_mm.items()},
        "residuals_on": r.residuals_on,
        "units": units,
        "station": outcome.origin,
        "postures": {"count": len(session.postures) if session is not None else None,
                     "ids": [int(p.index) for p in session.postures] if session is not None else [],
                     "sha256": postures_hash(outcome.session_path)},
        "code_version": _code_version(),
        "calibrated_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    return json.loads(json.dumps(data, default=_plain))  # numpy numbers and arrays as plain YAML


def _plain(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not a number")


def save_result(outcome: CalibrationOutcome, units: str = "mm") -> Path:
    """Write ``SESSION/result.yaml`` atomically; returns its path.

    Raises
    ------
    OutputError
        The session folder cannot be written (the path, the reason, what to do).
    """
    path = Path(outcome.session_path) / RESULT_FILE
    write_yaml_atomic(path, result_record(outcome, units))
    return path


def _refuse(path: Path, why: str, session_dir) -> ResultError:
    return ResultError(f"{path} {why}: run handeye calibrate {session_dir}")


def read_result(session_dir) -> SavedResult | None:
    """``SESSION/result.yaml``, or ``None`` when there is none.

    Raises
    ------
    ResultError
        The file is damaged or of another format (one line: run handeye calibrate SESSION).
    """
    path = Path(session_dir) / RESULT_FILE
    if not path.exists():
        return None
    try:
        data = parse_yaml(read_text_file(path, "calibration result", OutputError), path, OutputError)
    except OutputError as exc:
        raise ResultError(f"{exc}: run handeye calibrate {session_dir}") from None
    if not isinstance(data, dict) or data.get("format") != RESULT_FORMAT:
        raise _refuse(path, f"is not a {RESULT_FORMAT} result", session_dir)
    try:
        pose = data["camera_pose"]
        x = transform_from_pose(pose["position_mm"], pose["quaternion_wxyz"])
        result = CalibrationResult(
            str(data["method"]), str(data["setup"]), x, dict(data.get("metrics") or {}),
            {int(k): float(v) for k, v in (data.get("posture_residuals_mm") or {}).items()},
            [int(i) for i in data.get("outliers") or []], 0.0, uncertainty=data.get("uncertainty"),
            excluded={int(k): str(v) for k, v in (data.get("excluded_before_solve") or {}).items()},
            residuals_on=str(data.get("residuals_on", "corners")))
        str(data["postures"]["sha256"])
    except (KeyError, TypeError, ValueError) as exc:
        raise _refuse(path, f"is damaged ({type(exc).__name__}: {exc})", session_dir) from None
    return SavedResult(result, data, path)


def _check_current(saved: SavedResult, session_dir, method: str | None, units: str) -> None:
    """Refuse a saved result that is not the one asked for: older than the postures, another method or unit."""
    if saved.data["postures"]["sha256"] != postures_hash(session_dir):
        raise _refuse(saved.path, f"is older than the session's postures (they were added, removed or changed after it "
                      f"was calibrated at {saved.data.get('calibrated_at', '?')})", session_dir)
    if method is not None and method != saved.result.method:
        raise ResultError(f"{saved.path} holds the {saved.result.method} result, not {method}'s: run handeye calibrate "
                          f"{session_dir} --method {method} (then this command writes that one)")
    if saved.data.get("units", "mm") != units:
        raise ResultError(f"{saved.path} was calibrated with --units {saved.data.get('units')}: give --units "
                          f"{saved.data.get('units')} here too, or run handeye calibrate {session_dir} --units {units}")


def refuse_stale_result(session_dir) -> None:
    """Refuse (ResultError) a saved result that is damaged or older than the postures; none saved is fine."""
    saved = read_result(session_dir)
    if saved is not None and saved.data["postures"]["sha256"] != postures_hash(session_dir):
        _check_current(saved, session_dir, None, saved.data.get("units", "mm"))


def current_outcome(session: Session, session_dir, method: str | None = None, units: str = "mm",
                    origin: str | None = None, say: Callable[[str], None] = print) -> CalibrationOutcome:
    """The session's saved result, as an outcome ``station.report.assessment.assess`` judges without solving.

    ``session`` is read (lengths in mm). A missing ``result.yaml`` is solved now with ``method`` (the
    recommended one when ``None``), ``say`` tells so in one line, and it is saved (a folder that cannot
    be written is then said too; the solve stands).

    Raises
    ------
    ResultError
        ``result.yaml`` is damaged, older than the postures, or of another ``method`` or ``units``.
    """
    from .calibrate import solve_session

    saved = read_result(session_dir)
    if saved is None:
        say(f"no {RESULT_FILE} in {session_dir} (never calibrated, or by a handeye before it was saved): solving it "
            "now, as handeye calibrate does, and saving it")
        outcome = solve_session(session, session_dir, method, origin=origin)
        try:
            save_result(outcome, units)
        except OutputError as exc:
            say(f"the result was not saved ({exc})")
        return outcome
    problem = problem_from_session(session)  # the session's own checks first (lengths that look like metres)
    _check_current(saved, session_dir, method, units)
    return CalibrationOutcome(Path(session_dir), saved.result, False, session, problem, None, origin)
