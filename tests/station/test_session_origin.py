"""Where a session comes from (station/origin.py), and how the report, the text summary and the JSON of
``handeye calibrate`` say it: a mock or simulated session must never read like a calibration of the
real robot."""

from __future__ import annotations

import json

import pytest

from handeye.calibration.session import create_session, read_session, write_posture, write_truth
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session, truth_dict
from handeye.station.cli import main
from handeye.station.origin import ORIGINS, session_origin
from handeye.station.report.document import write_report

from helpers import assessed, scene

NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)
MOCK_BANNER = "MOCK SESSION</b> &ndash; captured on a mock station (embedded, or a rehearsal); not a calibration of a real robot"


def _session(tmp_path, name, capture=None, truth=False):
    sc = scene(12)
    session = sample_session(sc, NOISE)
    if capture is not None:
        session.extra["capture"] = capture
    path = tmp_path / name
    create_session(path, session)
    for posture in session.postures:
        write_posture(path, posture)
    if truth:
        write_truth(path, truth_dict(sc, NOISE))
    return path


@pytest.mark.parametrize("capture, truth, expected", [
    ({"station": "mock"}, False, "mock"),
    ({"station": "real"}, False, "real"),
    ({"station": "real"}, True, "real"),          # the capture record wins over a stray truth.yaml
    (None, True, "simulated"),
    (None, False, "unknown"),
    ({"plan_score": {}}, False, "unknown"),
    ({"config": {"camera": {"backend": "mock"}}}, False, "mock"),  # captured before 'station' was recorded
    ({"config": {"camera": {"backend": "xb3"}}}, False, "unknown"),
    ({"station": "MOCK"}, False, "mock"),
])
def test_session_origin(tmp_path, capture, truth, expected):
    path = _session(tmp_path, "s", capture, truth)
    assert session_origin(read_session(path)) == expected
    assert session_origin(read_session(path), path) == expected
    assert session_origin(path=path) == expected  # from the folder alone
    assert expected in ORIGINS


def test_session_origin_without_a_session_is_unknown(tmp_path):
    assert session_origin() == "unknown"
    assert session_origin(path=tmp_path / "missing") == "unknown"
    (tmp_path / "session.yaml").write_text("capture: [unbalanced\n")
    assert session_origin(path=tmp_path) == "unknown"


@pytest.mark.parametrize("capture, truth, station, banner", [
    ({"station": "mock"}, False, "mock", MOCK_BANNER),
    (None, True, "simulated", "SIMULATED SESSION</b> &ndash; synthetic data"),
    ({"station": "real"}, False, "real", None),
    (None, False, "unknown", None),
])
def test_calibrate_says_where_the_data_come_from(tmp_path, capsys, capture, truth, station, banner):
    path = _session(tmp_path, "s", capture, truth)
    out = tmp_path / "r.json"
    assert main(["calibrate", str(path), "--report", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert json.loads(out.read_text())["station"] == station
    page = (path / "report.html").read_text()
    first_line = printed.splitlines()[0]
    if banner is None:
        assert 'class="origin"' not in page and "MOCK" not in page and "SIMULATED" not in page
        assert "MOCK" not in printed and "SIMULATED" not in printed
    else:
        word = banner.split("<")[0]
        assert banner in page
        # prominent: before the verdict and the literal
        assert page.index(banner) < page.index('class="verdict ') < page.index("RAPID literal")
        assert first_line.startswith(f"*** {word}") and "not a calibration of a real robot" in first_line
    assert main(["calibrate", str(path), "--json", "-"]) == 0  # JSON on stdout, without --report too
    assert json.loads(capsys.readouterr().out)["station"] == station


def test_write_report_reads_the_origin_from_the_session_folder(tmp_path):
    """As the demo calls it: no origin given, the session folder says mock."""
    path = _session(tmp_path, "s", {"station": "mock"})
    problem = problem_from_session(read_session(path))
    result = calibrate(problem)
    page = write_report(tmp_path / "r.html", assessed(problem, result, path)).read_text()
    assert MOCK_BANNER in page
    page = write_report(tmp_path / "r2.html", assessed(problem, result, path, origin="real")).read_text()
    assert "MOCK" not in page
