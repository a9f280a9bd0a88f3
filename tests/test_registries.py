"""One registry per kind of back end: everything that lists back ends reads it, and a package that
is not handeye adds one through entry points (tests/plugin: a ``.dist-info`` and a module)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from handeye.drivers.camera import CameraError, open_camera
from handeye.drivers.camera.backends import CAMERAS, CameraBackend, register_backend
from handeye.drivers.controller import InvalidRequest, open_controller
from handeye.drivers.controller.backends import (
    CONTROLLERS,
    RAPID_LINKS,
    ControllerBackend,
    ControllerLink,
    link_settings,
)
from handeye.mocks.backends import mock_protocols
from handeye.mocks.controller import start_mock_controller
from handeye.rapid.links import BUILT_IN_LINKS
from handeye.station.cli import build_parser, main
from handeye.station.config.station import ConfigError, config_from_dict, describe_keys
from handeye.station.runtime import _camera_options, _controller_options, open_station

from helpers import plugin_installed

PLUGIN = Path(__file__).with_name("plugin")
BUILT_IN_CONTROLLERS = ("socket", "serial", "modbus", "rws")


@pytest.fixture
def plugin(monkeypatch):
    """The test plug-in installed (its folder on sys.path); uninstalled again afterwards."""
    with plugin_installed(monkeypatch, PLUGIN, ("handeye_test_plugin", "handeye_test_plugin_method")):
        yield


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


def test_every_controller_back_end_carries_its_rapid_link_module():
    # the back end's entry names its RAPID module; rapid, standing alone, knows the package's own
    assert tuple(RAPID_LINKS) == CONTROLLERS.names()
    assert all(RAPID_LINKS[name] is BUILT_IN_LINKS[name] for name in BUILT_IN_CONTROLLERS)


def test_every_list_of_back_ends_is_the_registry():
    assert tuple(_choices(["robot", "joints"])) == CONTROLLERS.names()
    assert tuple(_choices(["robot", "status"])) == CONTROLLERS.names()
    assert tuple(_choices(["mock", "controller"])) == mock_protocols()
    assert tuple(_choices(["demo"])) == mock_protocols()
    assert tuple(_choices(["rapid", "generate"])) == CONTROLLERS.names()
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
    assert CONTROLLERS["loopback"].default_port == 11025 and CONTROLLERS["loopback"].mock.default_port == 11026
    assert mock_protocols()[-1] == "loopback" and RAPID_LINKS["loopback"].module == "HeLoop"
    assert CAMERAS.names() == ("xb3", "mock", "blank", "tinted") and "BlankCamera" in CAMERAS["blank"].help
    with open_camera("blank", grey=9) as camera:
        assert camera.grab().left.max() == 9


def test_the_plugin_back_ends_pass_the_station_config(plugin):
    config = config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "blank"}})
    assert (config.controller.protocol, config.camera.backend) == ("loopback", "blank") and not config.is_mock
    with pytest.raises(ConfigError, match="controller.protocol must be one of socket, serial, modbus, rws, loopback, mock"):
        config_from_dict({"controller": {"protocol": "x"}, "camera": {"backend": "blank"}})


def test_a_plugin_cameras_own_setting_is_a_station_config_key(plugin):
    config = config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "tinted", "tint": 40}})
    assert config.camera.tint == 40 and config.to_dict()["camera"]["tint"] == 40
    assert _camera_options(config) == {"grey": 40}  # what open_station opens the camera with
    with open_camera("tinted", **_camera_options(config)) as camera:
        assert camera.grab().left.max() == 40
    with pytest.raises(ConfigError, match="camera.tint must be"):
        config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "tinted", "tint": 300}})
    untinted = config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "tinted"}})
    with pytest.raises(CameraError, match=r"the tinted camera needs a grey level 0..255 \(camera.tint in the station "
                                          r"config\)"):
        _camera_options(untinted)


def test_a_camera_key_no_back_end_declares_is_refused():
    with pytest.raises(ConfigError, match="unknown key camera.tint; known keys of camera: backend, grab_timeout_s, "
                                          "guid, mock_arm"):
        config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "xb3", "tint": 40}})


@pytest.mark.parametrize("given, kept", [("00B09D0100AABBCC", "00b09d0100aabbcc"), ("0x2222", "0000000000002222")])
def test_the_xb3_is_chosen_by_the_guid_of_the_station_config(given, kept):
    config = config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "xb3", "guid": given}})
    assert config.camera.guid == kept and _camera_options(config) == {"guid": kept}
    for wrong, says in (("zz", "must be the camera.s FireWire GUID, up to 16 hex digits"), (2222, "must be a text")):
        with pytest.raises(ConfigError, match=f"camera.guid {says}"):
            config_from_dict({"controller": {"protocol": "socket"}, "camera": {"backend": "xb3", "guid": wrong}})


def test_the_plugin_controller_is_a_choice_of_robot_joints(plugin, capsys, no_leaked_threads):
    assert "loopback" in _choices(["robot", "joints"])
    with start_mock_controller("socket", time_scale=0.002) as server:
        argv = ["robot", "joints", "--protocol", "loopback", "--host", "127.0.0.1", "--port", str(server.port), "--json"]
        assert main(argv) == 0
        state = json.loads(capsys.readouterr().out)
        assert np.allclose(state["joints_deg"], server.robot.current_joints, atol=1e-3)


def test_a_station_on_plugin_back_ends_opens_them(plugin, no_leaked_threads):
    with start_mock_controller("socket", time_scale=0.002) as server:
        config = config_from_dict({"controller": {"protocol": "loopback", "host": "127.0.0.1", "port": server.port,
                                                  "loop_label": "cell 4"},
                                   "camera": {"backend": "blank"}})
        with open_station(config) as link:
            assert type(link.controller).__name__ == "LoopbackController" and link.controller.protocol == "loopback"
            assert link.controller.label == "cell 4"  # the plug-in's own setting, from the station file
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
    assert CONTROLLERS.names() == BUILT_IN_CONTROLLERS + ("loopback",)  # listed from the metadata, not loaded
    assert "loopback" not in CONTROLLERS  # asked for: it does not load
    assert "controller protocol 'loopback' from entry point handeye_test_plugin:CONTROLLER is unusable" in caplog.text
    assert CONTROLLERS.names() == BUILT_IN_CONTROLLERS and "loopback" in CONTROLLERS.unusable()
    with pytest.raises(ConfigError, match="got 'loopback': the controller protocol 'loopback' of the installed package "
                                          "handeye-test-plugin .* failed to load \\(AttributeError: "):
        config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "xb3"}})


def test_the_plugin_protocol_gets_its_own_rapid_module(plugin, tmp_path, capsys):
    config = tmp_path / "station.yaml"
    config.write_text("controller:\n  protocol: loopback\n  write_key: plugin-key-1\ncamera:\n  backend: xb3\n")
    assert "loopback" in _choices(["rapid", "generate"])
    assert main(["rapid", "generate", "--config", str(config), "-o", str(tmp_path / "out")]) == 0
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == ["HeKey.sys", "HeLoop.mod", "HeMain.mod", "HeTool.mod"]
    text = (tmp_path / "out" / "HeLoop.mod").read_text()
    assert text.startswith("MODULE HeLoop\n  ! the test plug-in's link") and "$" not in text
    assert "plugin-key-1" not in text and "HeKeyMatches" in text  # keyed like the built-in line links
    assert "HeLoop.mod" in capsys.readouterr().out


def test_the_demo_runs_on_the_plugin_protocol(plugin, tmp_path, capsys, no_leaked_threads):
    """The plug-in's own mock runs the plug-in's own RAPID module, which the capture generated."""
    assert "loopback" in _choices(["demo"]) and "loopback" in _choices(["mock", "controller"])
    out = tmp_path / "demo.json"
    code = main(["demo", "--session", str(tmp_path / "demo"), "--json", str(out), "--protocol", "loopback",
                 "--postures", "12", "--no-report"])
    result = json.loads(out.read_text())
    assert code == 0 and result["protocol"] == "loopback" and result["readback_ok"] is True
    assert result["errors"]["rotation_error_deg"] <= 0.05 and result["errors"]["translation_error_mm"] <= 0.5
    assert sorted(p.name for p in (tmp_path / "demo" / "session" / "rapid").iterdir()) == \
        ["HeLoop.mod", "HeMain.mod", "HeTool.mod"]


def test_a_protocol_without_a_rapid_module_is_refused_by_rapid_generate(tmp_path, capsys):
    CONTROLLERS.register(ControllerBackend("bare", "handeye_test_plugin:LoopbackController", default_port=1))
    try:
        assert "bare" in CONTROLLERS and "bare" not in RAPID_LINKS and "bare" not in _choices(["rapid", "generate"])
        config = tmp_path / "station.yaml"
        config.write_text("controller:\n  protocol: bare\ncamera:\n  backend: xb3\n")
        assert main(["rapid", "generate", "--config", str(config), "-o", str(tmp_path / "out")]) == 1
        err = capsys.readouterr().err
        assert "controller.protocol must be one of socket, serial, modbus, rws (a protocol with a RAPID link module)" \
               f"; got 'bare'" in err and len(err.strip().splitlines()) == 1
    finally:
        CONTROLLERS.unregister("bare")
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------------------------ settings described once
def test_a_station_file_sets_every_link_setting_a_back_end_declares():
    config = config_from_dict({"controller": {"protocol": "serial", "serial_url": "/dev/ttyS1", "baudrate": 19200},
                               "camera": {"backend": "xb3"}})
    assert {k: _controller_options(config)[k] for k in ("url", "baudrate")} == {"url": "/dev/ttyS1", "baudrate": 19200}
    with pytest.raises(ConfigError, match="controller.baudrate must be a whole number; got 'fast'"):
        config_from_dict({"controller": {"protocol": "serial", "baudrate": "fast"}, "camera": {"backend": "xb3"}})
    with pytest.raises(ConfigError, match="controller.tls_fingerprint must be the SHA-256"):
        config_from_dict({"controller": {"protocol": "rws", "tls_fingerprint": "ab"}, "camera": {"backend": "xb3"}})
    declared = [(s.key, names) for s, names in (link_settings()[k] for k in link_settings())]
    assert [k for k, _ in declared] == ["serial_url", "baudrate", "modbus_map", "username", "password", "tls_fingerprint"]
    documented = {line.split(":")[0] for line in describe_keys()}
    assert {f"controller.{key}" for key, _ in declared} <= documented


def test_the_plugin_link_setting_is_a_config_key_a_flag_and_a_keyword(plugin, capsys, no_leaked_threads):
    assert "controller.loop_label: loopback: a label the link keeps" in describe_keys()
    config = config_from_dict({"controller": {"protocol": "loopback", "loop_label": "A"}, "camera": {"backend": "xb3"}})
    assert config.controller.loop_label == "A" and _controller_options(config)["label"] == "A"
    assert config_from_dict({"controller": {"protocol": "loopback"}, "camera": {"backend": "xb3"}}).controller.loop_label \
        == "plain"
    with pytest.raises(ConfigError, match="controller.loop_label must be a text"):
        config_from_dict({"controller": {"protocol": "loopback", "loop_label": 3}, "camera": {"backend": "xb3"}})
    assert CONTROLLERS["loopback"].link_options(ControllerLink(loop_label="B"))["label"] == "B"
    parser = build_parser()
    args = parser.parse_args(["robot", "status", "--protocol", "loopback", "--loop-label", "C"])
    from handeye.station.commands.robot import _options

    assert args.link_loop_label == "C" and _options(args)["label"] == "C"


def test_without_the_plugin_its_setting_is_unknown():
    with pytest.raises(ConfigError, match="unknown key controller.loop_label"):
        config_from_dict({"controller": {"protocol": "socket", "loop_label": "A"}, "camera": {"backend": "xb3"}})


def test_the_plugin_mock_option_is_a_flag_of_mock_controller(plugin, no_leaked_threads):
    from handeye.mocks.backends import mock_settings
    from handeye.mocks.controller.service import MockControllerOptions, run_mock_controller

    assert mock_settings()["note"][1] == ("loopback",) and mock_settings()["generation"][1] == ("rws",)
    args = build_parser().parse_args(["mock", "controller", "--protocol", "loopback", "--loop-note", "hello"])
    assert args.server_note == "hello"
    with start_mock_controller("loopback", time_scale=0.002, note="kept", generation=2) as server:
        assert server.note == "kept" and server.protocol == "loopback"  # generation: not the loopback mock's
    lines = []
    options = MockControllerOptions(protocol="loopback", port=0, server_options={"note": "x"}, duration_s=0.2,
                                    time_scale=0.002)
    assert run_mock_controller(options, announce=lines.append, warn=lines.append) == 0
    assert lines[0].startswith("mock loopback controller (simulated IRB 1400 running the RAPID generated for loopback")
    assert "try: handeye robot joints --protocol loopback --host 127.0.0.1 --port " in lines[0]


def test_the_contract_tests_run_on_the_plugin_protocol():
    # installed, the plug-in's protocol is a parameter of the contract tests like a built-in one
    import os
    import re
    import subprocess

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(PLUGIN), os.environ.get("PYTHONPATH")]))}
    contract = Path(__file__).parent / "drivers" / "controller" / "test_contract.py"
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(contract), "-k", "loopback"],
                          env=env, capture_output=True, text=True, timeout=900)
    summary = done.stdout.strip().splitlines()[-1]
    assert done.returncode == 0 and re.match(r"\d+ passed, \d+ deselected", summary), done.stdout[-2000:]
    assert int(summary.split()[0]) >= 10


def test_a_command_line_naming_a_plugin_protocol_has_its_own_flags(plugin, no_leaked_threads):
    # issue 42 (c): robot and mock controller load only the plug-in --protocol names, and then offer its flags
    from handeye.station.cli import build_parser as build

    words = ["robot", "joints", "--protocol", "loopback", "--loop-label", "cell 4"]
    assert build(only="robot", words=words).parse_args(words).link_loop_label == "cell 4"
    words = ["mock", "controller", "--protocol=loopback", "--loop-note", "hello"]
    assert build(only="mock", words=words).parse_args(words).server_note == "hello"
    CONTROLLERS.refresh()
    with pytest.raises(SystemExit):  # a built-in protocol: the plug-in is not loaded, so neither is its flag
        build(only="robot", words=["robot", "joints"]).parse_args(["robot", "joints", "--loop-label", "x"])
    assert "loopback" not in CONTROLLERS.loaded_names()
