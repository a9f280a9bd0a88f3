"""The mock cell's I/O signals as a RAPID program sees them: WaitDI on an input a test sets, its
\\MaxTime raising ERR_WAIT_MAXTIME as RAPID does, SetDO on an output, the link's own signals passed through."""

from __future__ import annotations

import threading

import pytest

from handeye.mocks.controller.signals import CellSignals, parse_signal
from handeye.rapid.interpreter import Bindings, FixedArm, MemoryIo, Task, load_program


def _run(body: str, io: CellSignals, timeout: float = 20.0) -> Task:
    text = (f"MODULE T\n  VAR num got := 0;\n  VAR bool late := FALSE;\n  PROC main()\n{body}\n    EXIT;\n"
            "  ERROR\n    IF ERRNO = ERR_WAIT_MAXTIME THEN\n      got := -1;\n      TRYNEXT;\n    ENDIF\n  ENDPROC\n"
            "ENDMODULE\n")
    task = Task(load_program([(text, "T.mod")], signals=io.signals()), Bindings(io=io, motion=FixedArm())).start()
    assert task.finished.wait(timeout) and task.state == "exited", task.error
    return task


def test_waitdi_waits_for_the_input_a_test_sets_and_setdo_writes_the_output():
    io = CellSignals().over(MemoryIo({"diHeGateway": "signaldi"}))
    io.set("diCellDoor", 0)
    threading.Timer(0.3, io.set, ("diCellDoor", 1)).start()
    task = _run("    WaitDI diCellDoor, 1 \\MaxTime:=20;\n    SetDO doCellLamp, 1;\n    got := DInput(diHeGateway) + 2;", io)
    assert task.program.datum("got", "T").box[0] == 2  # no timeout; the link's signal read through
    assert io.value("doCellLamp") == 1


def test_waitdi_maxtime_raises_err_wait_maxtime_and_timeflag_is_set_instead():
    io = CellSignals()
    io.set("diCellReady", 0)
    task = _run("    WaitDI diCellReady, 1 \\MaxTime:=0.2;\n    WaitDI diCellReady, 1 \\MaxTime:=0.2 \\TimeFlag:=late;", io)
    assert task.program.datum("got", "T").box[0] == -1  # the error handler took ERR_WAIT_MAXTIME
    assert task.program.datum("late", "T").box[0] is True


def test_what_is_not_a_cell_input_is_refused():
    io = CellSignals(extra=[parse_signal("diFence:signaldi=1")])
    assert io.signals()["diFence"] == "signaldi" and io.read("diFence") == 1
    with pytest.raises(ValueError, match="'doCellLamp' is not an input of the mock cell"):
        io.set("doCellLamp", 1)
    with pytest.raises(ValueError, match="0 or 1"):
        io.set("diCellDoor", 2)
    with pytest.raises(ValueError, match="NAME:TYPE=VALUE"):
        parse_signal("diFence=1")
