"""The JSON of ``handeye calibrate --json``: a presenter of ``station.report.assessment.Assessment``.

The result's own keys (conventions.md, ``CalibrationResult.to_json``), plus ``station`` (where the
data come from: ``real``, ``mock``, ``simulated`` or ``unknown``), when the assessment holds a
verdict, ``verdict``, and when it holds a method comparison, ``method_comparison`` (its rows, ranked
by the held-out error ``held_out_mm``) with ``method_comparison_note`` when the chosen method's
in-sample d_org is not the lowest, ``method_rank_note`` when it is not first by the held-out error,
``verdict_scope`` when a PASS stands beside systematic robot errors, and ``method_comparison_failed`` (``{method: reason}``) when a
compared method could not solve the data. Nothing is computed here.
"""

from __future__ import annotations

import math

from .assessment import Assessment

__all__ = ["calibration_json"]


def calibration_json(assessment: Assessment) -> dict:
    """The JSON mapping of one assessed calibration."""
    data = assessment.result.to_json()
    data["station"] = assessment.origin  # mock | real | simulated | unknown
    if assessment.verdict is not None:
        data["verdict"] = assessment.verdict.to_json()
    if assessment.comparison:
        data["method_comparison"] = [{key: _finite(value) for key, value in row.items()} for row in assessment.comparison]
        if assessment.comparison_note:
            data["method_comparison_note"] = assessment.comparison_note
        if assessment.rank_note:
            data["method_rank_note"] = assessment.rank_note
        if assessment.comparison_failures:
            data["method_comparison_failed"] = dict(assessment.comparison_failures)
    if assessment.verdict_scope:
        data["verdict_scope"] = assessment.verdict_scope
    return data


def _finite(value):
    """``None`` for a float that JSON cannot hold (NaN, infinity); the value otherwise."""
    return None if isinstance(value, float) and not math.isfinite(value) else value
