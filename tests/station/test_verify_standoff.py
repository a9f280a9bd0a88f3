"""``handeye verify`` against the stand-off prediction of ``calibrate --kinematics`` (issue 36), on the
embedded mock station: an arm with known deviations (``mock.arm``), a session captured, calibrated with
the kinematics (``SESSION/standoff.json``) and written back; the check states the error it measured at
the stand-off next to the prediction at the same postures, and whether it is within it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from helpers import mock_baseline, mock_station_config, verify_against
from handeye.station.standoff_file import STANDOFF_FILE, read_prediction

ARM = ("mock:\n  arm: {joint_zero_deg: [0, 0.012, -0.01, 0.008, -0.012, 0],"
       " link_mm: {a2: -0.1, a3: 0.1, d4: -0.08}}\n")
BASE_YAML = "controller: {protocol: mock}\ncamera: {backend: mock}\nplan: {postures: 14}\n"


def _config(folder, name: str, faults: str = "") -> str:
    return mock_station_config(folder, name, BASE_YAML + ARM, faults)


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    root = tmp_path_factory.mktemp("verify_standoff")
    return root, mock_baseline(root, _config(root, "mock"), "--kinematics")


def _verify(station, name: str, faults: str = ""):
    root, session = station
    return verify_against(root, session, _config(root, name, faults), name)


def test_calibrate_kinematics_saves_the_prediction_per_posture(station):
    _, session = station
    data = read_prediction(session)
    assert data is not None and data["standoff_mm"] == 750.0
    assert len(data["postures"]) == len(data["without_correction_mm"]) == len(data["with_correction_mm"]) >= 10
    # the arm's deviations (0.008-0.012 deg on J2-J5, 0.1 mm) put the uncorrected point a tenth of a mm or more off
    assert 0.1 < np.sqrt(np.mean(np.square(data["without_correction_mm"]))) < 3.0
    assert np.all(np.array(data["with_correction_mm"]) < np.array(data["without_correction_mm"]))


def test_nothing_changed_the_check_is_within_the_prediction(station, capsys):
    code, data = _verify(station, "none")
    assert code == 0
    entry = data["standoff"]
    assert entry is not None and entry["postures"] == data["revisited"]
    assert entry["within_prediction"]
    # measured against the mock's true arm: close to what was predicted for those postures
    assert 0.5 < entry["measured_rms_mm"] / entry["predicted_rms_mm"] < 1.5
    out = capsys.readouterr().out
    assert "stand-off 750 mm: measured" in out and "within the prediction" in out


def test_a_moved_camera_is_beyond_the_prediction(station, capsys):
    code, data = _verify(station, "moved", "camera_shift_mm: [3.0, -3.0, 2.0]")
    assert code == 3
    entry = data["standoff"]
    assert not entry["within_prediction"] and entry["measured_rms_mm"] > 1.5 * entry["predicted_rms_mm"]
    assert "beyond 1.5 times the prediction" in capsys.readouterr().out


def test_a_session_without_the_prediction_has_none(station, tmp_path):
    _, session = station
    saved = (session / STANDOFF_FILE).read_text()
    (session / STANDOFF_FILE).unlink()
    try:
        code, data = _verify(station, "plain")
        assert code == 0 and data["standoff"] is None
    finally:
        (session / STANDOFF_FILE).write_text(saved)


@pytest.mark.parametrize("damage", [{"without_correction_mm": None}, {"postures": "0-9"}, {"standoff_mm": -750},
                                    {"with_correction_mm": [1.0]}, {"postures": [0.5]}])
def test_a_damaged_prediction_is_not_used(station, damage):
    """A prediction whose hash still matches but whose content does not hold (edited by hand, damaged) is not
    compared against: the check runs and says nothing of the stand-off, rather than failing as handeye's fault."""
    _, session = station
    saved = (session / STANDOFF_FILE).read_text()
    damaged = {**json.loads(saved), **damage}
    (session / STANDOFF_FILE).write_text(json.dumps({k: v for k, v in damaged.items() if v is not None}))
    try:
        assert read_prediction(session) is None
    finally:
        (session / STANDOFF_FILE).write_text(saved)
    assert read_prediction(session) is not None
