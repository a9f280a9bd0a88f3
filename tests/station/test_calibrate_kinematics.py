"""``handeye calibrate --kinematics`` on a session of a deviated arm (synthetic, known truth)."""

import json

import numpy as np
import pytest

from handeye.calibration.arm_parameters import parameter_names
from handeye.calibration.arm_synthetic import deviated_session, random_deviation
from handeye.calibration.session import create_session, write_postures
from handeye.calibration.synthetic import SceneConfig, make_scene
from handeye.station.cli import main


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kin") / "session"
    deviation = random_deviation(np.random.default_rng(21))
    data = deviated_session(make_scene(SceneConfig(postures=30, seed=21)), deviation, seed=21)
    create_session(folder, data)
    write_postures(folder, data.postures)
    return folder, deviation


def test_kinematics_json_and_text(session, tmp_path, capsys):
    folder, deviation = session
    out = tmp_path / "r.json"
    assert main(["calibrate", str(folder), "--kinematics", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "J3 zero" in text and "stand-off" in text
    data = json.loads(out.read_text())
    for key in ("method", "camera_pose", "uncertainty", "details"):  # the existing keys stay
        assert key in data
    kin = data["kinematics"]
    names = parameter_names()
    assert kin["joint_zero_deg"][0] is None and kin["joint_zero_deg"][5] is None
    for axis in (2, 3, 4, 5):
        true = deviation[names.index(f"zero{axis}")]
        assert abs(kin["joint_zero_deg"][axis - 1] - true) < 3 * kin["sigma_deg"][axis - 1]
    hidden = {row["parameter"] for row in kin["not_identifiable"]}
    assert {"zero1", "d1", "zero6", "d6", "d3"} <= hidden
    standoff = kin["standoff_error"]
    assert standoff["standoff_mm"] == 750.0
    assert standoff["with_correction_rms_mm"] < 0.6 * standoff["without_correction_rms_mm"]


def test_without_the_option_no_kinematics_key(session, tmp_path):
    out = tmp_path / "r.json"
    assert main(["calibrate", str(session[0]), "--json", str(out), "--quiet"]) == 0
    assert "kinematics" not in json.loads(out.read_text())


def test_bad_standoff_is_a_usage_error(session, capsys):
    assert main(["calibrate", str(session[0]), "--kinematics", "--standoff", "-5"]) == 2
    err = capsys.readouterr().err
    assert "--standoff" in err and "Traceback" not in err


def test_report_maps_the_working_volume(session, tmp_path, capsys):
    """The report's kinematics section: a picture of the predicted error over the working volume."""
    from handeye.calibration.arm_identification import identify_arm
    from handeye.calibration.session import read_session
    from handeye.calibration.solve import problem_from_session
    from handeye.calibration.standoff import predicted_standoff, working_volume_joints
    from handeye.robot import load_robot
    from handeye.station.kinematics_report import volume_standoff

    folder, _ = session
    report = tmp_path / "report.html"
    assert main(["calibrate", str(folder), "--kinematics", "--report", str(report), "--quiet"]) == 0
    html = report.read_text()
    assert "over the working volume" in html and "data:image/png;base64" in html
    ident = identify_arm(problem_from_session(read_session(folder)))
    robot = load_robot(ident.robot)
    joints = working_volume_joints(robot, ident.camera_only.fit.x, 300)
    assert len(joints) == 300 and np.all(robot.within_limits(joints))
    assert np.all(robot.chain_points(joints)[:, 1:, 2] > 0)  # the arm above the base's plane
    spread = np.ptp(joints, axis=0)
    assert np.all(spread[:5] > 0.8 * np.ptp(robot.joint_limits_deg[:5], axis=1) - 10)  # the whole volume, not the plan
    volume = volume_standoff(ident, 750.0)
    assert np.median(volume.corrected_mm) < np.median(volume.uncorrected_mm)
    # the map's numbers are the prediction's: the same function at the plan's postures gives the plan's figure
    plan = predicted_standoff(ident, draws=0)
    assert plan.corrected_rms_mm == pytest.approx(predicted_standoff(ident).corrected_rms_mm)
    # away from the plan the correction extrapolates: the error there is larger than at the plan's postures
    assert np.median(volume.corrected_mm) > plan.corrected_rms_mm
