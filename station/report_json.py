"""The JSON of ``handeye calibrate --json``: a presenter of ``station.assessment.Assessment``.

The result's own keys (conventions.md, ``CalibrationResult.to_json``), plus ``station`` (where the
data come from: ``real``, ``mock``, ``simulated`` or ``unknown``) and, when the assessment holds a
verdict, ``verdict``. Nothing is computed here.
"""

from __future__ import annotations

from .assessment import Assessment

__all__ = ["calibration_json"]


def calibration_json(assessment: Assessment) -> dict:
    """The JSON mapping of one assessed calibration."""
    data = assessment.result.to_json()
    data["station"] = assessment.origin  # mock | real | simulated | unknown
    if assessment.verdict is not None:
        data["verdict"] = assessment.verdict.to_json()
    return data
