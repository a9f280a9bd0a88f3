"""Where a session comes from (station/origin.py), and how the JSON of ``handeye calibrate`` says it."""

from __future__ import annotations

import json

import pytest

from handeye.calibration.session import create_session, read_session, write_posture, write_truth
from handeye.calibration.synthetic import NoiseConfig, sample_session, truth_dict
from handeye.station.cli import main
from handeye.station.origin import ORIGINS, session_origin

from helpers import scene

NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)


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


@pytest.mark.parametrize("capture, truth, station", [
    ({"station": "mock"}, False, "mock"),
    (None, True, "simulated"),
    ({"station": "real"}, False, "real"),
    (None, False, "unknown"),
])
def test_calibrate_json_says_where_the_data_come_from(tmp_path, capsys, capture, truth, station):
    path = _session(tmp_path, "s", capture, truth)
    assert main(["calibrate", str(path), "--json", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["station"] == station
