"""``calibrate`` re-checks the X-free invariants of AX = XB and refuses poses no rigid camera mount fits
(calibration/consistency.py, called from solve.problem_from_session) instead of returning a pose."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.base.errors import CalibrationError
from handeye.calibration.session import Session, create_session, write_posture
from handeye.calibration.solve import calibrate_session, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.geometry.transforms import invert_transforms
from handeye.station import cli
from handeye.station.importers import read_any

from helpers import scene, shared_dataset


def pose_session(tool0, target, setup) -> Session:
    from handeye.calibration.session import Posture

    return Session(setup=setup, postures=[Posture(index=k, tool0_in_base=a, target_in_camera=b)
                                          for k, (a, b) in enumerate(zip(tool0, target))])


def poses(setup, sigma_cam=0.5, sigma_rob=0.01, postures=20, seed=2):
    from handeye.calibration.compact_points import compact_points_from_corners

    sc = scene(postures, setup, 0)
    session = sample_session(sc, NoiseConfig(sigma_rob_deg=sigma_rob, sigma_cam_mm=sigma_cam, seed=seed))
    tool0 = np.array([p.tool0_in_base for p in session.postures])
    return tool0, compact_points_from_corners(np.array([p.points_mm for p in session.postures]), sc.board).target2cam


@pytest.mark.parametrize("name, file", [("moveit-calibration", "pose_samples.json"),
                                        ("camodocal-ar-tag", "TransformPairsInput.yml"), ("visp-eye-in-hand", None),
                                        ("ethz-robot-arm", None), ("visp-apps-eye-in-hand", None)])
def test_real_sets_pass_the_re_check(name, file):
    folder = shared_dataset(name)
    session = read_any(folder / file if file else folder)
    from handeye.calibration.consistency import consistency_figures

    problem = problem_from_session(session)  # raises when the re-check refuses
    f = consistency_figures(problem.hand, problem.target2cam)
    assert f["gap_deg"] < 1.5 and f["axis_deg"] < 3.0 and f["translation"] < 0.1
    assert f["other_axis_deg"] > 15.0  # the other set-up is far: the check has room on both sides


@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
@pytest.mark.parametrize("sigma_cam, sigma_rob", [(0.0, 0.0), (1.0, 0.02), (20.0, 0.3)])
def test_noisy_mock_sessions_pass(setup, sigma_cam, sigma_rob):
    """The mock station's sessions, up to the paper's worst camera noise (20 mm) and 0.3 deg per joint."""
    session = sample_session(scene(20, setup, 0), NoiseConfig(sigma_rob_deg=sigma_rob, sigma_cam_mm=sigma_cam, seed=4))
    # 20 mm of noise spreads the corners beyond the square-size check: only the re-check is asked for here
    problem_from_session(session, check_units=False, check_consistency=True)


def test_a_few_gross_outliers_are_left_to_the_robust_solver():
    tool0, target = poses("eye_in_hand", postures=20)
    for k in (3, 9, 15):  # three postures 25 deg off, as a wrong board detection would be
        target[k, :3, :3] = Rotation.from_rotvec([0.0, 0.44, 0.0]).as_matrix() @ target[k, :3, :3]
    result = calibrate_session(pose_session(tool0, target, "eye_in_hand"))
    assert set(result.outliers) >= {3, 9, 15}


WRONG = {
    "the other set-up": (lambda a, b: (a, b), "other", r"fit no rigid camera mount as eye_to_hand: .*they fit eye_in_hand"),
    "robot base in flange": (lambda a, b: (invert_transforms(a), b), "same", r"fit no rigid camera mount as eye_in_hand"),
    "camera in target": (lambda a, b: (a, invert_transforms(b)), "same", r"fit no rigid camera mount as eye_in_hand"),
    "both inverted": (lambda a, b: (invert_transforms(a), invert_transforms(b)), "same",
                      r"^the camera would be \d+ mm from the flange and the board \d+ mm from the base: both pose sets "
                      r"look inverted"),
    "camera in target, other set-up": (lambda a, b: (a, invert_transforms(b)), "other",
                                       r"^the board is behind the camera .*--camera-pose, --setup"),
    "rotation vector read as Euler angles": (
        lambda a, b: (a, _rotvec_as_euler(b)), "same", r"relative rotations of robot and board differ by a median"),
    "quaternion order swapped on both sides": (
        lambda a, b: (_swapped_quaternions(a), _swapped_quaternions(b)), "same",
        r"the rotations fit but the translations do not .*wrong order"),
}


def _rotvec_as_euler(poses):
    out = poses.copy()
    out[:, :3, :3] = Rotation.from_euler("xyz", Rotation.from_matrix(poses[:, :3, :3]).as_rotvec()).as_matrix()
    return out


def _swapped_quaternions(poses):
    out = poses.copy()
    q = Rotation.from_matrix(poses[:, :3, :3]).as_quat()  # x y z w read as w x y z
    out[:, :3, :3] = Rotation.from_quat(q, scalar_first=True).as_matrix()
    return out


@pytest.mark.parametrize("wrong", list(WRONG))
def test_inconsistent_sessions_are_refused_with_the_likely_cause(wrong):
    tool0, target = poses("eye_in_hand")
    change, setup, message = WRONG[wrong]
    a, b = change(tool0, target)
    session = pose_session(a, b, "eye_to_hand" if setup == "other" else "eye_in_hand")
    with pytest.raises(CalibrationError, match=message) as info:  # consistency.InconsistentPosesError
        calibrate_session(session)
    assert "\n" not in str(info.value) and "handeye import" in str(info.value)


def test_the_command_refuses_in_one_line(tmp_path, capsys):
    tool0, target = poses("eye_in_hand")
    session = pose_session(tool0, target, "eye_to_hand")
    create_session(tmp_path / "s", session)
    for posture in session.postures:
        write_posture(tmp_path / "s", posture)
    code = cli.main(["calibrate", str(tmp_path / "s"), "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("handeye calibrate: error: the robot and board poses fit no rigid camera mount as eye_to_hand")
    assert not (tmp_path / "r.json").exists()


def test_the_check_is_quiet_on_too_little_data():
    from handeye.calibration.consistency import check_consistent

    tool0, target = poses("eye_in_hand", postures=20)
    check_consistent(tool0[:2], target[:2], "eye_in_hand")  # fewer than 3 postures: the solver refuses those
    nan = copy.deepcopy(target)
    nan[0, 0, 0] = np.nan
    check_consistent(tool0, nan, "eye_in_hand")  # non-finite values are the solver guard's to refuse
