"""Plug-ins that hang: an import that never returns, a solver that sleeps, a protocol that lacks what a
command needs. A package written in this test (a ``.dist-info`` and modules in a temporary folder, on
``sys.path``) registers them through entry points only. A command that does not need a plug-in never
imports it; one that needs it waits at most the time bound (``HANDEYE_PLUGIN_TIME_S``, short here),
names it in one line and goes on.

Every hang waits on a gate the fixture opens afterwards (and at most a few seconds), so no thread
outlives the test for long.
"""

from __future__ import annotations

import json
import sys
import textwrap
import threading

import pytest
from handeye.calibration.methods import METHODS
from handeye.drivers.camera.backends import CAMERAS
from handeye.drivers.controller.backends import CONTROLLERS
from handeye.station.cli import main

from helpers import plugin_installed

PACKAGE = "handeye-hanging-plugin"
GATE, SOLVERS, STUCK_CAMERA, STUCK_LINK = ("handeye_hang_gate", "handeye_hang_solvers", "handeye_hang_camera",
                                          "handeye_hang_link")
#: The bound the commands run with here, s.
BOUND_S = 0.3

MODULES = {
    GATE: "import threading\nOPEN = threading.Event()\n",
    SOLVERS: '''
from handeye.calibration.methods import Method
from handeye.drivers.controller.backends import ControllerBackend
from handeye_hang_gate import OPEN


def sleepy(hand, target2cam, pairs=None):
    OPEN.wait(5)
    raise RuntimeError("woke up too late")


SLEEPY = Method("sleepy", "classic", "Nobody (2026)", "sleeps", f"{__name__}:sleepy", in_comparison=True)
BARE = ControllerBackend("bare", "handeye_test_plugin:LoopbackController", default_port=11997,
                         help="a link without a mock or a RAPID module")
''',
    STUCK_CAMERA: '''
from handeye_hang_gate import OPEN

OPEN.wait(5)  # an import waiting for hardware that is not there
from handeye.drivers.camera.backends import CameraBackend

BACKEND = CameraBackend("stuck", "handeye_test_plugin:BlankCamera", help="never loads")
''',
    STUCK_LINK: '''
from handeye_hang_gate import OPEN

OPEN.wait(5)
from handeye.drivers.controller.backends import ControllerBackend

BACKEND = ControllerBackend("frozen", "handeye_test_plugin:LoopbackController", default_port=11996)
''',
}

ENTRY_POINTS = f"""
[handeye.methods]
sleepy = {SOLVERS}:SLEEPY

[handeye.controllers]
bare = {SOLVERS}:BARE
frozen = {STUCK_LINK}:BACKEND

[handeye.cameras]
stuck = {STUCK_CAMERA}:BACKEND
"""


