"""``handeye kinematics export``: offsets where an engineer enters them, a corrected program, refusals."""

import re

import numpy as np
import pytest

from handeye.calibration.arm_identification import identify_arm
from handeye.calibration.arm_parameters import corrected_robot, parameter_names
from handeye.robot.kinematics import load_robot
from handeye.calibration.arm_synthetic import deviated_session
from handeye.calibration.session import create_session, write_postures
from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import SceneConfig, make_scene
from handeye.station.cli import main
from handeye.station.kinematics_export import _refusal

NAMES = parameter_names()
ZEROS = {"zero2": 0.04, "zero3": -0.03, "zero4": 0.05, "zero5": -0.045}


def _deviation():
    deviation = np.zeros(len(NAMES))
    for name, value in ZEROS.items():
        deviation[NAMES.index(name)] = value
    return deviation


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    deviation = _deviation()
    session = deviated_session(make_scene(SceneConfig(postures=30, seed=31)), deviation, seed=31)
    folder = tmp_path_factory.mktemp("exp") / "session"
    create_session(folder, session)
    write_postures(folder, session.postures)
    return folder, session


def test_offsets_and_corrected_jointtargets(data, tmp_path):
    folder, _ = data
    program = tmp_path / "prog"
    program.mkdir()
    q = np.round(make_scene(SceneConfig(postures=3, seed=131)).joints_deg[0], 4)  # a view of the board
    (program / "Work.mod").write_text("MODULE Work\n  CONST jointtarget jA := [[" + ",".join(f"{v:.4f}" for v in q)
                                      + "],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n")
    out = tmp_path / "out"
    assert main(["kinematics", "export", str(folder), "-o", str(out), "--program", str(program)]) == 0
    text = (out / "joint_offsets.txt").read_text()
    assert "check in the controller's manual" in text and "Absolute Accuracy" in text
    assert "Calibration Offset" not in text and "cal_offset" not in text  # names we cannot cite are not stated
    rows = {int(line.split(",")[0]): line for line in text.splitlines() if re.match(r"^\d,", line)}
    for axis, name in ((2, "zero2"), (3, "zero3"), (4, "zero4"), (5, "zero5")):
        value, sigma = float(rows[axis].split(",")[1]), float(rows[axis].split(",")[3])
        assert abs(value - ZEROS[name]) < 3 * sigma
    assert "not identifiable" in rows[1] and "not identifiable" in rows[6]
    corrected = (out / "program" / "Work.mod").read_text()
    values = [float(v) for v in re.search(r"jA := \[\[([^\]]*)\]", corrected).group(1).split(",")]
    # the true arm at the corrected angles puts the camera, relative to the true board, where the station's
    # camera-only calibration believes it is at the program's angles (the zeros alone: q - offset)
    nominal = load_robot("IRB1400")
    truth = corrected_robot(nominal, _deviation())
    scene = make_scene(SceneConfig(postures=30, seed=31))
    fit = identify_arm(problem_from_session(data[1])).camera_only.fit
    believed = np.linalg.inv(fit.target) @ nominal.forward_transform(q) @ fit.x

    def real(joints):
        return np.linalg.inv(scene.target2fixed) @ truth.forward_transform(joints) @ scene.x_true

    before = np.linalg.norm(real(q)[:3, 3] - believed[:3, 3])
    after = np.linalg.norm(real(np.array(values))[:3, 3] - believed[:3, 3])
    assert before > 0.3 and after < 0.2 * before
    assert np.all(np.abs(np.array(values) - (q - np.array([0, 0.04, -0.03, 0.05, -0.045, 0]))) < 0.03)
    assert corrected.startswith("MODULE Work")


def test_weak_identification_is_refused(data):
    _, session = data
    ident = identify_arm(problem_from_session(session), prior={"length_mm": 0.5, "angle_deg": 1e-4})
    assert "weak" in _refusal(ident) and "J2" in _refusal(ident)


def test_session_without_joints_is_one_line(tmp_path, capsys):
    assert main(["kinematics", "export", str(tmp_path / "missing"), "-o", str(tmp_path / "o")]) != 0
    assert "Traceback" not in capsys.readouterr().err
