"""Compute once, present many times (station/report/assessment.py): one assessment per calibration, and the
presenters (text, JSON, HTML) only format it."""

from __future__ import annotations

import html
import json

import pytest

import handeye.calibration.metrics as metrics
import handeye.calibration.quality_words as quality_words
import handeye.calibration.solve as solve
import handeye.station.report.assessment as assessment_module
import handeye.station.report.quality as quality
from handeye.calibration.session import create_session, write_posture, write_truth
from handeye.calibration.solve import DEFAULT_METHOD
from handeye.calibration.synthetic import NoiseConfig, sample_session, truth_dict
from handeye.station.report.assessment import COMPARISON_METHODS, assess
from handeye.station.calibrate import calibrate_session_folder
from handeye.station.cli import main
from handeye.station.report.document import write_report
from handeye.station.report.as_json import calibration_json
from handeye.station.report.text import calibration_summary

from helpers import scene

NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)


@pytest.fixture(scope="module")
def session_path(tmp_path_factory):
    sc = scene(12)
    session = sample_session(sc, NOISE)
    path = tmp_path_factory.mktemp("assessment") / "s"
    create_session(path, session)
    for p in session.postures:
        write_posture(path, p)
    write_truth(path, truth_dict(sc, NOISE))
    return path


def _forbid(monkeypatch, *targets):
    """Make every (module, name) raise when called: what a presenter must never do."""
    def refuse(*_args, **_kwargs):
        raise AssertionError("a presenter computed instead of formatting the assessment")

    for module, name in targets:
        monkeypatch.setattr(module, name, refuse)


def test_presenters_only_format_the_assessment(session_path, tmp_path, monkeypatch):
    assessed = assess(calibrate_session_folder(session_path), methods=COMPARISON_METHODS)
    # the comparison holds the listed methods and the result's own (the default, solved once, not again)
    methods = [r["method"] for r in assessed.comparison]
    assert assessed.verdict.passed and sorted(methods) == sorted({*COMPARISON_METHODS, assessed.result.method})
    _forbid(monkeypatch, (solve, "calibrate"), (solve, "_calibrate"), (quality, "verdict"), (quality, "quality_figures"),
            (quality_words, "result_d_org"), (quality_words, "rotation_axis_coverage"),
            (quality_words, "hand_axis_coverage"), (metrics, "fixed_points"), (metrics, "d_org"),
            (assessment_module, "assess"), (assessment_module, "comparison_results"),
            (assessment_module, "quality_figures"), (assessment_module, "verdict"),
            (assessment_module, "method_comparison"), (assessment_module, "corner_repeatability"))
    page = write_report(tmp_path / "r.html", assessed).read_text()
    text = calibration_summary(assessed)
    data = calibration_json(assessed)
    header = f"{assessed.d_org.mm:.3f} mm"
    assert f'data-d-org="header">{header}' in page and f"d_org   {header}" in text
    assert data["verdict"] == assessed.verdict.to_json() and data["station"] == "simulated"
    assert f"rotation-axis spread {assessed.coverage.spread_deg:.1f} deg" in page
    # the posture residual: one text (quality_words) in every presenter, naming the points it is measured on
    meaning = quality_words.posture_residual_meaning("corners")
    assert assessed.result.residuals_meaning == meaning and "the board corners" in meaning
    assert meaning in text and html.escape(meaning) in page and data["posture_residuals_meaning"] == meaning


def _count(monkeypatch, module, name, calls):
    original = getattr(module, name)

    def counted(*args, **kwargs):
        calls[name] = calls.get(name, 0) + 1
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)


def test_calibrate_with_report_and_json_assesses_once_and_solves_each_method_once(session_path, tmp_path, monkeypatch,
                                                                                   capsys):
    calls = {}
    for module, name in ((assessment_module, "assess"), (assessment_module, "quality_figures")):
        _count(monkeypatch, module, name, calls)
    solved = []  # (method, postures) of every solve
    original = solve._calibrate
    monkeypatch.setattr(solve, "_calibrate", lambda problem, method=None, *args, **kwargs: (
        solved.append((method or DEFAULT_METHOD, problem.n)) or original(problem, method, *args, **kwargs)))
    out = tmp_path / "r.json"
    assert main(["calibrate", str(session_path), "--report", str(tmp_path / "r.html"), "--json", str(out)]) == 0
    # each comparison method solved once on the whole session, and the default once (it is not one of the
    # comparison's); the held-out error adds one solve per fold of each comparison method on the postures
    # outside the fold (the default's own cross-validation is reused)
    n = len(json.loads(out.read_text())["posture_residuals_mm"])
    whole = sorted(method for method, postures in solved if postures == n)
    assert whole == sorted({*COMPARISON_METHODS, DEFAULT_METHOD}) and calls == {"assess": 1, "quality_figures": 1}
    folds = [(method, postures) for method, postures in solved if postures < n]
    assert sorted({method for method, _ in folds}) == sorted(COMPARISON_METHODS)
    assert len(folds) == 5 * len(COMPARISON_METHODS) and all(postures >= n - (n + 4) // 5 for _, postures in folds)
    printed = capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["verdict"]["passed"] and "verdict: PASS (10 of 10 checks)" in printed


def test_calibrate_without_report_or_thresholds_shows_no_verdict_and_compares_nothing(session_path, tmp_path,
                                                                                      monkeypatch, capsys):
    calls = {}
    _count(monkeypatch, solve, "_calibrate", calls)
    out = tmp_path / "r.json"
    assert main(["calibrate", str(session_path), "--json", str(out)]) == 0
    assert calls == {"_calibrate": 1}
    assert "verdict" not in json.loads(out.read_text()) and "verdict:" not in capsys.readouterr().out


def test_writeback_judges_through_the_assessment(tmp_path, monkeypatch, capsys):
    session = sample_session(scene(12), NOISE)  # no truth.yaml: write-back refuses simulated sessions
    create_session(tmp_path / "s", session)
    for p in session.postures:
        write_posture(tmp_path / "s", p)
    calls = {}
    _count(monkeypatch, assessment_module, "assess", calls)
    assert main(["writeback", str(tmp_path / "s"), "--dry-run"]) == 0
    assert calls == {"assess": 1}
    assert "verdict: PASS" in capsys.readouterr().out
