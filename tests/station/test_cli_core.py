import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.calibration.session import Posture, Session, create_session, write_posture
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.geometry.transforms import invert_transforms, transform_from_rotation_translation
from handeye.station.cli import main

from helpers import scene


def _write(path, session):
    create_session(path, session)
    for p in session.postures:
        write_posture(path, p)
    return path


@pytest.fixture
def good_session(tmp_path):
    return _write(tmp_path / "good", sample_session(scene(8), NoiseConfig(sigma_cam_mm=1.0, seed=4)))


def test_help_teaches():
    out = subprocess.run([sys.executable, "-m", "handeye.station", "calibrate", "--help"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "mcb" in out.stdout and "Example" in out.stdout


def test_calibrate_json_follows_conventions(good_session, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["calibrate", str(good_session), "--method", "mcb", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["method"] == "mcb" and data["setup"] == "eye_in_hand"
    pose = data["camera_pose"]
    assert pose["parent"] == "tool0" and len(pose["position_mm"]) == 3 and pose["quaternion_wxyz"][0] >= 0
    assert np.isclose(np.linalg.norm(pose["quaternion_wxyz"]), 1.0)
    assert {"d_org_mm", "d_back_mm"} <= set(data["metrics"])
    assert data["outliers"] == [] and data["runtime_s"] > 0
    text = capsys.readouterr().out
    assert "[[" in text and "d_back" in text  # RAPID literal and metrics in the text report


def test_simulate_then_calibrate_reports_truth(tmp_path, capsys):
    path = tmp_path / "sim"
    assert main(["simulate", "-o", str(path), "--postures", "6", "--sigma-cam", "1"]) == 0
    assert (path / "truth.yaml").exists() and len(list((path / "postures").glob("*.yaml"))) == 6
    assert main(["calibrate", str(path), "--method", "mcy"]) == 0
    assert "Against the synthetic truth" in capsys.readouterr().out
    assert main(["simulate", "-o", str(path), "--postures", "6"]) == 1
    assert "already holds a session" in capsys.readouterr().err



def test_simulate_joint_offset_takes_one_value_per_robot_axis(tmp_path, capsys):
    path = tmp_path / "offset"
    assert main(["simulate", "-o", str(path), "--postures", "4", "--joint-offset", "0.1,0,0,0,0,0"]) == 0
    import yaml

    truth = yaml.safe_load((path / "truth.yaml").read_text())
    assert truth["noise"]["joint_offset_deg"] == [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]
    capsys.readouterr()
    assert main(["simulate", "-o", str(tmp_path / "bad"), "--postures", "4", "--joint-offset", "1,2,3"]) == 2  # usage
    err = capsys.readouterr().err.strip()
    assert err == "handeye simulate: error: --joint-offset needs 6 values, one per axis of the IRB1400; got 3"
    assert not (tmp_path / "bad").exists()

def _rewrite(path, index, **changes):
    import yaml

    file = path / "postures" / f"{index:03d}.yaml"
    data = yaml.safe_load(file.read_text())
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    file.write_text(yaml.safe_dump(data))


def _pose_session(tmp_path, hand_rotations, hand_positions):
    x = transform_from_rotation_translation(Rotation.from_euler("xyz", [10, 20, 30], degrees=True).as_matrix(), [50, 0, 100])
    target2base = transform_from_rotation_translation(np.eye(3), [1000, 0, 0])
    postures = []
    for k, (r, p) in enumerate(zip(hand_rotations, hand_positions)):
        hand = transform_from_rotation_translation(r, p)
        postures.append(Posture(index=k, tool0_in_base=hand, target_in_camera=invert_transforms(hand @ x) @ target2base))
    return _write(tmp_path / "poses", Session(setup="eye_in_hand", postures=postures))


def _errors(capsys, args):
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


@pytest.mark.parametrize("case", ["two_postures", "nan", "non_unit", "corner_count", "parallel", "small"])
def test_bad_sessions_give_one_line_and_write_nothing(case, good_session, tmp_path, capsys):
    path = good_session
    expect = {
        "two_postures": "at least 3 postures",
        "nan": "posture 2 .*nan",
        "non_unit": "posture 5 .*not unit",
        "corner_count": "posture 3 has 103 corners; the board has 13x8 = 104",
        "parallel": "nearly parallel axes",
        "small": "barely rotates",
    }[case]
    if case == "two_postures":
        for f in sorted((path / "postures").glob("*.yaml"))[2:]:
            f.unlink()
    elif case == "nan":
        _rewrite(path, 2, joints_deg=[0, float("nan"), 0, 0, 0, 0], tool0_in_base=None)
    elif case == "non_unit":
        _rewrite(path, 5, tool0_in_base={"position_mm": [1, 2, 3], "quaternion_wxyz": [0.9, 0.1, 0.0, 0.0]})
    elif case == "corner_count":
        import yaml

        data = yaml.safe_load((path / "postures" / "003.yaml").read_text())
        _rewrite(path, 3, points_mm=data["points_mm"][:-1])
    elif case == "parallel":
        angles = np.radians([0, 20, 45, 70, 95])
        rots = [Rotation.from_rotvec([0, 0, a]).as_matrix() for a in angles]
        path = _pose_session(tmp_path, rots, [[500 + 30 * k, 10 * k, 800] for k in range(5)])
    elif case == "small":
        axes = np.random.default_rng(0).normal(size=(5, 3))
        rots = [Rotation.from_rotvec(np.radians(0.6) * a / np.linalg.norm(a)).as_matrix() for a in axes]
        path = _pose_session(tmp_path, rots, [[500 + 30 * k, 10 * k, 800] for k in range(5)])
    out = tmp_path / "out.json"
    code, err = _errors(capsys, ["calibrate", str(path), "--json", str(out)])
    assert code == 1
    assert len(err) == 1, err
    import re

    assert re.search(expect, err[0]), err[0]
    assert not out.exists()


def test_no_traceback_from_the_real_command(tmp_path):
    out = subprocess.run([sys.executable, "-m", "handeye.station", "calibrate", str(tmp_path / "nothing")],
                         capture_output=True, text=True)
    assert out.returncode == 1
    assert "Traceback" not in out.stderr and out.stderr.count("\n") == 1
    assert "no session folder" in out.stderr
