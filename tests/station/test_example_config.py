"""The back ends' documentation written from their declarations: the example station file's controller
part (station/config/example.py) and the help lines (station/backend_help.py)."""

from __future__ import annotations

from dataclasses import replace

import pytest
import yaml

from handeye.drivers.controller.backends import CONTROLLERS, ControllerBackend, ControllerLink, LinkSetting, link_settings
from handeye.station.config import example as example_config
from handeye.station.cli import build_parser
from handeye.station.config.station import EXAMPLE_FILE
from handeye.station.config.example import BEGIN, END, REGENERATE, controller_lines, example_problem, render_example

from test_registries import plugin  # noqa: F401 (the fixture)


def _help(capsys, *argv) -> str:
    with pytest.raises(SystemExit):
        build_parser().parse_args([*argv, "--help"])
    return capsys.readouterr().out


def test_the_shipped_example_is_what_the_back_ends_declare():
    text = EXAMPLE_FILE.read_text()
    assert example_problem() is None, f"station/config/example_station.yaml is out of date: run {REGENERATE}"
    assert render_example(text) == text
    part = text[text.index(BEGIN):text.index(END)]
    words = " ".join(word for word in part.split() if word != "#")  # the comments, unwrapped
    section = yaml.safe_load(text)["controller"]
    for name in CONTROLLERS.names_in_code():
        assert f"{name}: {CONTROLLERS[name].help}" in words
    for key, (setting, _) in link_settings().items():
        assert section[key] == setting.default and setting.help in words and setting.note in words


def test_a_new_setting_or_back_end_not_in_the_file_fails_with_the_command(monkeypatch, tmp_path):
    extra = LinkSetting("parity", str, "none", "parity bit of the serial line")
    monkeypatch.setitem(CONTROLLERS, "serial", replace(CONTROLLERS["serial"], link_settings=CONTROLLERS["serial"].link_settings + (extra,)))
    problem = example_problem()
    assert problem is not None and REGENERATE in problem
    assert any(line.startswith("  parity: none ") and "parity bit" in line for line in controller_lines())
    CONTROLLERS.register(ControllerBackend("profinet", "m:C", default_port=34964, help="a PROFINET device"))
    try:
        assert "  # profinet: a PROFINET device; no RAPID module; default port 34964; no settings of its own" in \
            controller_lines()
        copy = tmp_path / "station.yaml"
        copy.write_text(render_example(EXAMPLE_FILE.read_text()))  # regenerated: the file documents both
        assert example_problem(copy) is None and yaml.safe_load(copy.read_text())["controller"]["parity"] == "none"
    finally:
        CONTROLLERS.unregister("profinet")


def test_the_regenerating_command_writes_the_file(monkeypatch, tmp_path, capsys):
    copy = tmp_path / "example_station.yaml"
    text = EXAMPLE_FILE.read_text()
    copy.write_text(text.replace("  baudrate: null", "  baudrate: 4800"))
    monkeypatch.setattr("handeye.station.config.station.EXAMPLE_FILE", copy)
    assert example_config.main(["--check"]) == 1 and REGENERATE in capsys.readouterr().err
    assert example_config.main([]) == 0 and copy.read_text() == text
    assert example_config.main(["--check"]) == 0
    copy.write_text("controller:\n  protocol: socket\n")
    with pytest.raises(ValueError, match="no generated part"):
        example_config.main([])


def test_the_help_lines_are_the_registry(capsys):
    robot = _help(capsys, "robot", "joints")
    for name in CONTROLLERS:
        backend = CONTROLLERS[name]
        assert f"--protocol {name:<8} {backend.help}" in robot and backend.usage() in robot
    assert "--host H [--port P, default 1025]" in robot and "--url DEVICE_OR_URL [--baudrate B]" in robot
    generate = _help(capsys, "rapid", "generate")
    for module, name in (("HeSocket", "socket"), ("HeSerial", "serial"), ("HeIo", "modbus"), ("HeRws", "rws")):
        assert f"  {module}.mod " in generate and f"(protocol {name})" in " ".join(generate.split())


def test_a_plugin_protocol_shows_up_in_the_help_as_a_built_in_does(plugin, capsys):  # noqa: F811
    robot = " ".join(_help(capsys, "robot", "status").split())
    assert ("--protocol loopback the test plug-in's TCP link; RAPID module HeLoop "
            "--host H [--port P, default 11025] [--loop-label TEXT]") in robot
    mock = " ".join(_help(capsys, "mock", "controller").split())
    assert "loopback HeLoop executed: the line protocol over TCP, port 11026" in mock and "--loop-note" in mock
    generate = " ".join(_help(capsys, "rapid", "generate").split())
    assert "HeLoop.mod the test plug-in's TCP link (protocol loopback)" in generate
    assert all(f"  # {name}:" not in "\n".join(controller_lines()) for name in ("loopback",))  # the shipped file: the package's


def test_a_misspelt_link_setting_is_refused_not_read_as_unset():
    link = ControllerLink(host="h", serial_url="loop://")
    assert link.serial_url == "loop://" and link.baudrate is None and link.get("baudrate", 9600) == 9600
    with pytest.raises(AttributeError, match="no controller link setting 'serial_ulr'; the registered back ends "
                                             "declare: host, port, serial_url, baudrate, modbus_map"):
        link.serial_ulr
    with pytest.raises(KeyError, match="no controller link setting 'baud'"):
        link.get("baud")
    with pytest.raises(TypeError, match="no controller link setting 'hots'"):
        ControllerLink(hots="h")
    assert not hasattr(link, "serial_ulr") and getattr(link, "modbus_map", "x") is None
