"""The guided RAPID program (``rapid generate --guided``, issue 22) and what the interpreter runs for it:
Stop \\NoRegain (execution stops, the program pointer stays, Start continues after it), TPReadFK and
UIMessageBox answered at the pendant."""

from __future__ import annotations

import re

import pytest

from handeye.drivers.controller import protocol as P
from handeye.drivers.controller.modbus_map import GUIDED_REGISTERS, load_register_map
from handeye.rapid.errors import RapidError
from handeye.rapid.generate import IO_SIGNALS, render_guided_program, render_program
from handeye.rapid.guided import GUIDED_IO_SIGNALS, HINT_CODES, VERDICTS
from handeye.rapid.interpreter import Bindings, FixedArm, Task, load_program
from handeye.rapid.interpreter.pendant import FlexPendant
from handeye.rapid.station import default_station


@pytest.fixture(scope="module")
def guided():
    station = default_station().with_(write_key="Cell7-key_2024")
    return {(protocol, prompt): render_guided_program(station, protocol, prompt)
            for protocol in ("socket", "serial", "modbus") for prompt in ("fk", "messagebox")}


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_every_guided_module_passes_rapidchecker_and_never_moves_the_robot(guided):
    from rapidchecker.check import check_format

    from handeye.rapid.checks import for_rapidchecker

    checked = set()
    for (protocol, prompt), modules in guided.items():
        assert [m.name for m in modules][0] == "HeGuide"
        for m in modules:
            if m.text not in checked:  # each distinct module once (rapidchecker takes a while)
                assert check_format(for_rapidchecker(m.text)) == [], (protocol, prompt, m.name)
                checked.add(m.text)
        main = modules[0].text
        assert "Stop \\NoRegain;" in main and "CONST num HE_COUNT := 0;" in main
        assert not re.search(r"\bMove(AbsJ|J|L)\b|CONST jointtarget", main)
        assert ("TPReadFK heKey" in main) == (prompt == "fk") and ("UIMessageBox(" in main) == (prompt == "messagebox")
        for verdict in VERDICTS:
            assert f'RETURN "{verdict.text}";' in main


def test_the_guided_dispatcher_serves_every_codec_command_and_the_planned_one_not_guide(guided):
    from test_rapid_generate import _dispatcher_cases

    for protocol in ("socket", "serial"):
        cases = _dispatcher_cases(guided[(protocol, "fk")][1].text)
        assert set(cases) == set(P.SPECS)
        assert all(cases[name] == len(spec.args) for name, spec in P.SPECS.items())
        planned = render_program(default_station(), protocol=protocol)[1].text
        assert '"GUIDE"' not in planned and "HeLinkWaitGuide" not in planned  # the planned program is as it was
    assert (P.VERDICT.low, P.VERDICT.high) == (min(v.code for v in VERDICTS), max(v.code for v in VERDICTS))
    assert (P.HINT.low, P.HINT.high) == (min(HINT_CODES), max(HINT_CODES))


def test_the_guided_io_module_uses_the_guide_registers_of_the_map(guided):
    text = guided[("modbus", "fk")][1].text
    used = set(re.findall(r"\b([gd][io]He\w+|a[io]He\w+)\b", text))
    assert used == set(IO_SIGNALS) | set(GUIDED_IO_SIGNALS)
    registers = load_register_map().registers
    assert {name for reg in GUIDED_REGISTERS for name in registers[reg].signals()} == set(GUIDED_IO_SIGNALS)


def test_protocol_md_lists_the_verdicts_hints_and_guide_registers_of_the_code():
    from pathlib import Path

    from handeye.rapid.guided import HINTS

    text = (Path(__file__).resolve().parents[2] / "src" / "handeye" / "rapid" / "PROTOCOL.md").read_text()
    section = text.split("## Guided capture without options")[1].split("\n## ")[0]
    assert set(re.findall(r"^\| (\d+) \| ([A-Z_]+) \| (.+) \|$", section, re.M)) == \
        {(str(v.code), v.name, v.text) for v in VERDICTS}
    assert set(re.findall(r"^\| (\d+) \| ([a-z].+) \|$", section, re.M)) == {(str(k), t) for k, t in HINTS.items()}
    registers = load_register_map().registers
    for name in GUIDED_REGISTERS:
        assert f"| {name} | {registers[name].address} | PC | {registers[name].signal} |" in text
    assert "| `GUIDE v h` |" in text


def test_robot_web_services_has_no_guided_program():
    with pytest.raises(RapidError, match="no guided program over rws"):
        render_guided_program(default_station(), "rws")


# ---------------------------------------------------------------------------------------- the interpreter
_PROGRAM = """MODULE T
  VAR num stage := 0;
  VAR num key := 0;
  VAR num box := 0;
  VAR errnum flag := 0;
  VAR string buttons{2} := ["Yes", "No"];
  PROC main()
    stage := 1;
    TPReadFK key, "go on?", "Capture", stEmpty, stEmpty, stEmpty, "Done";
    stage := 2;
    Stop \\NoRegain;
    stage := 3;
    box := UIMessageBox(\\Header:="h" \\Message:="again?" \\BtnArray:=buttons);
    TPReadFK key, "late?", "A", stEmpty, stEmpty, stEmpty, stEmpty \\MaxTime:=0.1 \\BreakFlag:=flag;
    stage := 4;
    EXIT;
  ENDPROC
ENDMODULE
"""


def test_stop_noregain_waits_for_start_and_the_prompts_for_the_operator():
    pendant = FlexPendant()
    program = load_program([(_PROGRAM, "T.mod")])
    task = Task(program, Bindings(motion=FixedArm(), flexpendant=pendant)).start()
    datum = lambda name: program.datum(name, "T").box[0]  # noqa: E731
    assert pendant.wait(lambda p: p.prompt is not None, 5)
    assert pendant.prompt.keys == {1: "Capture", 5: "Done"} and datum("stage") == 1
    assert pendant.start() is not None  # not stopped: Start does nothing
    assert "not offered" in pendant.answer(3)
    assert pendant.answer(5) is None
    assert pendant.wait(lambda p: p.stopped, 5)
    assert datum("stage") == 2 and task.running and task.halted  # stopped at the Stop, the pointer kept
    assert pendant.answer(1) == "no prompt on the pendant"
    assert pendant.start() is None
    assert pendant.wait(lambda p: p.prompt is not None, 5)
    assert datum("stage") == 3 and pendant.prompt.keys == {1: "Yes", 2: "No"}  # execution went on after the Stop
    assert pendant.answer(2) is None
    assert task.finished.wait(5) and task.state == "exited", task.error
    assert datum("key") == 5 and datum("box") == 2 and datum("stage") == 4
    assert datum("flag") > 0  # nobody answered within \MaxTime: the break flag says ERR_TP_MAXTIME


def test_without_a_pendant_stop_ends_the_program_and_a_prompt_stops_it_on_an_error():
    program = load_program([(_PROGRAM.replace('    TPReadFK key, "go on?", "Capture", stEmpty, stEmpty, stEmpty, "Done";\n',
                                              ""), "T.mod")])
    task = Task(program, Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5) and task.state == "stopped" and task.ended == "a Stop instruction"
    task = Task(load_program([(_PROGRAM, "T.mod")]), Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5) and task.state == "error" and "no pendant" in task.error
