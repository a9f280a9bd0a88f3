"""The station's write key: configured once, used by the link, never printed, never in a session."""

import numpy as np
import pytest
import yaml

from handeye.drivers.controller import InvalidRequest, ToolData, open_controller
from handeye.drivers.controller.types import write_key_code
from handeye.mocks.station import MockStation, MockStationSpec
from handeye.station.capture.loop import capture
from handeye.station.cli import main
from handeye.station.config.station import ConfigError, config_from_dict, default_config
from handeye.station.runtime import _controller_options, open_station

KEY = "Station-7_secret"


def _config(**controller):
    """A station config (the embedded mock station: both back ends named, as a file must)."""
    return config_from_dict({"controller": {"protocol": "mock", **controller}, "camera": {"backend": "mock"},
                             "plan": {"postures": 3}})


def _keyed_config(**controller):
    return _config(write_key=KEY, **controller)


def test_the_key_is_never_in_repr_or_to_dict():
    config = _keyed_config()
    assert config.controller.write_key == KEY
    for text in (repr(config), str(config), repr(config.controller)):
        assert KEY not in text
    record = config.to_dict()
    assert record["controller"]["write_key"] == "<set>" and KEY not in yaml.safe_dump(record)
    assert default_config().to_dict()["controller"]["write_key"] is None


@pytest.mark.parametrize("value, message", [
    ("short", "8 to 32"), ("x" * 40, "8 to 32"), ("with spaces in", "8 to 32"), (123456789, "quote it in YAML"),
])
def test_bad_keys_are_refused_without_echo(value, message):
    with pytest.raises(ConfigError, match=f"controller.write_key .*{message}") as info:
        _config(write_key=value)
    assert str(value) not in str(info.value)


@pytest.mark.parametrize("value", [0.05, 0, 11, "5"])
def test_idle_timeout_must_be_a_tenth_to_ten_seconds(value):
    with pytest.raises(ConfigError, match="controller.idle_timeout_s"):
        _config(idle_timeout_s=value)
    assert default_config().controller.idle_timeout_s == 5.0
    assert _config(idle_timeout_s=0.1).controller.idle_timeout_s == 0.1


def test_the_controller_options_carry_the_key_and_the_idle_timeout():
    options = _controller_options(_keyed_config(idle_timeout_s=2.5))
    assert options["write_key"] == KEY and options["idle_timeout"] == 2.5
    rapid = _keyed_config().rapid_dict([[0, 0, 0, 0, 30, 0]])["controller"]
    assert rapid["write_key"] == KEY and rapid["idle_timeout_s"] == 5.0  # for HeKey.sys; never written to disk by capture


def test_a_capture_and_writeback_with_a_key_leave_no_trace_of_it(tmp_path, no_leaked_threads):
    from handeye.calibration.session import read_session
    from handeye.calibration.solve import calibrate, problem_from_session
    from handeye.station.writeback import writeback

    config = _keyed_config()
    session = tmp_path / "s"
    with open_station(config, mock=True) as link:
        summary = capture(config, session, link)
        assert summary.complete
        result = calibrate(problem_from_session(read_session(session)))
        outcome = writeback(session, config, result, link.controller)
        assert outcome.readback_ok  # the key reached the controller: the write went through
    files = [p for p in session.rglob("*") if p.is_file()]
    assert any(p.suffix == ".mod" for p in files) and any(p.name == "writeback.yaml" for p in files)
    assert not any(p.suffix == ".sys" for p in files)  # HeKey.sys is never part of a session
    for path in files:
        data = path.read_bytes()
        assert KEY.encode() not in data, path
        assert str(write_key_code(KEY)).encode() not in data, path
    header = yaml.safe_load((session / "session.yaml").read_text())
    assert header["capture"]["config"]["controller"]["write_key"] == "<set>"


def test_the_embedded_mock_makes_a_key_per_run_and_hands_it_to_the_pc(no_leaked_threads):
    tool = ToolData((1.0, 2.0, 90.0), (1.0, 0.0, 0.0, 0.0), 1.2)
    with MockStation(MockStationSpec()) as a, MockStation(MockStationSpec()) as b:
        key_a, key_b = a.controller_options()["write_key"], b.controller_options()["write_key"]
        assert key_a != key_b and len(key_a) == 32
        with open_controller("socket", **a.controller_options()) as c:
            assert c.set_tool(tool).close_to(tool)
        options = {**a.controller_options(), "write_key": None}
        with open_controller("socket", **options) as c, pytest.raises(InvalidRequest, match="write_key"):
            c.set_tool(tool)
    with MockStation(MockStationSpec(write_key=KEY)) as station:  # or the station's own key
        assert station.controller_options()["write_key"] == KEY
        assert KEY not in repr(station.spec)


def test_writeback_without_a_key_says_what_to_do(tmp_path):
    """A real (not mock) station without controller.write_key: one line that names the fix."""
    from handeye.calibration.solve import calibrate

    from helpers import problem as synthetic_problem

    prob, _, _ = synthetic_problem(10, sigma_cam=0.2)
    result = calibrate(prob)
    with MockStation(MockStationSpec()) as station:
        before = station.arm.tool
        options = {**station.controller_options(), "write_key": None}
        with open_controller("socket", **options) as controller:
            from handeye.station.writeback import WritebackError, writeback

            with pytest.raises(WritebackError, match="controller.write_key.*HeKey.sys") as info:
                writeback(tmp_path, default_config(), result, controller)
            assert "\n" not in str(info.value)
        assert station.arm.tool == before and np.allclose(before.position_mm, station.arm.tool.position_mm)


def test_mock_controller_cli_takes_the_key_from_the_config(tmp_path, capsys):
    config = tmp_path / "station.yaml"
    config.write_text(yaml.safe_dump({"controller": {"protocol": "socket", "write_key": KEY, "idle_timeout_s": 1.5,
                                                     "host": "192.168.125.1", "timeout_s": 2.0},
                                      "camera": {"backend": "xb3"}}))
    assert main(["mock", "controller", "--config", str(config), "--port", "0", "--duration", "0.2"]) == 0
    captured = capsys.readouterr()
    assert "idle timeout 1.5 s; tool writes need the write key" in captured.out
    assert KEY not in captured.out + captured.err
    assert main(["mock", "controller", "--port", "0", "--duration", "0.2"]) == 0
    assert "tool writes refused: no write key (start it with --write-key KEY or --config" in capsys.readouterr().out
    assert main(["mock", "controller", "--port", "0", "--duration", "0.2", "--write-key", "bad"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--write-key must be 8 to 32" in err and "bad" not in err.split("got")[1]


@pytest.mark.parametrize("host, warned", [("127.0.0.1", False), ("0.0.0.0", True), ("localhost", False)])
def test_mock_controller_warns_when_others_can_reach_it(capsys, host, warned):
    assert main(["mock", "controller", "--port", "0", "--host", host, "--duration", "0.1"]) == 0
    err = capsys.readouterr().err
    if warned:
        assert err.count("\n") == 1 and "not a loopback address" in err and "testing only" in err
    else:
        assert err == ""
