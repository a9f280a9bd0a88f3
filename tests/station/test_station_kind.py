"""One decision of which station a command runs on (station/config/station_kind.py): any mock part (the embedded
station, a simulated camera, the camera of `handeye mock controller`, a driver that says it talks to a
simulation, data derived from a mock session) makes it a mock station; a session on disk that says
``real`` beside a recorded mock configuration reads as ``mock``. The end-to-end paths over every link
are tests/station/test_mock_never_real.py."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from handeye.calibration.session import create_session, read_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.station.config.station import config_from_dict, default_config
from handeye.station.origin import MOCK, REAL, session_origin
from handeye.station.runtime import StationLink, open_station
from handeye.station.config.station_kind import mock_parts, station_kind, station_tag

from helpers import scene

REAL_CONFIG = {"controller": {"protocol": "socket", "host": "127.0.0.1", "port": 1}, "camera": {"backend": "xb3"}}
REHEARSAL = {"controller": {"protocol": "socket", "host": "127.0.0.1", "port": 1},
             "camera": {"backend": "mock", "mock_arm": "127.0.0.1:1100"}}


@pytest.mark.parametrize("data, kind", [
    (REAL_CONFIG, REAL),
    (REHEARSAL, MOCK),
    ({"controller": {"protocol": "modbus"}, "camera": {"backend": "mock", "mock_arm": "127.0.0.1:1100"}}, MOCK),
    ({"controller": {"protocol": "rws", "host": "127.0.0.1", "port": 1}, "camera": {"backend": "mock",
                                                                                      "mock_arm": "127.0.0.1:1100"}},
     MOCK),
    ({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}, MOCK),
])
def test_the_config_alone(data, kind):
    config = config_from_dict(data)
    assert station_kind(config) == kind
    assert station_tag(config) == ("MOCK " if kind == MOCK else "")
    assert bool(mock_parts(config)) == (kind == MOCK)


class _Driver:
    def __init__(self, simulated):
        self.simulated = simulated


@pytest.mark.parametrize("link, part", [
    (StationLink(_Driver(False), _Driver(False), mock=object()), "embedded mock"),
    (StationLink(_Driver(False), _Driver(False), rehearsal="127.0.0.1:1100"), "rehearsal camera"),
    (StationLink(_Driver(True), _Driver(False)), "controller that says it is a simulation"),
    (StationLink(_Driver(False), _Driver(True)), "camera that says it is a simulation"),
    (SimpleNamespace(controller=_Driver(True)), "controller that says"),  # a link of another shape: no .mock
])
def test_any_mock_part_of_the_link_makes_a_real_config_a_mock_station(link, part):
    config = config_from_dict(REAL_CONFIG)
    assert station_kind(config, link) == MOCK
    assert any(part in p for p in mock_parts(config, link)), mock_parts(config, link)
    assert station_tag(config, link) == "MOCK "


def test_a_real_link_and_real_data_are_the_real_station():
    config = config_from_dict(REAL_CONFIG)
    link = StationLink(_Driver(False), _Driver(False))
    assert station_kind(config, link, REAL) == REAL
    assert station_kind(config, SimpleNamespace(controller=object(), camera=object())) == REAL
    for origin in (MOCK, "simulated", "unknown"):  # data derived from anything but a real session
        assert station_kind(config, link, origin) == MOCK


@pytest.mark.parametrize("protocol, simulated", [("rws", True), ("socket", False)])
def test_the_mock_robot_web_services_announce_a_simulation(protocol, simulated):
    """The standalone and the embedded mock's RWS say they are ``handeye-mock``: the driver knows it talks to
    a simulation (a line protocol has no such word: the config's mock camera says it there)."""
    from dataclasses import replace

    config = default_config()
    config = replace(config, mock=replace(config.mock, protocol=protocol))
    with open_station(config, mock=True) as link:
        assert link.controller.simulated is simulated
        assert link.camera.simulated is True


@pytest.mark.parametrize("camera", [{"backend": "mock", "mock_arm": "127.0.0.1:1100"}, {"backend": "mock"}])
def test_a_session_recorded_real_beside_a_mock_configuration_reads_as_mock(tmp_path, camera):
    """Sessions written before the decision was one (a guided rehearsal said ``station: real``) are mock."""
    session = sample_session(scene(4), NoiseConfig(seed=1))
    session.extra["capture"] = {"station": "real", "mode": "guided",
                                "config": {"controller": {"protocol": "socket"}, "camera": camera}}
    create_session(tmp_path / "s", session)
    assert session_origin(read_session(tmp_path / "s")) == MOCK
    assert session_origin(path=tmp_path / "s") == MOCK
    session.extra["capture"]["config"]["camera"] = {"backend": "xb3"}
    create_session(tmp_path / "r", session)
    assert session_origin(path=tmp_path / "r") == REAL


def test_a_real_config_over_a_link_that_is_a_mock_says_mock_on_every_line(tmp_path, capsys, monkeypatch):
    """The config names real hardware, but the link opened is a mock (here the embedded one stands in for a
    controller that says it is a simulation): capture re-decides once the link is open; every line says MOCK
    and the session is a mock one."""
    import yaml

    from handeye.station import runtime
    from handeye.station.cli import main

    opened = runtime.open_station
    monkeypatch.setattr(runtime, "open_station", lambda config, session_dir=None: opened(config, True, session_dir))
    real = tmp_path / "real.yaml"
    real.write_text(yaml.safe_dump({**REAL_CONFIG, "plan": {"postures": 6}}))
    assert main(["capture", "--config", str(real), "--session", str(tmp_path / "s"), "--plan-only"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.strip()]
    assert lines[0].startswith("MOCK: the embedded mock station's controller and camera") and "never written" in lines[0]
    assert all(line.startswith("MOCK") for line in lines), lines
    assert session_origin(read_session(tmp_path / "s")) == MOCK
