"""Issue 39, one result on disk: ``calibrate`` saves ``SESSION/result.yaml``; ``writeback`` writes that result
(never a new solve), refuses it once the postures changed (by their hash, not their mtime), solves and saves it,
saying so, when there is none."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import yaml

from handeye.calibration import solve
from handeye.calibration.session import create_session, write_posture
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.geometry.transforms import transform_from_pose
from handeye.station.cli import main

from helpers import scene


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    root = tmp_path_factory.mktemp("result")
    session = root / "sim"  # of unknown origin (a simulated one is never written, dry run or not)
    sampled = sample_session(scene(14), NoiseConfig(sigma_cam_mm=0.05, seed=3))
    create_session(session, sampled)
    for posture in sampled.postures:
        write_posture(session, posture)
    assert main(["calibrate", str(session), "--json", str(root / "r.json"), "--quiet"]) == 0
    return session, json.loads((root / "r.json").read_text())


def _copy(session, folder):
    import shutil

    copy = folder / session.name
    shutil.copytree(session, copy)
    return copy


def test_calibrate_saves_the_pose_its_uncertainty_method_version_and_postures(calibrated):
    from handeye import __version__
    from handeye.station.result_file import postures_hash

    session, printed = calibrated
    saved = yaml.safe_load((session / "result.yaml").read_text())
    assert saved["format"] == "handeye-result/1" and saved["method"] == printed["method"] == "ml"
    assert saved["camera_pose"] == printed["camera_pose"]  # parent, position_mm, quaternion_wxyz (w >= 0)
    assert saved["camera_pose"]["parent"] == "tool0" and saved["camera_pose"]["quaternion_wxyz"][0] >= 0
    assert saved["uncertainty"]["translation_mm"] == printed["uncertainty"]["translation_mm"]
    assert saved["code_version"] == __version__ and saved["calibrated_at"].endswith("Z")
    assert saved["postures"]["ids"] == list(range(14)) and saved["postures"]["count"] == 14
    assert saved["postures"]["sha256"] == postures_hash(session) and len(saved["postures"]["sha256"]) == 64


def _literal_pose(out: str):
    literal = next(line for line in out.splitlines() if line.startswith("PERS tooldata"))
    numbers = literal.split("[[", 1)[1].split("]]", 1)[0].replace("],[", ",").split(",")
    return np.array([float(v) for v in numbers])


def test_writeback_writes_the_saved_result_without_solving(calibrated, capsys, monkeypatch):
    session, printed = calibrated
    monkeypatch.setattr(solve, "_calibrate", lambda *a, **k: pytest.fail("writeback solved the session again"))
    capsys.readouterr()
    assert main(["writeback", str(session), "--dry-run"]) == 0
    pose = _literal_pose(capsys.readouterr().out)
    saved = printed["camera_pose"]
    assert np.allclose(pose[:3], saved["position_mm"], atol=6e-4) and np.allclose(pose[3:], saved["quaternion_wxyz"],
                                                                                 atol=6e-7)


@pytest.mark.parametrize("change", ["edit", "add", "remove"])
def test_a_result_older_than_its_postures_is_refused_with_what_to_do(calibrated, tmp_path, capsys, change):
    session = _copy(calibrated[0], tmp_path)
    postures = session / "postures"
    if change == "edit":
        path = postures / "005.yaml"
        posture = yaml.safe_load(path.read_text())
        posture["points_mm"][0][0] += 0.01
        path.write_text(yaml.safe_dump(posture))
    elif change == "add":
        (postures / "014.yaml").write_text((postures / "013.yaml").read_text().replace("index: 13", "index: 14"))
    else:
        (postures / "013.yaml").unlink()
    capsys.readouterr()
    assert main(["writeback", str(session), "--dry-run"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is older than the session's postures" in err
    assert err.rstrip().endswith(f"run handeye calibrate {session}") and "Traceback" not in err
    assert main(["calibrate", str(session), "--quiet", "--json", str(tmp_path / "r.json")]) == 0
    assert main(["writeback", str(session), "--dry-run"]) == 0  # calibrated again: accepted


def test_touching_the_posture_files_is_not_a_change(calibrated, tmp_path):
    session = _copy(calibrated[0], tmp_path)
    for path in (session / "postures").iterdir():
        os.utime(path, (path.stat().st_atime + 3600, path.stat().st_mtime + 3600))  # newer than result.yaml
    assert main(["writeback", str(session), "--dry-run"]) == 0


def test_without_a_result_writeback_solves_says_so_and_saves_it(calibrated, tmp_path, capsys):
    session = _copy(calibrated[0], tmp_path)
    (session / "result.yaml").unlink()
    capsys.readouterr()
    assert main(["writeback", str(session), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert f"no result.yaml in {session}" in out and "solving it now" in out
    saved = yaml.safe_load((session / "result.yaml").read_text())
    pose = _literal_pose(out)
    assert np.allclose(pose[:3], saved["camera_pose"]["position_mm"], atol=6e-4)


def test_another_method_than_the_saved_one_is_refused(calibrated, capsys):
    session, _ = calibrated
    capsys.readouterr()
    assert main(["writeback", str(session), "--dry-run", "--method", "mcb"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds the ml result" in err and f"handeye calibrate {session} --method mcb" in err


def test_a_damaged_result_is_refused_in_one_line(calibrated, tmp_path, capsys):
    session = _copy(calibrated[0], tmp_path)
    text = (session / "result.yaml").read_text()
    (session / "result.yaml").write_text(text.replace("camera_pose:", "camera_pos:"))
    capsys.readouterr()
    assert main(["writeback", str(session), "--dry-run"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is damaged" in err and f"run handeye calibrate {session}" in err


def test_the_saved_pose_round_trips_to_the_solved_one(calibrated):
    from handeye.station.result_file import read_result

    session, printed = calibrated
    saved = read_result(session)
    pose = printed["camera_pose"]
    assert np.allclose(saved.result.x, transform_from_pose(pose["position_mm"], pose["quaternion_wxyz"]), atol=1e-12)
    assert saved.result.method == "ml" and saved.result.uncertainty is not None
