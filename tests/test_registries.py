"""One registry per kind of back end: everything that lists back ends reads it, and a package that
is not handeye adds one through entry points (tests/plugin: a ``.dist-info`` and a module)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from handeye.calibration.methods import METHODS
from handeye.drivers.camera import CameraError, open_camera
from handeye.drivers.camera.backends import CAMERAS, CameraBackend, register_backend
from handeye.drivers.controller import InvalidRequest, open_controller
from handeye.drivers.controller.backends import CONTROLLERS, ControllerLink
from handeye.mocks.backends import mock_protocols
from handeye.mocks.controller import start_mock_controller
from handeye.rapid.links import LINK_MODULES
from handeye.station.cli import build_parser, main
from handeye.station.config import ConfigError, config_from_dict
from handeye.station.runtime import _controller_options, open_station

PLUGIN = Path(__file__).with_name("plugin")
BUILT_IN_CONTROLLERS = ("socket", "serial", "modbus", "rws")


@pytest.fixture
def plugin(monkeypatch):
    """The test plug-in installed (its folder on sys.path); uninstalled again afterwards."""
    monkeypatch.syspath_prepend(str(PLUGIN))
    CONTROLLERS.refresh()
    CAMERAS.refresh()
    METHODS.refresh()  # its .dist-info adds a method too (tests/test_method_plugin.py)
    yield
    monkeypatch.undo()
    sys.modules.pop("handeye_test_plugin", None)
    sys.modules.pop("handeye_test_plugin_method", None)
    CONTROLLERS.refresh()
    CAMERAS.refresh()
    METHODS.refresh()


def _choices(argv_prefix, option="--protocol"):
    """The ``choices`` of an option of a sub-command, as ``handeye`` builds them now."""
    parser = build_parser()
    sub = parser
    for word in argv_prefix:
        action = next(a for a in sub._actions if a.__class__.__name__ == "_SubParsersAction")
        sub = action.choices[word]
    return next(a for a in sub._actions if option in a.option_strings).choices


# ------------------------------------------------------------------------------------ the package alone
def test_the_package_registers_its_back_ends_and_the_mocks_theirs():
    assert CONTROLLERS.names() == BUILT_IN_CONTROLLERS
    assert [CONTROLLERS[n].default_port for n in BUILT_IN_CONTROLLERS] == [1025, None, 502, 80]
    assert mock_protocols() == BUILT_IN_CONTROLLERS
    assert [CONTROLLERS[n].mock.default_port for n in BUILT_IN_CONTROLLERS] == [1025, 1026, 5020, 8080]
    assert CAMERAS.names() == ("xb3", "mock") and CAMERAS["mock"].simulated and not CAMERAS["xb3"].simulated
    assert "loopback" not in CONTROLLERS and "blank" not in CAMERAS


def test_rapid_has_a_link_module_for_every_controller_back_end():
    # rapid keeps its own table (it must not import the drivers): this is where the two meet
    assert tuple(LINK_MODULES) == CONTROLLERS.names()


def test_every_list_of_back_ends_is_the_registry():
    assert _choices(["robot", "joints"]) == CONTROLLERS.names()
    assert _choices(["robot", "status"]) == CONTROLLERS.names()
    assert _choices(["mock", "controller"]) == mock_protocols()
    assert _choices(["demo"]) == mock_protocols()
    assert _choices(["rapid", "generate"]) == tuple(LINK_MODULES)
    with pytest.raises(ConfigError, match="controller.protocol must be one of socket, serial, modbus, rws, mock; got 'x'"):
        config_from_dict({"controller": {"protocol": "x"}, "camera": {"backend": "xb3"}})
    with pytest.raises(ConfigError, match="camera.backend must be one of xb3, mock; got 'x'"):
        config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "x"}})
    with pytest.raises(ConfigError, match="mock.protocol must be one of socket, serial, modbus, rws; got 'x'"):
        config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}, "mock": {"protocol": "x"}})
    with pytest.raises(InvalidRequest, match="unknown controller protocol 'profinet'; choose one of socket, serial, modbus, rws$"):
        open_controller("profinet")


@pytest.mark.parametrize("protocol, section, options", [
    ("socket", {"host": "10.0.0.2", "port": 1030}, {"host": "10.0.0.2", "port": 1030}),
    ("serial", {"serial_url": "/dev/ttyS1"}, {"url": "/dev/ttyS1"}),
    ("modbus", {"host": "10.0.0.3", "port": 502}, {"host": "10.0.0.3", "port": 502}),
    ("modbus", {"host": "10.0.0.3", "port": 502, "modbus_map": "map.yaml"},
     {"host": "10.0.0.3", "port": 502, "register_map": "map.yaml"}),
])
def test_the_runtime_options_come_from_the_back_ends_entry(protocol, section, options):
    config = config_from_dict({"controller": {"protocol": protocol, **section}, "camera": {"backend": "xb3"}})
    got = _controller_options(config)
    assert {k: got[k] for k in options} == options
    assert not {"host", "port", "url", "register_map"} - set(options) & set(got)


def test_the_command_line_fills_the_default_port_and_needs_a_url_for_serial():
    assert CONTROLLERS["modbus"].link_options(ControllerLink(host="h")) == {"host": "h", "port": 502}
    assert CONTROLLERS["socket"].link_options(ControllerLink(host="h", port=7)) == {"host": "h", "port": 7}
    assert CONTROLLERS["serial"].link_options(ControllerLink(serial_url="loop://", baudrate=19200)) == \
        {"url": "loop://", "baudrate": 19200}
    with pytest.raises(InvalidRequest, match="the serial link needs a device or pyserial URL"):
        CONTROLLERS["serial"].link_options(ControllerLink())


def test_a_back_end_registered_in_code_appears_and_goes(monkeypatch):
    register_backend("grey", "handeye_test_plugin:BlankCamera", help="grey frames")
    try:
        assert CAMERAS.names()[-1] == "grey" and isinstance(CAMERAS["grey"], CameraBackend)
        config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "grey"}})
    finally:
        CAMERAS.unregister("grey")
    assert "grey" not in CAMERAS
    with pytest.raises(CameraError, match="unknown camera back end 'grey'; choose one of xb3, mock"):
        open_camera("grey")
    with pytest.raises(TypeError, match="registered as a ControllerBackend"):
        CONTROLLERS.register(CameraBackend("x", "m:C"))


# ------------------------------------------------------------------------------------ a plug-in package
def test_entry_points_add_a_controller_and_a_camera(plugin):
    assert CONTROLLERS.names() == BUILT_IN_CONTROLLERS + ("loopback",)
    assert CONTROLLERS["loopback"].default_port == 11025 and CONTROLLERS["loopback"].mock is None
    assert "loopback" not in mock_protocols()  # no mock serves it: not a choice of the mock station
    assert CAMERAS.names() == ("xb3", "mock", "blank") and "BlankCamera" in CAMERAS["blank"].help
    with open_camera("blank", grey=9) as camera:
        assert camera.grab().left.max() == 9


def test_the_plugin_back_ends_pass_the_station_config(plugin):
    config = config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "blank"}})
    assert (config.controller.protocol, config.camera.backend) == ("loopback", "blank") and not config.is_mock
    with pytest.raises(ConfigError, match="controller.protocol must be one of socket, serial, modbus, rws, loopback, mock"):
        config_from_dict({"controller": {"protocol": "x"}, "camera": {"backend": "blank"}})


def test_the_plugin_controller_is_a_choice_of_robot_joints(plugin, capsys, no_leaked_threads):
    assert "loopback" in _choices(["robot", "joints"])
    with start_mock_controller("socket", time_scale=0.002) as server:
        argv = ["robot", "joints", "--protocol", "loopback", "--host", "127.0.0.1", "--port", str(server.port), "--json"]
        assert main(argv) == 0
        state = json.loads(capsys.readouterr().out)
        assert np.allclose(state["joints_deg"], server.robot.current_joints, atol=1e-3)


def test_a_station_on_plugin_back_ends_opens_them(plugin, no_leaked_threads):
    with start_mock_controller("socket", time_scale=0.002) as server:
        config = config_from_dict({"controller": {"protocol": "loopback", "host": "127.0.0.1", "port": server.port},
                                   "camera": {"backend": "blank"}})
        with open_station(config) as link:
            assert type(link.controller).__name__ == "LoopbackController" and link.controller.protocol == "loopback"
            assert type(link.camera).__name__ == "BlankCamera" and link.camera.is_connected
            assert link.controller.info().postures == len(server.robot.postures)


def test_without_the_plugin_its_names_are_refused(capsys):
    assert "loopback" not in _choices(["robot", "joints"])
    with pytest.raises(SystemExit) as info:
        main(["robot", "joints", "--protocol", "loopback"])
    assert info.value.code == 2 and "invalid choice: 'loopback'" in capsys.readouterr().err
    with pytest.raises(ConfigError, match="controller.protocol must be one of socket, serial, modbus, rws, mock; got 'loopback'"):
        config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "xb3"}})


def test_a_broken_entry_point_is_skipped_with_a_warning(plugin, monkeypatch, caplog):
    import handeye_test_plugin

    monkeypatch.delattr(handeye_test_plugin, "CONTROLLER")
    CONTROLLERS.refresh()
    assert CONTROLLERS.names() == BUILT_IN_CONTROLLERS
    assert "controller protocol 'loopback' from entry point handeye_test_plugin:CONTROLLER is unusable" in caplog.text
