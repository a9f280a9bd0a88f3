"""Rehearsing the station without hardware: the real drivers against `handeye mock controller` in
another process, whose RAPID interpreter runs the session's program and whose arm carries the mock
camera (camera.backend: mock, camera.mock_arm: HOST:PORT). The silent mixing of a mock camera with a
real controller stays refused."""

from __future__ import annotations

import re

import pytest
import yaml
from helpers import start_mock_station, stop_standalone_mock

from handeye.base.errors import ConfigError
from handeye.calibration.session import read_session
from handeye.station.cli import main
from handeye.station.config.station import config_from_dict
from handeye.station.origin import session_origin

KEY = "rehearse-key_07"


# ---------------------------------------------------------------------------------------- the config's rule
def test_a_mock_camera_with_a_real_controller_needs_the_mock_arm():
    with pytest.raises(ConfigError, match="mock camera only sees the mock robot.*camera.mock_arm"):
        config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "mock"}})
    config = config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "mock",
                                                                               "mock_arm": "127.0.0.1:1100"}})
    assert config.is_rehearsal and not config.is_mock
    assert config.to_dict()["camera"]["mock_arm"] == "127.0.0.1:1100"


@pytest.mark.parametrize("controller, camera, message", [
    ("socket", {"backend": "xb3", "mock_arm": "127.0.0.1:1100"}, "camera.mock_arm is for a rehearsal"),
    ("mock", {"backend": "mock", "mock_arm": "127.0.0.1:1100"}, "camera.mock_arm is for a rehearsal"),
    ("mock", {"backend": "xb3"}, "the embedded mock station has its own camera"),
    ("socket", {"backend": "mock", "mock_arm": "nowhere"}, "camera.mock_arm must be HOST:PORT"),
])
def test_silent_mixing_stays_refused(controller, camera, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict({"controller": {"protocol": controller}, "camera": camera})
    assert not config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}).is_rehearsal


# ---------------------------------------------------------------------------------------- the rehearsal
def _start_mock(protocol: str):
    """`handeye mock controller` with a camera, in its own process; returns (process, link section, mock_arm)."""
    return start_mock_station(protocol, KEY)[:3]


def _config(tmp_path, protocol: str, link: dict, mock_arm: str, postures: int):
    path = tmp_path / "rehearsal.yaml"
    path.write_text(yaml.safe_dump({
        "controller": {"protocol": protocol, "write_key": KEY, **link},
        "camera": {"backend": "mock", "mock_arm": mock_arm},
        "plan": {"postures": postures},
    }))
    return path


def _stop(proc) -> None:
    stop_standalone_mock(proc)


@pytest.mark.parametrize("protocol", ["socket", "modbus", "rws"])
def test_capture_calibrate_writeback_against_the_standalone_mock(tmp_path, capsys, protocol):
    proc, link, mock_arm = _start_mock(protocol)
    try:
        config = _config(tmp_path, protocol, link, mock_arm, 10)
        session = tmp_path / "s"
        assert main(["capture", "--config", str(config), "--session", str(session), "--yes"]) == 0
        out = capsys.readouterr().out
        lines = [line for line in out.splitlines() if line.strip()]
        assert lines[0].startswith("MOCK: rehearsal") and mock_arm in lines[0]
        assert all(line.startswith("MOCK") for line in lines), out
        # the session's own RAPID (10 approved postures; the mock started with the generated program's 12) was
        # loaded into the mock controller and executed
        assert "10 of 10 postures" in out and (session / "rapid" / "HeMain.mod").is_file()
        assert session_origin(read_session(session)) == "mock"
        if protocol == "rws":  # the PC itself uploaded, loaded and started the program over RWS, and stopped it
            assert "RAPID program stopped" in out

        assert main(["calibrate", str(session)]) == 0
        assert "MOCK SESSION" in capsys.readouterr().out

        assert main(["writeback", str(session), "--config", str(config), "--force"]) == 0
        out = capsys.readouterr().out
        assert "MOCK read back: identical to the last digit" in out and "MOCK: rehearsal" in out
    finally:
        _stop(proc)


def test_a_rehearsal_config_naming_another_controller_is_refused(tmp_path, capsys):
    proc, link, mock_arm = _start_mock("socket")
    try:
        wrong = {**link, "port": link["port"] + 1 if link["port"] < 65535 else link["port"] - 1}
        config = _config(tmp_path, "socket", wrong, mock_arm, 6)
        assert main(["capture", "--config", str(config), "--session", str(tmp_path / "s")]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "a rehearsal drives the mock controller whose arm the mock camera sees" in err
        assert not (tmp_path / "s").exists()
    finally:
        _stop(proc)


def test_the_shipped_rehearsal_config_is_a_rehearsal_of_the_mock_the_docs_start():
    from pathlib import Path

    from handeye.station.config.station import REHEARSAL_FILE, load_config

    config = load_config(REHEARSAL_FILE)
    assert config.is_rehearsal and not config.is_mock
    repo = Path(__file__).resolve().parents[2]
    readme = (repo / "docs" / "rehearsal.md").read_text()
    command = re.search(r"handeye mock controller --port (\d+) --camera-port (\d+) --write-key (\S+)", readme)
    assert command, "the rehearsal page (docs/rehearsal.md) starts the mock for the rehearsal"
    port, camera_port, key = command.groups()
    assert (config.controller.port, config.camera.mock_arm) == (int(port), f"127.0.0.1:{camera_port}")
    assert config.controller.write_key == key
    assert f"--config {REHEARSAL_FILE.resolve().relative_to(repo).as_posix()}" in readme
