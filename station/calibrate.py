"""Calibrate a session folder (the library side of ``handeye calibrate``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..calibration.session import read_session, read_truth
from ..calibration.solve import CalibrationResult, calibrate_session, truth_from_dict


@dataclass(frozen=True)
class CalibrationOutcome:
    """A result with where it came from."""

    session_path: Path
    result: CalibrationResult
    has_truth: bool


def calibrate_session_folder(path, method: str | None = None) -> CalibrationOutcome:
    """Read, validate and solve a session; uses ``truth.yaml`` when present (synthetic sessions)."""
    session = read_session(path)
    truth = truth_from_dict(read_truth(path), session.setup)
    result = calibrate_session(session, method, truth)
    return CalibrationOutcome(Path(path), result, truth is not None)