@pytest.fixture
def hanging(tmp_path, monkeypatch):
    """The hanging package installed, the time bound short; the gate opened afterwards."""
    folder = tmp_path / "site"
    info = folder / "handeye_hanging_plugin-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {PACKAGE}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(textwrap.dedent(ENTRY_POINTS))
    for module, source in MODULES.items():
        (folder / f"{module}.py").write_text(source)
    monkeypatch.setenv("HANDEYE_PLUGIN_TIME_S", str(BOUND_S))
    with plugin_installed(monkeypatch, folder, tuple(MODULES)):
        import handeye_hang_gate

        try:
            yield folder
        finally:
            handeye_hang_gate.OPEN.set()
            for thread in threading.enumerate():  # the abandoned loads and solves end now
                if thread.name.startswith("handeye-plugin-"):
                    thread.join(2)


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A simulated session (truth.yaml beside it): 8 postures."""
    path = tmp_path_factory.mktemp("hanging") / "sim"
    assert main(["simulate", "-o", str(path), "--postures", "8", "--sigma-cam", "0.3", "--seed", "4"]) == 0
    return path


def test_a_plan_on_a_station_without_the_hanging_camera_never_imports_it(hanging, tmp_path, capsys):
    assert main(["capture", "--mock", "--plan-only", "--postures", "6", "--session", str(tmp_path / "s")]) == 0
    assert STUCK_CAMERA not in sys.modules and STUCK_LINK not in sys.modules
    assert CAMERAS.unusable() == {} and CONTROLLERS.unusable() == {}  # not even tried
    assert "stuck" in CAMERAS.names() and "frozen" in CONTROLLERS.names()  # listed from the metadata


def test_calibrating_with_one_method_never_imports_the_plugins(hanging, simulated, capsys):
    assert main(["calibrate", str(simulated), "--method", "tsai", "--quiet"]) == 0
    assert SOLVERS not in sys.modules and STUCK_CAMERA not in sys.modules


def test_a_sleeping_solver_is_not_compared_and_the_report_is_whole(hanging, simulated, tmp_path, capsys):
    out, report = tmp_path / "r.json", tmp_path / "r.html"
    assert main(["calibrate", str(simulated), "--report", str(report), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    line = [line for line in text.splitlines() if "not compared: method sleepy" in line]
    assert len(line) == 1 and f"from the installed package {PACKAGE}" in line[0], text
    assert f"took longer than {BOUND_S:g} s" in line[0], line
    data = json.loads(out.read_text())
    assert "took longer than" in data["method_comparison_failed"]["sleepy"]
    assert "sleepy" not in {row["method"] for row in data["method_comparison"]} and len(data["method_comparison"]) > 3
    assert report.is_file() and STUCK_CAMERA not in sys.modules


def test_a_hanging_camera_a_station_uses_is_named_in_one_line(hanging, tmp_path, capsys):
    config = tmp_path / "station.yaml"
    config.write_text("controller:\n  protocol: socket\ncamera:\n  backend: stuck\n")
    assert main(["capture", "--config", str(config), "--plan-only", "--session", str(tmp_path / "s")]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "stuck" in err and f"did not load within {BOUND_S:g} s" in err, err
    assert METHODS.unusable() == {}


# ------------------------------------------------------------------ a plug-in that cannot serve a command (issue 40.5)
def _one_error_line(capsys, command: str) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"handeye {command}: error: ") and "Traceback" not in err, err
    return lines[0]


def test_a_protocol_without_a_mock_is_refused_by_the_demo_saying_what_it_lacks(hanging, capsys):
    with pytest.raises(SystemExit) as info:
        main(["demo", "--protocol", "bare", "--no-report"])
    line = _one_error_line(capsys, "demo")
    assert info.value.code == 2 and "invalid choice: 'bare' (choose from socket, serial, modbus, rws): " in line, line
    assert f"'bare' of the installed package {PACKAGE} (entry point {SOLVERS}:BARE) has no mock" in line, line
    with pytest.raises(SystemExit):
        main(["demo", "--help"])
    help_text = capsys.readouterr().out
    assert "Installed plug-ins left out of --protocol:" in help_text
    assert "'bare' of the installed package" in help_text and "'frozen' of the installed package" in help_text
    assert f"did not load within {BOUND_S:g} s" in help_text


def test_a_protocol_without_a_rapid_module_is_refused_by_rapid_generate_saying_so(hanging, tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["rapid", "generate", "--protocol", "bare", "-o", str(tmp_path / "out")])
    line = _one_error_line(capsys, "rapid generate")
    assert info.value.code == 2 and "'bare' of the installed package" in line and "has no RAPID link module" in line
    assert not (tmp_path / "out").exists()


def test_a_station_whose_mock_protocol_has_no_mock_is_told_why(hanging):
    from handeye.base.errors import ConfigError
    from handeye.station.config.station import config_from_dict

    with pytest.raises(ConfigError, match="mock.protocol must be one of .*; got 'bare': the controller protocol 'bare' of "
                                          f"the installed package {PACKAGE} .* has no mock"):
        config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}, "mock": {"protocol": "bare"}})


def test_handeye_plugins_lists_every_plugin_with_what_it_can_do(hanging, tmp_path, capsys):
    out = tmp_path / "plugins.json"
    assert main(["plugins", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    for title in ("methods (entry-point group handeye.methods): 1 installed",
                  "controller protocols (entry-point group handeye.controllers): 2 installed",
                  "camera back ends (entry-point group handeye.cameras): 1 installed"):
        assert title in text, text
    assert "  sleepy: the installed package handeye-hanging-plugin" in text
    assert "the report's method comparison (calibrate --report, demo): yes" in text
    assert "demo --protocol, mock controller, mock.protocol: no, it has no mock" in text
    assert "rapid generate: no, it has no RAPID link module" in text
    assert text.count(f"did not load within {BOUND_S:g} s: fix or uninstall that package") == 2  # frozen, stuck
    data = json.loads(out.read_text())
    assert set(data) == {"methods", "controllers", "cameras"}
    bare = next(row for row in data["controllers"] if row["name"] == "bare")
    assert bare["serves"]["rapid generate"] is False and "RAPID link" in bare["lacks"]["rapid generate"]
    assert [row["unusable"] for row in data["cameras"]] == [f"did not load within {BOUND_S:g} s"]


def test_handeye_plugins_without_any_says_none(capsys):
    assert main(["plugins"]) == 0
    text = capsys.readouterr().out
    assert "methods (entry-point group handeye.methods): none installed" in text
    assert "camera back ends (entry-point group handeye.cameras): none installed" in text


# ------------------------------------------------------------------ robot, mock controller, --method (issue 42 c)
def _closed_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _no_plugin_imported() -> None:
    assert SOLVERS not in sys.modules and STUCK_LINK not in sys.modules and STUCK_CAMERA not in sys.modules
    assert CONTROLLERS.unusable() == {} and METHODS.unusable() == {}  # not even tried


def test_robot_with_a_builtin_protocol_never_imports_the_plugins(hanging, capsys):
    code = main(["robot", "joints", "--protocol", "socket", "--port", str(_closed_port()), "--timeout", "0.5",
                 "--idle-timeout", "0.5"])
    assert code == 1 and "Traceback" not in capsys.readouterr().err  # nothing listens there
    _no_plugin_imported()


def test_mock_controller_with_a_builtin_protocol_never_imports_the_plugins(hanging, capsys):
    assert main(["mock", "controller", "--protocol", "socket", "--port", "0", "--duration", "0.2"]) == 0
    _no_plugin_imported()


def test_robot_with_a_hanging_protocol_names_it_in_one_line(hanging, capsys):
    with pytest.raises(SystemExit) as info:
        main(["robot", "joints", "--protocol", "frozen", "--port", str(_closed_port())])
    line = _one_error_line(capsys, "robot joints")
    assert info.value.code == 2 and "'frozen' of the installed package" in line, line
    assert f"did not load within {BOUND_S:g} s" in line, line
    assert SOLVERS not in sys.modules  # the other plug-in is not imported for it


def test_mock_controller_with_a_hanging_protocol_names_it_in_one_line(hanging, capsys):
    with pytest.raises(SystemExit) as info:
        main(["mock", "controller", "--protocol", "frozen", "--port", "0", "--duration", "0.2"])
    line = _one_error_line(capsys, "mock controller")
    assert info.value.code == 2 and f"'frozen' of the installed package {PACKAGE}" in line, line
    assert f"did not load within {BOUND_S:g} s" in line, line


@pytest.mark.parametrize("argv", [["robot", "joints", "--help"], ["mock", "controller", "--help"]])
def test_the_help_lists_the_plugins_and_names_the_hanging_one(hanging, capsys, argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert f"'frozen' of the installed package {PACKAGE}" in text and f"did not load within {BOUND_S:g} s" in text, text


def test_a_users_own_plugin_method_that_hangs_is_named_in_one_line(hanging, simulated, capsys):
    assert main(["calibrate", str(simulated), "--method", "sleepy", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "sleepy" in err and f"from the installed package {PACKAGE}" in err, err
    assert f"took longer than {BOUND_S:g} s" in err, err
