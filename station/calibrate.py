"""Calibrate a session folder (the library side of ``handeye calibrate``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..calibration.errors import HandEyeError
from ..calibration.plausibility import session_in_mm
from ..calibration.problem import HandEyeProblem
from ..calibration.session import Session, read_session, read_truth
from ..calibration.solve import CalibrationResult, calibrate, problem_from_session, truth_from_dict

#: File name of the report inside the session folder when ``--report`` is given without a value.
DEFAULT_REPORT_NAME = "report.html"


@dataclass(frozen=True)
class CalibrationOutcome:
    """A result with where it came from (the session, the problem it was solved from, the truth if any).

    ``origin`` is where the data were captured: ``mock``, ``real``, ``simulated`` or ``unknown``
    (``station.origin.session_origin``); the text summary, the report and the JSON key ``station`` show it.
    """

    session_path: Path
    result: CalibrationResult
    has_truth: bool
    session: Session | None = None
    problem: HandEyeProblem | None = None
    truth: dict | None = None
    origin: str = "unknown"


def calibrate_session_folder(path, method: str | None = None, units: str = "mm", progress=None) -> CalibrationOutcome:
    """Read, validate and solve a session; uses ``truth.yaml`` when present (synthetic sessions).

    ``units`` declares the session's length unit (``mm``, the format's own, or ``m``: converted on
    reading); lengths that do not look like millimetres then are refused before solving.
    ``progress(done, total, label)`` is called after each stage of the default estimator.
    """
    from .origin import session_origin

    session = session_in_mm(read_session(path), units)
    truth = truth_from_dict(read_truth(path))
    problem = problem_from_session(session)
    result = calibrate(problem, method, truth, progress)
    return CalibrationOutcome(Path(path), result, truth is not None, session, problem, truth,
                              session_origin(session, path))


@dataclass(frozen=True)
class ReportOutcome:
    """What :func:`report_calibration` wrote and judged."""

    path: Path
    verdict: object  # station.quality.Verdict
    comparison: dict


def report_path_for(session_path, report: str | None) -> Path:
    """The report file: ``report`` itself, or ``SESSION/report.html`` when ``report`` is empty."""
    return Path(session_path) / DEFAULT_REPORT_NAME if not report else Path(report)


def judge_calibration(outcome: CalibrationOutcome, thresholds_file=None):
    """The quality verdict of an outcome, with the thresholds of ``thresholds_file`` (YAML) or the defaults."""
    from .quality import QualityThresholds, load_thresholds, verdict

    thresholds = load_thresholds(thresholds_file) if thresholds_file else QualityThresholds()
    return verdict(outcome.result, outcome.problem, thresholds)


def report_calibration(outcome: CalibrationOutcome, report_path, thresholds_file=None, methods=None,
                       verdict=None) -> ReportOutcome:
    """Compare methods, judge the result and write the HTML report of a calibrated session.

    Parameters
    ----------
    outcome : CalibrationOutcome
        From :func:`calibrate_session_folder`.
    report_path : str or Path
        The HTML file to write.
    thresholds_file : str or Path, optional
        YAML thresholds (see ``station.quality.load_thresholds``); the defaults when omitted.
    methods : sequence of str, optional
        Methods to compare (default ``station.report.COMPARISON_METHODS``); the outcome's own result
        is reused for its method and always included.
    verdict : Verdict, optional
        An already computed verdict (otherwise computed here).

    Raises
    ------
    HandEyeError
        Bad thresholds file, or the report cannot be written.
    """
    from ..calibration.diagnostics import diagnose_session
    from .report import COMPARISON_METHODS, comparison_results, write_report

    if outcome.problem is None:
        raise HandEyeError("the report needs the solved problem; use calibrate_session_folder")
    path = Path(report_path)
    if not path.parent.is_dir():  # fail before the comparison solves, not after
        raise HandEyeError(f"cannot write the report {path}: folder {path.parent} does not exist")
    if verdict is None:
        verdict = judge_calibration(outcome, thresholds_file)
    result = outcome.result
    comparison = comparison_results(outcome.problem, methods or COMPARISON_METHODS, outcome.truth,
                                    known={result.method: result})
    findings = None
    if outcome.session is not None:
        try:
            findings = diagnose_session(outcome.session)
        except HandEyeError:
            findings = None
    title = f"Hand-eye calibration report: {outcome.session_path.resolve().name}"
    written = write_report(path, outcome.session_path, outcome.problem, result, comparison, verdict,
                           title=title, findings=findings, origin=outcome.origin)
    return ReportOutcome(written, verdict, comparison)
