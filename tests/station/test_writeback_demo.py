"""Write-back and the demo, end to end against the mock controller over real sockets."""

import json
from dataclasses import replace

import numpy as np
import pytest
import yaml

from handeye.calibration.session import create_session, write_posture
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.drivers.controller import open_controller
from handeye.mocks.station import MockStation
from handeye.station.cli import main
from handeye.station.config.station import default_config
from handeye.station.writeback import WritebackError, writeback

from helpers import problem as synthetic_problem
from helpers import scene


def _session(tmp_path, postures=20, sigma_cam=0.2, setup="eye_in_hand"):
    session = sample_session(scene(postures, setup), NoiseConfig(sigma_cam_mm=sigma_cam, seed=3))
    path = tmp_path / "s"
    create_session(path, session)
    for p in session.postures:
        write_posture(path, p)
    return path


def test_dry_run_prints_the_rapid_literal(tmp_path, capsys):
    path = _session(tmp_path)
    assert main(["writeback", str(path), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "PERS tooldata tHeCamera := [TRUE,[[" in out
    assert not list(path.glob("tooldata_backup_*"))  # nothing touched


@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus", "rws"])
def test_writes_reads_back_and_keeps_a_backup(tmp_path, no_leaked_threads, protocol):
    from handeye.calibration.solve import calibrate
    from handeye.mocks.station import MockStationSpec

    prob, truth, _ = synthetic_problem(20, sigma_cam=0.2, seed=3)
    result = calibrate(prob)
    config = default_config()
    with MockStation(MockStationSpec(protocol=protocol)) as station, \
            open_controller(protocol, **station.controller_options()) as controller:
        old = controller.read_tool()
        outcome = writeback(tmp_path, config, result, controller)
        held = station.arm.tool
    assert outcome.readback_ok and outcome.old == old
    assert np.allclose(held.position_mm, np.round(result.x[:3, 3], 3), atol=1e-9)
    backup = yaml.safe_load(outcome.backup.read_text())
    assert backup["values"]["q1"] == old.quaternion_wxyz[0]
    record = yaml.safe_load((tmp_path / "writeback.yaml").read_text())
    assert record["read_back_ok"] is True and record["literal"].startswith("PERS tooldata tHeCamera := [TRUE,")


def test_a_failed_verdict_is_refused_unless_forced(tmp_path, capsys):
    path = _session(tmp_path, postures=8, sigma_cam=5.0)  # few postures, heavy noise: verdict fails
    assert main(["writeback", str(path), "--mock"]) == 1
    err = capsys.readouterr().err
    assert "failed its quality verdict" in err and "--force" in err and err.count("\n") == 1
    assert not list(path.glob("tooldata_backup_*"))
    assert main(["writeback", str(path), "--mock", "--force"]) == 0
    assert "identical to the last digit" in capsys.readouterr().out


def test_eye_to_hand_results_are_not_tool_data(tmp_path):
    from handeye.calibration.solve import calibrate

    prob, _, _ = synthetic_problem(10, setup="eye_to_hand", sigma_cam=0.2)
    with pytest.raises(WritebackError, match="only an eye-in-hand"):
        writeback(tmp_path, default_config(), calibrate(prob), None, dry_run=True)


def test_bad_tool_values_are_refused_before_sending(tmp_path):
    from handeye.calibration.solve import calibrate

    prob, _, _ = synthetic_problem(10, sigma_cam=0.2)
    result = calibrate(prob)
    result.x[:3, 3] = [2000.0, 0.0, 0.0]  # a frame 2 m from the flange: units wrong somewhere
    with pytest.raises(WritebackError, match="from the flange"):
        writeback(tmp_path, default_config(), result, None, dry_run=True)
    config = default_config()
    with pytest.raises(WritebackError, match="mass"):
        writeback(tmp_path, replace(config, tool=replace(config.tool, mass_kg=0.0)), calibrate(prob), None, dry_run=True)


@pytest.mark.parametrize("protocol, postures", [("socket", 30), ("serial", 12), ("modbus", 12), ("rws", 12)])
def test_demo_recovers_the_hidden_mount(tmp_path, protocol, postures, capsys, no_leaked_threads):
    """The demo on every link: the capture's own RAPID modules are loaded into the mock and executed."""
    out = tmp_path / "demo.json"
    code = main(["demo", "--session", str(tmp_path / "demo"), "--json", str(out), "--protocol", protocol,
                 "--postures", str(postures)] + (["--no-report"] if protocol != "socket" else []))
    result = json.loads(out.read_text())
    assert {"camera_pose", "truth_camera_pose", "postures_captured", "readback_ok"} <= set(result)
    assert result["postures_captured"] == postures and result["readback_ok"] is True
    assert result["errors"]["rotation_error_deg"] <= 0.05 and result["errors"]["translation_error_mm"] <= 0.5
    assert code == 0
    assert result["camera_pose"]["parent"] == "tool0" and result["camera_pose"]["quaternion_wxyz"][0] >= 0
    if protocol == "socket":
        assert result["verdict"]["passed"] and (tmp_path / "demo" / "session" / "report.html").exists()
    text = capsys.readouterr().out
    assert "hidden truth" in text and "read back: identical" in text


def test_demo_refuses_to_replace_a_folder_it_did_not_make(tmp_path, capsys):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "important.txt").write_text("keep me")
    assert main(["demo", "--session", str(tmp_path / "mine")]) == 1
    assert "not a demo folder" in capsys.readouterr().err
    assert (tmp_path / "mine" / "important.txt").exists()
