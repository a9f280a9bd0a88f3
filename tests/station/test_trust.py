"""Never a confident wrong answer at the station: the mock only when asked, lengths that must be
millimetres, write-back that needs only the controller and never loses the old tool data."""

from __future__ import annotations

import re
import time
from dataclasses import replace

import numpy as np
import pytest
import yaml

from handeye.calibration.plausibility import UnitsError, check_plausible, implausibilities, session_in_mm
from handeye.calibration.session import create_session, read_session, write_posture
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.geometry.transforms import translation_error_mm
from handeye.drivers.controller import open_controller
from handeye.drivers.controller.errors import ControllerRefused, ControllerTimeout
from handeye.mocks.controller import start_mock_controller
from handeye.mocks.station import MockStation
from handeye.station.capture.loop import CaptureError, capture
from handeye.station.cli import main
from handeye.station.config.station import ConfigError, config_from_dict, default_config, load_config
from handeye.station.origin import session_origin
from handeye.station.runtime import StationLink
from handeye.station.writeback import PENDING_FILE, WritebackError, writeback

from helpers import scene

REAL_STATION = {"controller": {"protocol": "socket", "host": "127.0.0.1", "port": 1, "timeout_s": 0.5},
                "camera": {"backend": "xb3"}}


def _write(path, session):
    create_session(path, session)
    for p in session.postures:
        write_posture(path, p)
    return path


def _synthetic(postures=20, sigma_cam=0.2, seed=3):
    return sample_session(scene(postures), NoiseConfig(sigma_cam_mm=sigma_cam, seed=seed))


def _scaled(session, robot=1.0, board=1.0, only=None):
    """The session with lengths multiplied (robot side, board side), optionally for one posture only."""
    postures = []
    for k, p in enumerate(session.postures):
        if only is not None and k != only:
            postures.append(p)
            continue
        tool0 = None if p.tool0_in_base is None else p.tool0_in_base.copy()
        if tool0 is not None:
            tool0[:3, 3] *= robot
        postures.append(replace(p, tool0_in_base=tool0, points_mm=None if p.points_mm is None else p.points_mm * board))
    return replace(session, postures=postures)


def _config_file(tmp_path, data, name="station.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def _one_error_line(capsys):
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in captured.err, captured.err
    return captured.out, err[0]


# ---------------------------------------------------------------------------------- the mock only when asked
@pytest.mark.parametrize("data, key", [
    ({"camera": {"backend": "xb3"}}, "controller.protocol is missing"),
    ({"controller": {"protocol": "socket"}}, "camera.backend is missing"),
    ({"controller": {"host": "192.168.125.1"}, "camera": {"backend": "xb3"}}, "controller.protocol is missing"),
    ({"target": {"corners": [13, 8]}}, "is missing"),
])
def test_a_config_that_names_no_hardware_is_refused(data, key):
    with pytest.raises(ConfigError, match=key):
        config_from_dict(data)


def test_the_mock_camera_needs_the_mock_robot():
    with pytest.raises(ConfigError, match="the mock camera only sees the mock robot"):
        config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "mock"}})
    assert config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}).is_mock
    assert not config_from_dict(REAL_STATION).is_mock
    assert default_config().is_mock and load_config.__doc__


@pytest.mark.parametrize("command", ["capture", "writeback"])
def test_a_minimal_config_is_refused_on_the_command_line(tmp_path, capsys, command):
    config = _config_file(tmp_path, {"controller": {"host": "127.0.0.1", "port": 1}})
    session = _write(tmp_path / "s", _synthetic(10))
    argv = ["capture", "--config", str(config), "--session", str(tmp_path / "new")] if command == "capture" else \
        ["writeback", str(session), "--config", str(config)]
    assert main(argv) == 1
    out, err = _one_error_line(capsys)
    assert "controller.protocol is missing" in err and "identical" not in out
    assert not (tmp_path / "new").exists()


def test_writeback_to_a_controller_that_is_not_there_fails_without_a_mock(tmp_path, capsys):
    session = _write(tmp_path / "s", _synthetic(20))
    config = _config_file(tmp_path, REAL_STATION)
    started = time.monotonic()
    assert main(["writeback", str(session), "--config", str(config), "--force"]) == 1
    elapsed = time.monotonic() - started
    out, err = _one_error_line(capsys)
    assert "127.0.0.1:1" in err and "identical" not in out and "MOCK" not in out
    assert elapsed < 30  # the solve plus a 0.5 s link budget; never the 120 s motion timeout
    assert not list(session.glob("tooldata_backup_*")) and not (session / "writeback.yaml").exists()


def test_capture_with_a_controller_that_is_not_there_records_nothing(tmp_path, capsys):
    config = _config_file(tmp_path, REAL_STATION)
    assert main(["capture", "--config", str(config), "--session", str(tmp_path / "s")]) == 1
    out, err = _one_error_line(capsys)
    assert "127.0.0.1:1" in err and "MOCK" not in out
    assert not (tmp_path / "s").exists()


