"""The mock controllers EXECUTE the generated RAPID: a broken template fails the contract tests, a
module the interpreter cannot run is refused with its name and line, world zones are supervised."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from handeye.drivers.controller import open_controller
from handeye.drivers.controller.modbus_map import load_register_map
from handeye.drivers.errors import StationError
from handeye.mocks.controller import ControllerProgram, generated_program, start_mock_controller
from handeye.mocks.controller.modbus_server import GatewayIo
from handeye.rapid.errors import RapidError
from handeye.rapid.generate import IO_SIGNALS, render_key, render_program
from handeye.rapid.interpreter import ModuleSource, load_program
from handeye.rapid.station import default_station
from handeye.station.cli import main

from test_contract import test_goto_posture_reaches_the_approved_joints as contract_goto

KEY = "interp-key_0042"


@pytest.mark.parametrize("keyed", [False, True], ids=["no key", "key"])
@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus"])
def test_every_generated_program_loads_in_the_interpreter(protocol, keyed):
    """A template using a construct or built-in the interpreter lacks fails here, naming it and the line."""
    station = default_station().with_(write_key=KEY if keyed else None)
    modules = render_program(station, protocol=protocol) + ([render_key(station)] if keyed else [])
    signals = GatewayIo(load_register_map(None), [], None).signals() if protocol == "modbus" else None
    program = load_program([(m.text, m.filename) for m in modules], signals=signals)
    assert program.main is not None
    if protocol == "modbus":
        assert set(IO_SIGNALS) <= set(signals)  # the gateway maps every signal HeIo uses


def _broken(protocol: str, old: str, new: str) -> ControllerProgram:
    good = generated_program(protocol, ack_timeout_s=None, write_key=KEY)
    modules, changed = [], 0
    for m in good.modules:
        changed += m.text.count(old)
        modules.append(ModuleSource(m.text.replace(old, new), m.source))
    assert changed, f"the template no longer holds {old!r}: update this test"
    return ControllerProgram(tuple(modules), "a deliberately broken template", protocol, good.tool_name)


BROKEN = {
    # the JOINTS reply with no decimals instead of 4 for axis 2: values the PC accepts, but wrong
    "joints decimals": ("socket", "NumToStr(jt.robax.rax_2, 4)", "NumToStr(jt.robax.rax_2, 0)"),
    # a reply separator changed: the PC cannot read the reply
    "reply format": ("serial", 'NumToStr(jt.robax.rax_3, 4) + " "', 'NumToStr(jt.robax.rax_3, 4) + ","'),
    # HeIo publishing the wrong joint on a register
    "io register": ("modbus", "SetAO aoHeJ4, jt.robax.rax_4;", "SetAO aoHeJ4, jt.robax.rax_5;"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_a_broken_template_fails_the_contract_test(case):
    protocol, old, new = BROKEN[case]
    with start_mock_controller(protocol, time_scale=0.002, write_key=KEY, program=_broken(protocol, old, new)) as server:
        with open_controller(protocol, **{**server.client_options(), "timeout": 1.0, "retries": 0}) as c:
            with pytest.raises((AssertionError, StationError)):
                contract_goto(c, server, 10)
    with start_mock_controller(protocol, time_scale=0.002, write_key=KEY) as server:  # the template as shipped passes
        with open_controller(protocol, **{**server.client_options(), "timeout": 1.0}) as c:
            contract_goto(c, server, 10)


def test_a_program_the_interpreter_cannot_run_is_refused_at_start_with_module_and_line():
    good = generated_program("socket")
    modules = tuple(ModuleSource(m.text.replace("    HeLinkOpen;\n", "    HeLinkOpen;\n    MoveC p, p, v100, z10, tool0;\n"),
                                 m.source) for m in good.modules)
    with pytest.raises(RapidError, match=r"HeMain.mod:\d+: unknown instruction MoveC"):
        start_mock_controller("socket", program=ControllerProgram(modules, "broken", "socket"))


def test_mock_controller_cli_runs_a_folder_of_generated_modules(tmp_path):
    """handeye mock controller --program DIR with the generated modules: handeye robot joints works against it."""
    assert main(["rapid", "generate", "-o", str(tmp_path / "prog")]) == 0
    proc = subprocess.Popen([sys.executable, "-m", "handeye.station", "mock", "controller", "--program",
                             str(tmp_path / "prog"), "--port", "0", "--duration", "60"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        banner = proc.stdout.readline()
        assert f"running RAPID from {tmp_path / 'prog'}" in banner, banner + proc.stderr.read()
        port = int(re.search(r"listening on 127\.0\.0\.1:(\d+)", banner).group(1))
        with open_controller("socket", host="127.0.0.1", port=port, timeout=2) as c:
            info = c.info()
            assert info.program == "RAPID" and info.postures == 12
            assert np.allclose(c.read_joints(), 0.0)
    finally:
        proc.terminate()
        proc.communicate(timeout=30)


def test_mock_controller_cli_refuses_a_broken_module_naming_it(tmp_path, capsys):
    assert main(["rapid", "generate", "-o", str(tmp_path / "prog")]) == 0
    capsys.readouterr()
    link = tmp_path / "prog" / "HeSocket.mod"
    link.write_text(link.read_text().replace('heReply := id + " OK";', 'heReply := id + " OK"', 1))  # a lost ';'
    assert main(["mock", "controller", "--program", str(tmp_path / "prog"), "--port", "0", "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and re.search(r"HeSocket\.mod:\d+: expected ';'", err), err
    assert main(["mock", "controller", "--program", str(tmp_path / "nothere"), "--port", "0"]) == 1
    assert "no such folder" in capsys.readouterr().err


def test_mock_controller_refuses_a_program_of_another_link(tmp_path, capsys):
    assert main(["rapid", "generate", "--protocol", "modbus", "-o", str(tmp_path / "io")]) == 0
    capsys.readouterr()
    assert main(["mock", "controller", "--program", str(tmp_path / "io"), "--port", "0", "--duration", "1"]) == 1
    assert "choose --protocol modbus" in capsys.readouterr().err


def test_robot_joints_against_a_mock_running_a_module_that_replies_wrong_fails_in_one_line(tmp_path):
    """The module loads and runs, but its JOINTS reply lost a value: `handeye robot joints` against the
    mock running it exits 1 with one line naming the reply, and works again with the generated modules."""
    assert main(["rapid", "generate", "-o", str(tmp_path / "prog")]) == 0
    link = tmp_path / "prog" / "HeSocket.mod"
    text = link.read_text()
    old = ' + " " + NumToStr(jt.robax.rax_6, 4);'
    assert old in text, "the template no longer holds the JOINTS reply this test breaks: update the test"
    link.write_text(text.replace(old, ";", 1))
    for folder, broken in ((tmp_path / "prog", True), (None, False)):
        program = ["--program", str(folder)] if folder else []
        proc = subprocess.Popen([sys.executable, "-m", "handeye.station", "mock", "controller", *program,
                                 "--port", "0", "--duration", "60"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            banner = proc.stdout.readline()
            port = re.search(r"listening on 127\.0\.0\.1:(\d+)", banner)
            assert port, banner + proc.stderr.read()
            joints = subprocess.run([sys.executable, "-m", "handeye.station", "robot", "joints", "--protocol", "socket",
                                     "--host", "127.0.0.1", "--port", port.group(1), "--json"],
                                    capture_output=True, text=True, timeout=60)
        finally:
            proc.terminate()
            proc.communicate(timeout=30)
        if broken:
            assert joints.returncode == 1 and "Traceback" not in joints.stderr, joints.stderr
            assert joints.stderr.count("\n") == 1 and "JOINTS" in joints.stderr, joints.stderr
        else:
            assert joints.returncode == 0, joints.stderr
            assert len(json.loads(joints.stdout)["joints_deg"]) == 6
