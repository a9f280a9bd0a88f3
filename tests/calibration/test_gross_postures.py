"""A minority of gross postures (robot and camera poses swapped, one posture's quaternions in another
order, a posture of another station) is named and left out before solving; a session with no
consistent majority is still refused with the whole set's diagnosis (calibration/consistency.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from handeye.base.errors import CalibrationError
from handeye.calibration.metrics import errors_against_truth
from handeye.calibration.session import create_session, write_posture
from handeye.calibration.solve import calibrate_session, problem_from_session
from handeye.station import cli

from helpers import scene
from test_calibrate_consistency import _swapped_quaternions, pose_session, poses


def _swap(tool0, target, k):
    tool0[k], target[k] = target[k].copy(), tool0[k].copy()


def _quaternion_order(tool0, target, k):
    tool0[[k]], target[[k]] = _swapped_quaternions(tool0[[k]]), _swapped_quaternions(target[[k]])


def _other_station(tool0, target, k):
    """Posture ``k`` replaced by one of an eye-to-hand station (another camera, board and robot place)."""
    other_tool0, other_target = poses("eye_to_hand", seed=5)
    tool0[k], target[k] = other_tool0[k], other_target[k]


GROSS = {
    "robot and camera poses swapped": {5: _swap},
    "quaternion order wrong in one posture": {11: _quaternion_order},
    "a posture of another station": {7: _other_station},
    "three kinds at once": {2: _swap, 9: _quaternion_order, 16: _other_station},
}


def _gross_session(gross: dict):
    tool0, target = poses("eye_in_hand", seed=2)
    for k, spoil in gross.items():
        spoil(tool0, target, k)
    return pose_session(tool0, target, "eye_in_hand")


@pytest.mark.parametrize("case", list(GROSS))
def test_a_minority_of_gross_postures_is_named_and_left_out(case):
    gross = GROSS[case]
    result = calibrate_session(_gross_session(gross))
    assert set(result.excluded) == set(gross)
    assert set(result.outliers) >= set(gross)  # reported as outliers are: left out of the solution
    assert all("disagree with the other postures" in reason for reason in result.excluded.values())
    errors = errors_against_truth(result.x, scene(20, "eye_in_hand", 0).x_true)
    assert errors["translation_error_mm"] < 1.0 and errors["rotation_error_deg"] < 0.1
    assert set(result.residuals_mm) == set(range(20))  # the excluded postures keep their residual row
    assert all(result.residuals_mm[k] > 50.0 for k in gross)
    assert result.metrics["postures"] == 20 - len(result.outliers)


def test_every_method_leaves_the_gross_postures_out():
    from handeye.calibration.solve import calibrate

    problem = problem_from_session(_gross_session(GROSS["robot and camera poses swapped"]))
    assert problem.n == 20 and problem.excluded.keys() == {5}
    for method in ("mcb", "park", "robust"):
        result = calibrate(problem, method)
        assert 5 in result.outliers and result.excluded.keys() == {5}
        assert errors_against_truth(result.x, scene(20, "eye_in_hand", 0).x_true)["translation_error_mm"] < 3.0


def test_the_command_reports_the_left_out_posture(tmp_path, capsys):
    session = _gross_session(GROSS["robot and camera poses swapped"])
    create_session(tmp_path / "s", session)
    for posture in session.postures:
        write_posture(tmp_path / "s", posture)
    code = cli.main(["calibrate", str(tmp_path / "s"), "--method", "robust", "--json", str(tmp_path / "r.json"),
                     "--report", str(tmp_path / "r.html")])
    out = capsys.readouterr().out
    assert code == 0
    data = json.loads((tmp_path / "r.json").read_text())
    assert 5 in data["outliers"]
    assert [e["posture"] for e in data["excluded_before_solve"]] == [5]
    assert "disagree with the other postures" in data["excluded_before_solve"][0]["reason"]
    assert "Outlier postures (excluded from the solution): 5" in out
    assert "posture 5: left out before solving:" in out
    html = (tmp_path / "r.html").read_text()
    assert "left out before solving" in html and "disagree with the other postures" in html


def test_a_session_wholly_in_the_wrong_quaternion_order_is_still_refused():
    tool0, target = poses("eye_in_hand", seed=2)
    session = pose_session(_swapped_quaternions(tool0), _swapped_quaternions(target), "eye_in_hand")
    with pytest.raises(CalibrationError, match=r"the rotations fit but the translations do not .*wrong order"):
        calibrate_session(session)


def test_no_consistent_majority_is_refused_with_the_whole_sets_diagnosis():
    tool0, target = poses("eye_in_hand", seed=2)
    for k in range(0, 20, 2):  # half the postures in another quaternion order: no majority to keep
        _quaternion_order(tool0, target, k)
    with pytest.raises(CalibrationError, match=r"^the robot and board poses fit no rigid camera mount as eye_in_hand"):
        problem_from_session(pose_session(tool0, target, "eye_in_hand"))


@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
@pytest.mark.parametrize("seed, sigma_cam, sigma_rob", [(1, 0.0, 0.0), (2, 0.5, 0.01), (3, 5.0, 0.05),
                                                        (4, 20.0, 0.3)])
def test_no_clean_session_loses_a_posture_to_the_check(setup, seed, sigma_cam, sigma_rob):
    from handeye.calibration.consistency import consistent_majority

    tool0, target = poses(setup, sigma_cam=sigma_cam, sigma_rob=sigma_rob, seed=seed)
    problem = problem_from_session(pose_session(tool0, target, setup), check_units=False, check_consistency=True)
    assert problem.excluded == {}
    assert consistent_majority(problem.hand, problem.target2cam, setup) == {}
