"""``mock controller --program DIR``: a program that ends, or never opens its link, is reported in one
line with what to do, not served silently (issue 25, finding 7e)."""

from __future__ import annotations

import pytest

from handeye.mocks.controller import service
from handeye.mocks.controller.service import MockControllerOptions, run_mock_controller
from handeye.rapid.errors import RapidError

PROGRAMS = {
    "exit": "MODULE HeMain\n  PROC main()\n    WaitTime 0.2;\n    EXIT;\n  ENDPROC\nENDMODULE\n",
    "error": "MODULE HeMain\n  VAR num n := 0;\n  PROC main()\n    WaitTime 0.2;\n    n := 1 / n;\n  ENDPROC\nENDMODULE\n",
    "no_link": "MODULE HeMain\n  PROC main()\n    WHILE TRUE DO\n      WaitTime 0.05;\n    ENDWHILE\n  ENDPROC\nENDMODULE\n",
    "returns": "MODULE HeMain\n  PROC main()\n    TPWrite \"hello\";\n  ENDPROC\nENDMODULE\n",
}


@pytest.fixture
def program(tmp_path):
    def make(name):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "HeMain.mod").write_text(PROGRAMS[name])
        return str(folder)
    return make


def _run(protocol, folder, duration=1.5):
    lines = []
    code = run_mock_controller(MockControllerOptions(protocol=protocol, port=0, program=folder, duration_s=duration),
                               announce=lambda text: None, warn=lines.append)
    return code, lines


def test_serial_program_that_exits_is_reported(program):
    code, lines = _run("serial", program("exit"))
    assert code == 0
    assert len(lines) == 1 and "ended on EXIT at HeMain.mod:4" in lines[0] and "start the mock again" in lines[0]


def test_serial_program_that_stops_on_an_error_names_the_line(program):
    code, lines = _run("serial", program("error"))
    assert code == 1
    assert len(lines) == 1 and "stopped on an error: HeMain.mod:5: ERR_DIVZERO" in lines[0]
    assert "fix that line of the modules in" in lines[0]


@pytest.mark.parametrize("name, words", [("no_link", "has not opened its serial link 0.3 s after it started"),
                                         ("returns", "its main ran to its end")])
def test_serial_program_without_its_link_is_reported(program, monkeypatch, name, words):
    monkeypatch.setattr(service, "LINK_NOTICE_S", 0.3)
    code, lines = _run("serial", program(name))
    assert code == 0
    assert len(lines) == 1 and words in lines[0] and "the PC cannot connect" in lines[0]


@pytest.mark.parametrize("name, words", [("exit", "ended on EXIT at HeMain.mod:4 before it listened"),
                                         ("error", "stopped on an error: HeMain.mod:5: ERR_DIVZERO"),
                                         ("returns", "ran main to its end without listening")])
def test_socket_program_that_ends_before_listening_is_refused_at_once(program, name, words):
    with pytest.raises(RapidError) as info:
        _run("socket", program(name))
    message = str(info.value)
    assert words in message and "\n" not in message and "start the mock again" in message


def test_a_serving_program_says_nothing(monkeypatch):
    monkeypatch.setattr(service, "LINK_NOTICE_S", 0.3)
    code, lines = _run("serial", None, duration=1.0)
    assert code == 0 and lines == []