def test_writeback_opens_only_the_controller(tmp_path, capsys, monkeypatch, no_leaked_threads):
    import handeye.drivers.camera as camera_package

    def no_camera(*args, **kwargs):
        raise AssertionError("write-back opened the camera")

    monkeypatch.setattr(camera_package, "open_camera", no_camera)
    session = _write(tmp_path / "s", _synthetic(20))
    with start_mock_controller("socket", time_scale=0.002, write_key="cell-7-writes") as server:
        config = _config_file(tmp_path, {"controller": {"protocol": "socket", "host": "127.0.0.1", "port": server.port,
                                                        "write_key": "cell-7-writes"},
                                         "camera": {"backend": "xb3"}})
        assert main(["writeback", str(session), "--config", str(config), "--force"]) == 0
        held = server.robot.tool
    out = capsys.readouterr().out
    assert "read back: identical" in out and "MOCK" not in out
    result = calibrate(problem_from_session(read_session(session)))
    assert np.allclose(held.position_mm, np.round(result.x[:3, 3], 3), atol=1e-6)


def test_mock_runs_say_mock_and_are_recorded(tmp_path, capsys, no_leaked_threads):
    assert main(["capture", "--mock", "--session", str(tmp_path / "s"), "--postures", "6"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("MOCK: the embedded mock station")
    assert all(line.startswith("MOCK") or not line.strip() for line in out.splitlines())
    session = read_session(tmp_path / "s")
    assert session.extra["capture"]["station"] == "mock" and session_origin(session) == "mock"
    assert main(["writeback", str(tmp_path / "s"), "--mock", "--force"]) == 0
    assert "MOCK read back: identical" in capsys.readouterr().out
    assert yaml.safe_load((tmp_path / "s" / "writeback.yaml").read_text())["controller"] == "mock"


@pytest.mark.parametrize("origin", ["mock", "simulated"])
def test_a_mock_or_simulated_session_is_never_written_to_a_real_controller(tmp_path, capsys, origin):
    if origin == "simulated":
        assert main(["simulate", "-o", str(tmp_path / "s"), "--postures", "12"]) == 0
    else:
        session = _synthetic(12)
        session.extra["capture"] = {"station": "mock", "plan_joints_deg": []}
        _write(tmp_path / "s", session)
    capsys.readouterr()
    config = _config_file(tmp_path, REAL_STATION)
    assert main(["writeback", str(tmp_path / "s"), "--config", str(config), "--force"]) == 1
    out, err = _one_error_line(capsys)
    assert "not your robot's" in err and ("mock station" in err or "simulation" in err)


def test_a_mock_session_is_not_resumed_on_the_real_station(tmp_path):
    session = _synthetic(6)
    session.extra["capture"] = {"station": "mock", "plan_joints_deg": [[0.0] * 6] * 6}
    _write(tmp_path / "s", session)
    with pytest.raises(CaptureError, match="captured on the mock station"):
        capture(config_from_dict(REAL_STATION), tmp_path / "s", StationLink(None))


# ---------------------------------------------------------------------------------- lengths in millimetres
def test_a_session_in_metres_is_refused_and_converted_only_when_asked(tmp_path, capsys):
    truth_session = _synthetic(20)
    path = _write(tmp_path / "m", _scaled(truth_session, robot=1e-3, board=1e-3))
    assert main(["calibrate", str(path)]) == 1
    _, err = _one_error_line(capsys)
    assert "the session looks like metres" in err and "--units m" in err
    assert main(["calibrate", str(path), "--units", "m", "--json", str(tmp_path / "r.json")]) == 0
    converted = calibrate(problem_from_session(session_in_mm(read_session(path), "m")))
    reference = calibrate(problem_from_session(truth_session))
    assert translation_error_mm(converted.x, reference.x) < 1e-3
    config = _config_file(tmp_path, REAL_STATION)
    assert main(["writeback", str(path), "--config", str(config), "--force"]) == 1
    assert "looks like metres" in _one_error_line(capsys)[1]


@pytest.mark.parametrize("robot, board, only, kind, words", [
    (1e-3, 1.0, None, "robot_metres", "robot poses look like metres"),
    (1.0, 1e-3, None, "board_metres", "board measurements look like metres"),
    (1e-3, 1.0, 4, "posture_unit", "posture 4: the flange's distance"),
    (1.0, 1e-3, 7, "posture_unit", "posture 7: the board's distance"),
    (10.0, 10.0, None, "reach", "beyond the reach of the IRB1400"),
])
def test_partial_unit_mix_ups_name_the_units(robot, board, only, kind, words):
    session = _scaled(_synthetic(20), robot, board, only)
    found = implausibilities(session, np.array([p.tool0_in_base for p in session.postures]))
    assert found and found[0].kind == kind and words in found[0].message
    with pytest.raises(UnitsError, match=words):
        problem_from_session(session)


def test_the_square_size_must_match_the_measured_corners():
    session = _synthetic(12)
    assert not implausibilities(session, np.array([p.tool0_in_base for p in session.postures]))
    wrong = replace(session, target=replace(session.target, square_mm=3.0))
    with pytest.raises(UnitsError, match="corners are 30 mm apart but target.square_mm is 3 mm"):
        check_plausible(wrong, np.array([p.tool0_in_base for p in session.postures]))
    close = replace(session, target=replace(session.target, square_mm=30.9))  # 3 %: a printer's tolerance
    check_plausible(close, np.array([p.tool0_in_base for p in session.postures]))


# ---------------------------------------------------------------------------------- write-back keeps the old values
def test_two_writebacks_in_one_second_keep_both_backups(tmp_path, monkeypatch, no_leaked_threads):
    prob = problem_from_session(_synthetic(20))
    result = calibrate(prob)
    moved = replace(result, x=result.x.copy())
    moved.x[:3, 3] += [1.0, -2.0, 0.5]
    monkeypatch.setattr(time, "strftime", lambda *args: "20261201-120000")
    config = default_config()
    with MockStation() as station, open_controller("socket", **station.controller_options()) as controller:
        original = controller.read_tool()
        first = writeback(tmp_path, config, result, controller, mock_controller=True)
        second = writeback(tmp_path, config, moved, controller, mock_controller=True)
    assert first.backup != second.backup
    backups = sorted(tmp_path.glob("tooldata_backup_*.yaml"))
    assert [b.name for b in backups] == ["tooldata_backup_20261201-120000.yaml", "tooldata_backup_20261201-120000_2.yaml"]
    kept = yaml.safe_load(backups[0].read_text())["values"]
    assert list(kept.values()) == original.values()
    assert list(yaml.safe_load(backups[1].read_text())["values"].values()) == first.new.values()


class _LinkFailsDuringWrite:
    """A controller whose tool write fails: after the save (``saved=True``) or before anything is sent."""

    def __init__(self, controller, error, saved: bool):
        self.controller, self.error, self.saved = controller, error, saved
        self.address = controller.address

    def read_tool(self):
        return self.controller.read_tool()

    def set_tool(self, tool):
        if self.saved:
            self.controller.set_tool(tool)
        raise self.error


@pytest.mark.parametrize("saved", [True, False])
def test_a_write_cut_off_says_so_and_the_next_run_tells_which_value_is_in_place(tmp_path, saved, no_leaked_threads):
    result = calibrate(problem_from_session(_synthetic(20)))
    config = default_config()
    with MockStation() as station, open_controller("socket", **station.controller_options()) as controller:
        flaky = _LinkFailsDuringWrite(controller, ControllerTimeout("TOOLSAVE: no reply within 2 s"), saved)
        with pytest.raises(WritebackError, match="may hold the new or the old tool data; run the same writeback again"):
            writeback(tmp_path, config, result, flaky, mock_controller=True)
        assert (tmp_path / PENDING_FILE).exists()
        again = writeback(tmp_path, config, result, controller, mock_controller=True)
    assert ("did reach the controller" if saved else "did not reach the controller") in again.previous
    assert again.readback_ok and not (tmp_path / PENDING_FILE).exists()
    assert len(list(tmp_path.glob("tooldata_backup_*.yaml"))) == 2


def test_a_refused_write_says_nothing_was_written(tmp_path, no_leaked_threads):
    result = calibrate(problem_from_session(_synthetic(20)))
    with MockStation() as station, open_controller("socket", **station.controller_options()) as controller:
        before = controller.read_tool()
        refusing = _LinkFailsDuringWrite(controller, ControllerRefused("refused TOOLSAVE: tool data invalid", 6), False)
        with pytest.raises(WritebackError, match="nothing was written"):
            writeback(tmp_path, default_config(), result, refusing, mock_controller=True)
        assert controller.read_tool() == before
    assert not (tmp_path / PENDING_FILE).exists()


# ---------------------------------------------------------------------------------- command-line values
@pytest.mark.parametrize("argv, words", [
    (["simulate", "-o", "x", "--postures", "100000"], "--postures: must be between 3 and 1000"),
    (["simulate", "-o", "x", "--corners", "8x13"], "give the long side first: 13x8"),
    (["calibrate"], "required: SESSION"),
])
def test_usage_errors_are_one_line_with_exit_code_2(argv, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    _, err = _one_error_line(capsys)
    assert words in err and err.startswith(f"handeye {argv[0]}: error:")


@pytest.mark.parametrize("offset_mm, quality, words", [
    (0.12, {}, "inside it (quality.min_camera_offset_mm 20): the session's lengths look like metres"),
    (600.0, {}, "beyond quality.max_camera_offset_mm (500)"),
    (600.0, {"max_camera_offset_mm": 700}, None),
])
def test_the_camera_offset_is_checked_before_every_write_forced_or_not(tmp_path, offset_mm, quality, words):
    result = calibrate(problem_from_session(_synthetic(12)))
    result.x[:3, 3] *= offset_mm / np.linalg.norm(result.x[:3, 3])
    config = replace(default_config(), quality=quality)
    if words is None:
        assert writeback(tmp_path, config, result, None, dry_run=True, force=True).literal.startswith("PERS tooldata")
        return
    with pytest.raises(WritebackError, match=re.escape(words)):
        writeback(tmp_path, config, result, None, dry_run=True, force=True)
