"""Compute once, present many times: everything the station says about one calibration.

``solve -> assess -> presenters``. :func:`assess` takes a solved session (``station.calibrate``) and
computes, in one place, all the figures any output shows: the quality words of the result
(``calibration.quality_words`` through ``station.report.quality.quality_figures``: d_org, rotation-axis
coverage, the units advice), the verdict against the thresholds, the method comparison (the only
other solves), the data checks made before solving, the origin of the data and the repeatability of
the board points. The presenters (``report_text`` for the terminal, ``report_json`` for ``--json``,
``report`` for the HTML file) only format what an :class:`Assessment` holds; none of them solves.

``handeye calibrate`` (text, ``--json``, ``--report``), ``handeye writeback`` (which acts on the
verdict) and ``handeye demo`` all call :func:`assess`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...base import CalibrationError, HandEyeError
from ...calibration import comparison_methods
from ...calibration import fixed_points
from ...calibration import EYE_IN_HAND, CalibrationResult, HandEyeProblem
from ...calibration import AxisCoverage, DOrg, kept_postures, result_d_org
from ...geometry import rotation_error_deg
from ..calibrate import CalibrationOutcome
from .quality import QualityFigures, QualityThresholds, Verdict, quality_figures, verdict

if TYPE_CHECKING:
    from .units_advice import UnitsAdvice

__all__ = [
    "COMPARISON_METHODS",
    "comparison_methods",
    "Assessment",
    "assess",
    "comparison_results",
    "corner_repeatability",
    "d_org_note",
    "held_out_rms_mm",
    "method_comparison",
]


def __getattr__(name: str):
    """``COMPARISON_METHODS``: the methods the report compares, read now from the methods table
    (``calibration.methods.comparison_methods``: the rows marked ``in_comparison``, a plug-in's too)."""
    if name == "COMPARISON_METHODS":
        return comparison_methods()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class Assessment:
    """What the station knows about one calibration, computed once by :func:`assess`.

    Attributes
    ----------
    session_path : Path or str
        The session folder (shown in every output).
    problem : HandEyeProblem
        The data the result was solved from.
    result : CalibrationResult
        The calibration judged (normally the default estimator).
    origin : str
        ``mock``, ``real``, ``simulated`` or ``unknown`` (``station.origin``).
    figures : QualityFigures
        The result's quality words: d_org, rotation-axis coverage of the kept postures, units advice.
    verdict : Verdict or None
        PASS/FAIL against the thresholds; ``None`` when no verdict was asked for.
    comparison : list of dict or None
        One row per compared method, ranked by the held-out error (:func:`method_comparison`); ``None``
        when not compared.
    findings : list or None
        Data checks on the poses (``calibration.diagnostics``); ``None`` when they could not run.
    repeatability : dict
        The board points' deviations in the fixed frame (:func:`corner_repeatability`).
    tooldata_literal : str or None
        The full RAPID tooldata literal, when the tool's load is known (station configuration).
    plan_preview : bytes or None
        The capture plan's preview (``SESSION/preview.png``, ``station.cell.preview``), when the session has one.
    plan_preview_missing : str or None
        Why a planned capture's preview is not shown (its file is missing or unreadable), so the report
        says so instead of dropping the section; None when shown or when the session had no plan.
    comparison_failures : dict
        ``{method: the one-line reason}`` of the compared methods that could not solve these data (a
        plug-in's fault named as such): every presenter lists them under the comparison.
    """

    session_path: Path | str
    problem: HandEyeProblem
    result: CalibrationResult
    origin: str
    figures: QualityFigures
    verdict: Verdict | None
    comparison: list | None
    findings: list | None
    repeatability: dict
    tooldata_literal: str | None = None
    plan_preview: bytes | None = None
    plan_preview_missing: str | None = None
    comparison_failures: dict = field(default_factory=dict)

    @property
    def d_org(self) -> DOrg:
        """THE d_org of the result (``calibration.quality_words.result_d_org``)."""
        return self.figures.d_org

    @property
    def coverage(self) -> AxisCoverage:
        """Rotation-axis coverage of the kept postures (``calibration.quality_words``)."""
        return self.figures.coverage

    @property
    def comparison_note(self) -> str | None:
        """Why the chosen method's d_org is not the comparison's lowest (:func:`d_org_note`), or ``None``."""
        return d_org_note(self.comparison) if self.comparison else None

    @property
    def rank_note(self) -> str | None:
        """Why the chosen method is not first by the held-out error (:func:`rank_note`), or ``None``."""
        return rank_note(self.comparison, self.result) if self.comparison else None

    @property
    def verdict_scope(self) -> str | None:
        """What a PASS does not cover when the robot's errors are systematic (:func:`verdict_scope`)."""
        return verdict_scope(self.verdict, self.result)

    @property
    def units(self) -> UnitsAdvice | None:
        """The units advice (``station.report.units_advice.UnitsAdvice``), or ``None``."""
        return self.figures.units


def assess(outcome: CalibrationOutcome, thresholds: QualityThresholds | None = None, *, judge: bool = True,
           methods: Sequence[str] = (), tooldata_literal: str | None = None) -> Assessment:
    """Everything the outputs show about a solved session, computed once.

    Parameters
    ----------
    outcome : CalibrationOutcome
        The solved session (``station.calibrate``); ``outcome.problem`` is required.
    thresholds : QualityThresholds, optional
        For the verdict; the defaults when omitted.
    judge : bool
        Compute the verdict (``handeye calibrate`` without ``--report`` or ``--thresholds`` shows none).
    methods : sequence of str
        Methods to compare (e.g. :func:`comparison_methods`); the outcome's own result is reused for
        its method. Empty: no comparison (``Assessment.comparison`` is ``None``).
    tooldata_literal : str, optional
        The RAPID tooldata literal to show beside the pose.

    Returns
    -------
    Assessment

    Raises
    ------
    HandEyeError
        When the outcome carries no problem.
    """
    from ..origin import session_origin

    if outcome.problem is None:
        raise HandEyeError("the assessment needs the solved problem; use station.calibrate.calibrate_session_folder")
    problem, result = outcome.problem, outcome.result
    figures = quality_figures(problem, result)
    judged = verdict(result, problem, thresholds, figures) if judge else None
    comparison, failures = None, {}
    if methods:
        solved = comparison_results(problem, methods, outcome.truth, known={result.method: result}, failures=failures)
        comparison = method_comparison(problem, result, solved)
    origin = outcome.origin if outcome.origin is not None else session_origin(path=outcome.session_path)
    return Assessment(outcome.session_path, problem, result, origin, figures, judged, comparison,
                      _findings(problem), corner_repeatability(problem, result), tooldata_literal,
                      *_plan_preview(outcome.session_path, outcome.session), comparison_failures=failures)


def _plan_preview(session_path, session=None) -> tuple[bytes | None, str | None]:
    """The capture plan's preview PNG of the session folder, when there is one; else, for a session
    planned by capture (its record holds ``plan_joints_deg``), why it is not shown."""
    from ...base import read_file_bytes

    path = Path(session_path) / "preview.png" if session_path is not None else None
    planned = session is not None and "plan_joints_deg" in session.extra.get("capture", {})
    if path is None:
        return None, None
    if not path.is_file():
        return None, (f"{path} is missing: run the capture command again with --plan-only to draw it"
                      if planned else None)
    try:
        return read_file_bytes(path, "plan preview", HandEyeError), None
    except HandEyeError as exc:
        return None, (str(exc) if planned else None)


def _findings(problem: HandEyeProblem) -> list | None:
    """The data checks on the poses (``calibration.diagnostics.diagnose``), ``None`` if they fail."""
    from ...calibration import diagnose
    from ...calibration import hand_poses

    try:
        tool0 = hand_poses(problem.hand, problem.setup)  # the map is its own inverse for either set-up
        return diagnose(tool0, problem.target2cam, problem.setup, [int(i) for i in problem.posture_ids])
    except HandEyeError:
        return None


def comparison_results(problem: HandEyeProblem, methods: Sequence[str] | None = None, truth: dict | None = None,
                       known: dict | None = None, failures: dict | None = None) -> dict:
    """Solve ``problem`` with several methods: ``{method: CalibrationResult}``.

    Methods that raise :class:`CalibrationError` on these data (a plug-in's fault included:
    ``calibration.solve.calibrate`` names it) are left out, their one-line reason put in ``failures``.

    Parameters
    ----------
    problem : HandEyeProblem
    methods : sequence of str, optional
        Default: :func:`comparison_methods`, the table's methods marked for the comparison.
    truth : dict, optional
        ``{'x', 'target2fixed'}`` of a synthetic session (fills ``truth_errors``).
    known : dict, optional
        Results already computed (``{method: result}``), reused instead of solving again.
    failures : dict, optional
        Filled with ``{method: reason}`` of the methods left out.
    """
    from ...calibration import calibrate_within

    known = dict(known or {})
    out = {}
    for method in comparison_methods() if methods is None else methods:
        if method in known:
            out[method] = known[method]
            continue
        try:
            out[method] = calibrate_within(problem, method, truth)
        except CalibrationError as exc:
            if failures is not None:
                failures[method] = str(exc)
    for method, result in known.items():
        out.setdefault(method, result)
    return out


def method_comparison(problem: HandEyeProblem, chosen: CalibrationResult, comparison: dict) -> list[dict]:
    """One row per method, ranked by the held-out error: pose, differences from ``chosen``, d_org.

    ``held_out_mm`` (:func:`held_out_rms_mm`) is the cross-validated RMS error of the board points:
    it ranks the methods (rows in increasing order; ``None``, a method that failed on every fold,
    last). ``d_org_mm`` is THE d_org (``calibration.quality_words.result_d_org``) of each method's X
    over the postures the CHOSEN result kept and the same board points, so the chosen method's row
    shows the very figure of the report's header and the verdict; it is in-sample (:func:`d_org_note`).
    ``d_org_incl_outliers_mm`` is the same over every posture (``None`` when the chosen result left
    none out).
    """
    rows = []
    for name, r in comparison.items():
        scatter = result_d_org(problem, chosen, r.x)
        rows.append({
            "method": name,
            "position_mm": [float(v) for v in r.x[:3, 3]],
            "d_position_mm": float(np.linalg.norm(r.x[:3, 3] - chosen.x[:3, 3])),
            "d_rotation_deg": float(rotation_error_deg(r.x, chosen.x)),
            "held_out_mm": held_out_rms_mm(problem, chosen, r),
            "d_org_mm": scatter.mm,
            "d_org_incl_outliers_mm": scatter.incl_outliers_mm,
            "outliers": [int(i) for i in r.outliers],
            "runtime_s": float(r.runtime_s),
            "truth_errors": r.truth_errors,
            "chosen": r is chosen or (r.method == chosen.method and np.allclose(r.x, chosen.x)),
        })
    return sorted(rows, key=lambda row: (row["held_out_mm"] is None, row["held_out_mm"] or 0.0))


def held_out_rms_mm(problem: HandEyeProblem, chosen: CalibrationResult, result: CalibrationResult) -> float | None:
    """The cross-validated RMS error (mm) of the board points of ``result``'s method.

    ``calibration.crossval`` with its default folds over the postures the CHOSEN result kept, so every
    method is scored on the same folds and points: each fold's postures are predicted by the method
    solved on the others. A result that carries its own cross-validation over the same postures (the
    ``ml`` default: the same folds and definition, its refits keeping the full fit's noise levels)
    gives that figure instead of being solved again. ``None`` when no fold could be solved.
    """
    from ...calibration import cross_validate
    from ...calibration import bounded_for, calibrate
    from ...base import OutOfTime

    own = result.cross_validation
    if own and "rms_mm" in own and set(map(int, result.outliers)) == set(map(int, chosen.outliers)):
        return float(own["rms_mm"])
    try:  # another package's method refits under the time bound: too slow, it is ranked last
        cv = bounded_for(result.method, lambda: cross_validate(problem, lambda training: calibrate(training, result.method).x,
                                                               keep=kept_postures(problem, chosen)), "cross-validate")
    except OutOfTime:
        return None
    if cv is None:  # cross_validate always returns its figures; bounded_for's value is untyped (maybe None)
        raise CalibrationError(f"the cross-validation of method {result.method} returned nothing")
    return cv.rms_mm if np.isfinite(cv.rms_sq_mm2).any() else None


def d_org_note(rows: list[dict]) -> str | None:
    """One line on why the chosen method's d_org is not the lowest of the comparison (``None`` when it is)."""
    chosen = next((r for r in rows if r["chosen"]), None)
    lowest = min(rows, key=lambda r: r["d_org_mm"], default=None)
    if chosen is None or lowest is None or round(chosen["d_org_mm"], 3) <= round(lowest["d_org_mm"], 3):
        return None  # not lower where the outputs print it (three decimals)
    return (f"{chosen['method']} does not have the lowest d_org ({chosen['d_org_mm']:.3f} mm; {lowest['method']} "
            f"{lowest['d_org_mm']:.3f} mm): d_org is in-sample, measured on the postures each method was fitted to, "
            f"and rewards fitting their noise; the held-out error (each posture predicted by a fit without it) ranks "
            f"the methods.")


def _systematic(result) -> bool:
    """The result's cross-validation found the held-out error beyond its noise model (SYSTEMATIC)."""
    return bool((getattr(result, "cross_validation", None) or {}).get("systematic"))


def rank_note(rows: list[dict], result: CalibrationResult) -> str | None:
    """One line on why the chosen method is not first by the held-out error (``None`` when it is).

    The held-out error scores how well each X carries the board points of these postures through the
    robot's nominal flange poses; it does not measure the camera pose. With systematic robot errors a
    method that fits X alone folds them into X: it predicts these postures better with a camera
    further off. The line says how far the better-ranked methods' X lie from the chosen one.
    """
    ranked = [r for r in rows if r["held_out_mm"] is not None]
    place = next((k for k, r in enumerate(ranked, start=1) if r["chosen"]), None)
    if place is None or place == 1 or round(ranked[place - 1]["held_out_mm"], 3) <= round(ranked[0]["held_out_mm"], 3):
        return None
    chosen, better = ranked[place - 1], ranked[:place - 1]
    far = max(better, key=lambda r: r["d_position_mm"])
    turn = max(r["d_rotation_deg"] for r in better)
    head = (f"{chosen['method']} ranks {place} of {len(ranked)} by the held-out error, which scores how well each X "
            f"predicts these postures' board points through the robot's nominal flange poses, not how close X is to "
            f"the camera; the {len(better)} ranked above it put the camera up to {far['d_position_mm']:.3f} mm "
            f"({far['method']}) and {turn:.4f} deg from {chosen['method']}'s")
    if _systematic(result):
        return (head + ". The errors here are systematic (SYSTEMATIC above): a method that fits X alone can fold "
                "them into X and predict these postures better with a camera further off. "
                f"{chosen['method']} stays the result: in the benchmarks (docs/figures.md) it is the most accurate camera pose "
                "in every noise regime.")
    return (head + f". {chosen['method']} stays the result: in the benchmarks (docs/figures.md) it is the most accurate "
            "camera pose in every noise regime; compare those differences with its one-sigma.")


def verdict_scope(verdict: Verdict | None, result: CalibrationResult) -> str | None:
    """What a PASS does not cover when the robot's errors are systematic; ``None`` otherwise."""
    if verdict is None or not verdict.passed or not _systematic(result):
        return None
    return ("PASS is for the camera pose on the flange. The systematic errors found (SYSTEMATIC above) are not in it: "
            "where a tool lands in the cell also depends on them; act on that advice before trusting positions away "
            "from the calibration postures.")


def corner_repeatability(problem: HandEyeProblem, result: CalibrationResult) -> dict:
    """Board points in the fixed frame, their deviations from the mean over the inliers, per-point RMS.

    Returns
    -------
    dict
        ``deviations`` (n, m, 3) mm, ``centre_deviation`` (n, 3) mm (mean of a posture's deviations =
        deviation of the board centre), ``inliers`` (n,) bool, ``rms_per_point`` (m,) mm over the
        inliers, ``mean_points`` (m, 3), ``frame`` (``base`` or ``tool0``).
    """
    fixed = fixed_points(problem.hand, result.x, problem.points_cam)  # eq. 13
    inliers = kept_postures(problem, result)
    mean = fixed[inliers].mean(axis=0)
    deviations = fixed - mean
    rms = np.sqrt(np.mean(np.sum(deviations[inliers] ** 2, axis=-1), axis=0))
    return {
        "deviations": deviations,
        "centre_deviation": deviations.mean(axis=1),
        "inliers": inliers,
        "rms_per_point": rms,
        "mean_points": mean,
        "frame": "base" if problem.setup == EYE_IN_HAND else "tool0",
    }
