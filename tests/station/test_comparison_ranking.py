"""The report's method comparison ranks the methods by their held-out (cross-validated) error, carries it
per method in the JSON, and says in one line why the chosen method's in-sample d_org may not be the
lowest (station/report/assessment.py computes it; report, report_text and report_json present it)."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from handeye.calibration.crossval import cross_validate
from handeye.calibration.quality_words import kept_postures
from handeye.calibration.solve import calibrate
from handeye.station.report.assessment import COMPARISON_METHODS, assess, d_org_note
from handeye.station.calibrate import calibrate_session_folder
from handeye.station.cli import main


@pytest.fixture(scope="module")
def session_path(tmp_path_factory):
    """20 postures, 0.5 mm camera and 0.02 deg joint noise: the default's d_org is not the lowest here."""
    path = tmp_path_factory.mktemp("ranking") / "s"
    assert main(["simulate", "-o", str(path), "--postures", "20", "--sigma-rob", "0.02", "--sigma-cam", "0.5",
                 "--seed", "1"]) == 0
    return path


@pytest.fixture(scope="module")
def outputs(session_path, tmp_path_factory):
    folder = tmp_path_factory.mktemp("outputs")
    report, result = folder / "r.html", folder / "r.json"
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["calibrate", str(session_path), "--report", str(report), "--json", str(result)]) == 0
    return text.getvalue(), report.read_text(), json.loads(result.read_text())


def test_the_comparison_is_ranked_by_the_held_out_error_and_the_json_carries_it(outputs):
    _, _, data = outputs
    rows = data["method_comparison"]
    assert {r["method"] for r in rows} == {*COMPARISON_METHODS, data["method"]}
    held_out = [r["held_out_mm"] for r in rows]
    assert all(isinstance(v, float) and v > 0 for v in held_out)
    assert held_out == sorted(held_out)
    assert [r["method"] for r in rows if r["chosen"]] == [data["method"]]


def test_a_line_says_why_the_chosen_d_org_is_not_the_lowest(outputs):
    text, html, data = outputs
    rows = data["method_comparison"]
    chosen = next(r for r in rows if r["chosen"])
    assert round(chosen["d_org_mm"], 3) > round(min(r["d_org_mm"] for r in rows), 3)  # the case of the finding
    note = data["method_comparison_note"]
    assert "d_org is in-sample" in note and "held-out error" in note and "ranks the methods" in note
    assert note in text
    assert 'data-note="d-org"' in html and "d_org is in-sample" in html
    assert "ranked by the held-out error" in html and "held-out (mm)" in html
    assert "Method comparison (ranked by the held-out error" in text


def test_no_line_when_the_chosen_d_org_is_the_lowest():
    rows = [{"method": "a", "chosen": True, "d_org_mm": 0.5}, {"method": "b", "chosen": False, "d_org_mm": 0.6}]
    assert d_org_note(rows) is None
    rows[1]["d_org_mm"] = 0.4
    assert "a does not have the lowest d_org (0.500 mm; b 0.400 mm)" in d_org_note(rows)


def test_every_method_is_scored_on_the_same_folds(session_path):
    outcome = calibrate_session_folder(session_path)
    assessed = assess(outcome, methods=("park", "mc"))
    row = {r["method"]: r for r in assessed.comparison}
    keep = kept_postures(outcome.problem, outcome.result)
    for method in ("park", "mc"):
        expected = cross_validate(outcome.problem, lambda training, m=method: calibrate(training, m).x, keep=keep)
        assert row[method]["held_out_mm"] == pytest.approx(expected.rms_mm, rel=1e-12)
    assert row[outcome.result.method]["held_out_mm"] == pytest.approx(outcome.result.cross_validation["rms_mm"])
    assert np.isfinite([r["held_out_mm"] for r in assessed.comparison]).all()
