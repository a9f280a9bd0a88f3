"""The verdict's second line of defence against wrong units and impossible camera mounts
(station/report/quality.py, station/report/units_advice.py): a session written in metres must not PASS, and the
advice of a failed verdict names the units when the data say units."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from handeye.geometry.board import BoardGeometry
from handeye.base.errors import HandEyeError
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.station.commands.calibrate import EPILOG
from handeye.station.report.quality import QualityThresholds, ThresholdError, verdict

from helpers import scene

NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)


def _session(postures=12, robot=1.0, board=1.0, only=None, setup="eye_in_hand"):
    """A synthetic session with the robot positions scaled by ``robot`` and the board points by ``board``
    (1e-3: written in metres), for every posture or only posture ``only``."""
    session = copy.deepcopy(sample_session(scene(postures, setup), NOISE))
    for k, posture in enumerate(session.postures):
        if only is not None and k != only:
            continue
        pose = posture.tool0_in_base.copy()
        pose[:3, 3] *= robot
        posture.tool0_in_base = pose
        posture.points_mm = posture.points_mm * board
    if only is None and board != 1.0:
        session.target = BoardGeometry(session.target.corners, session.target.square_mm * board)
    # the verdict is the second line of defence: the refusal before solving (plausibility) is switched
    # off here so that these sessions reach it
    return problem_from_session(session, check_units=False)


def _judge(problem, method=None, thresholds=None):
    result = calibrate(problem, method)
    return result, verdict(result, problem, thresholds)


def test_a_session_in_metres_fails_on_the_camera_offset_and_says_metres():
    """On main this PASSed 8 of 8: every figure shrinks a thousandfold with the lengths."""
    result, judged = _judge(_session(robot=1e-3, board=1e-3))
    assert np.linalg.norm(result.x[:3, 3]) < 1.0  # the frame sits a fraction of a mm from the flange
    assert not judged.passed
    check = next(c for c in judged.checks if c.name == "min_camera_offset_mm")
    assert not check.passed and check.value < 1.0 and check.limit == 20.0
    assert "metres" in check.advice and "mm" in check.advice
    line = judged.line()
    assert line.startswith("verdict: FAIL - the session's lengths look like metres") and "lengths must be in mm" in line
    assert "\n" not in line


def test_the_offset_check_alone_names_metres():
    """Without any unit finding (the pose checks could be fooled) the check's own advice names the units."""
    problem = _session()
    result = calibrate(problem)
    result.x = result.x.copy()
    result.x[:3, 3] *= 1e-3
    judged = verdict(result, problem)
    check = next(c for c in judged.checks if c.name == "min_camera_offset_mm")
    assert not check.passed
    assert check.advice.startswith("the camera frame is 0.2 mm from the flange") and "look like metres" in check.advice
    assert "lengths must be in mm" in check.advice


def test_a_camera_far_from_the_flange_fails_with_units_and_mount_advice():
    problem = _session()
    result, judged = _judge(problem, thresholds=QualityThresholds(max_camera_offset_mm=100.0))
    check = next(c for c in judged.checks if c.name == "max_camera_offset_mm")
    assert not check.passed and check.value == pytest.approx(np.linalg.norm(result.x[:3, 3]))
    assert f"{check.value:.0f} mm from the flange, more than 100 mm" in check.advice
    assert "units" in check.advice and "raise max_camera_offset_mm" in check.advice
    assert verdict(result, problem).passed  # the default limit (500 mm) admits the 165 mm mount


def test_eye_to_hand_has_no_camera_offset_checks():
    problem = _session(setup="eye_to_hand")
    _, judged = _judge(problem)
    names = [c.name for c in judged.checks]
    assert "min_camera_offset_mm" not in names and "max_camera_offset_mm" not in names
    assert judged.passed  # the camera 2.3 m from the base is fine


def test_robot_in_metres_board_in_mm_advice_says_units_not_recapture():
    problem = _session(robot=1e-3)
    _, judged = _judge(problem)
    assert not judged.passed
    expected = "the robot poses (tool0_in_base) look like metres and the board poses like mm: fix the units (lengths in mm)"
    assert judged.cause == expected
    for check in judged.failed:
        if check.value is not None:
            assert check.advice == expected, check.name
            assert "re-capture" not in check.advice
    assert expected in judged.line()
    assert judged.to_json()["cause"] == expected


def test_board_in_metres_robot_in_mm_advice_names_the_board():
    _, judged = _judge(_session(board=1e-3))
    assert not judged.passed
    assert judged.cause.startswith("the board poses (board points in the camera) look like metres and the robot poses "
                                   "like mm: fix the units")


@pytest.mark.parametrize("method", ["robust", "mcb"])
def test_a_single_posture_in_metres_is_named(method):
    problem = _session(robot=1e-3, only=5)
    _, judged = _judge(problem, method)
    assert not judged.passed
    assert "posture 5" in judged.cause and "metres" in judged.cause and "lengths in mm" in judged.cause
    assert all("posture 5" in c.advice for c in judged.failed if c.value is not None)
    assert "metres" in judged.line()


def test_a_single_posture_in_metres_left_out_is_named_in_the_outlier_note():
    """With enough postures the robust default leaves it out and the result is right: the verdict passes,
    and the note on the outlier says why the posture was wrong."""
    problem = _session(postures=20, robot=1e-3, only=5)
    result, judged = _judge(problem)
    assert result.outliers == [5]
    assert judged.passed and judged.cause == ""
    note = next(c for c in judged.checks if c.name == "max_outlier_fraction").advice
    assert "posture 5" in note and "metres" in note


def test_good_sessions_get_no_units_advice():
    from handeye.station.report.units_advice import units_advice

    assert units_advice(_session()) is None
    _, judged = _judge(_session())
    assert judged.passed and judged.cause == "" and "metres" not in judged.line()


@pytest.mark.parametrize("mapping, words", [
    ({"min_camera_offset_mm": 600.0}, ["min_camera_offset_mm (600)", "below max_camera_offset_mm (500)"]),
    ({"max_camera_offset_mm": 10.0}, ["min_camera_offset_mm (20)", "max_camera_offset_mm (10)"]),
    ({"min_camera_offset_mm": 50, "max_camera_offset_mm": 50}, ["must be below"]),
    ({"max_camera_offset_mm": -1.0}, ["max_camera_offset_mm", "positive"]),
    ({"min_camera_offset_mm": "far"}, ["min_camera_offset_mm", "number"]),
])
def test_camera_offset_thresholds_are_validated(mapping, words):
    with pytest.raises(ThresholdError) as info:
        QualityThresholds.from_dict(mapping, "t.yaml")
    message = str(info.value)
    assert "\n" not in message and isinstance(info.value, HandEyeError) and message.startswith("t.yaml")
    for word in words:
        assert word in message
    assert QualityThresholds.from_dict({"min_camera_offset_mm": 5, "max_camera_offset_mm": 900}).max_camera_offset_mm == 900


def test_the_help_lists_every_threshold_key_with_its_default():
    import re

    text = " ".join(EPILOG.split())
    for key, value in QualityThresholds().to_dict().items():
        listed = re.search(rf"\b{key} \(([0-9.]+)\)", text)
        assert listed and float(listed.group(1)) == value, key
