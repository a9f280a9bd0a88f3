"""Calibrate a session folder (the library side of ``handeye calibrate``): read, validate, solve.

What comes after the solve (verdict, method comparison, figures) is ``station.report.assessment``; how it is
shown is the presenters' (``report_text``, ``report_json``, ``report``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..calibration import session_in_mm
from ..calibration import HandEyeProblem
from ..calibration import Session, read_session, read_truth
from ..calibration import CalibrationResult, calibrate_within, problem_from_session, truth_from_dict

#: File name of the report inside the session folder when ``--report`` is given without a value.
DEFAULT_REPORT_NAME = "report.html"


@dataclass(frozen=True)
class CalibrationOutcome:
    """A result with where it came from (the session, the problem it was solved from, the truth if any).

    ``origin`` is where the data were captured: ``mock``, ``real``, ``simulated`` or ``unknown``
    (``station.origin.session_origin``); the text summary, the report and the JSON key ``station`` show
    it. ``None`` means "not looked up": ``station.report.assessment.assess`` reads it from the folder
    ``session_path``.
    """

    session_path: Path
    result: CalibrationResult
    has_truth: bool = False
    session: Session | None = None
    problem: HandEyeProblem | None = None
    truth: dict | None = None
    origin: str | None = None


def solve_session(session: Session, path: str | Path, method: str | None = None, truth: dict | None = None,
                  origin: str | None = None, progress: Callable | None = None) -> CalibrationOutcome:
    """Solve a session already read (lengths in mm) with ``method`` (the recommended default when
    ``None``); ``origin`` is read from the session when omitted; ``progress(done, total, label)`` is
    called after each stage of the default estimator."""
    from .origin import session_origin

    problem = problem_from_session(session)
    result = calibrate_within(problem, method, truth, progress)  # another package's method under the time bound
    return CalibrationOutcome(Path(path), result, truth is not None, session, problem, truth,
                              session_origin(session, path) if origin is None else origin)


def calibrate_session_folder(path: str | Path, method: str | None = None, units: str = "mm", progress: Callable | None = None) -> CalibrationOutcome:
    """Read, validate and solve a session; uses ``truth.yaml`` when present (synthetic sessions).

    ``units`` declares the session's length unit (``mm``, the format's own, or ``m``: converted on
    reading); lengths that do not look like millimetres then are refused before solving.
    ``progress(done, total, label)`` is called after each stage of the default estimator.
    """
    session = session_in_mm(read_session(path), units)
    truth = truth_from_dict(read_truth(path))
    return solve_session(session, path, method, truth, progress=progress)


def report_path_for(session_path: str | Path, report: str | None) -> Path:
    """The report file: ``report`` itself, or ``SESSION/report.html`` when ``report`` is empty."""
    return Path(session_path) / DEFAULT_REPORT_NAME if not report else Path(report)
