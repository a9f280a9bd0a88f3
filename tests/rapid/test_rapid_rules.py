"""RAPID's own rules where the interpreter used to refuse or guess (RAPID reference, "Basic
Characteristics"): NOT's priority (7.7), IN parameters of PROC and FUNC (3.2), UNDO handlers, and the
byte order mark and file header RobotStudio writes."""

from __future__ import annotations

import itertools

import pytest

from handeye.rapid.interpreter import Bindings, FixedArm, RapidLoadError, Task, load_program

from test_interpreter import load_error, run, value


@pytest.mark.parametrize("a, b", list(itertools.product([False, True], repeat=2)))
def test_not_has_the_lowest_priority(a, b):
    """NOT a AND b is NOT (a AND b); NOT a OR b is (NOT a) OR b; a AND NOT b is a AND (NOT b)."""
    word = {False: "FALSE", True: "TRUE"}
    task = run(f"""
    a := {word[a]};
    b := {word[b]};
    r1 := NOT a AND b;
    r2 := NOT a OR b;
    r3 := a AND NOT b;
    r4 := NOT a AND b OR a;
    r5 := (NOT a) AND b;""", "  VAR bool a;\n  VAR bool b;\n" + "".join(f"  VAR bool r{i};\n" for i in range(1, 6)))
    assert value(task, "r1") is (not (a and b))
    assert value(task, "r2") is ((not a) or b)
    assert value(task, "r3") is (a and (not b))
    assert value(task, "r4") is ((not (a and b)) or a)
    assert value(task, "r5") is ((not a) and b)


def test_a_procs_in_parameter_is_a_routine_variable_and_the_argument_stays():
    task = run("""
    x := 5;
    p := [1, 2, 3];
    Twice x, p;""", "  VAR num x;\n  VAR num inside;\n  VAR pos p;\n  VAR pos seen;",
               """  PROC Twice(num n, pos q)
    n := n * 2;
    q.x := 100;
    inside := n;
    seen := q;
  ENDPROC""")
    assert value(task, "x") == 5 and value(task, "inside") == 10
    assert value(task, "p").fields["x"] == 1 and value(task, "seen").fields["x"] == 100


def test_a_funcs_in_parameter_is_a_constant():
    message = load_error("    x := Twice(2);", "  VAR num x;", """  FUNC num Twice(num n)
    n := n * 2;
    RETURN n;
  ENDFUNC""")
    assert "T.mod:10:" in message and "input parameter of function Twice, a constant" in message


@pytest.mark.parametrize("prefix", ["\ufeff", "\xef\xbb\xbf", "", "\ufeff%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\n",
                                    "%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n"])
def test_robotstudios_byte_order_mark_and_header_are_read(prefix):
    text = prefix + "MODULE T\n  VAR num x := 1;\n  PROC main()\n    x := 1 / 0;\n  ENDPROC\nENDMODULE\n"
    task = Task(load_program([(text, "T.mod")]), Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5) and task.state == "error"
    header_lines = prefix.count("\n")
    assert f"T.mod:{4 + header_lines}: ERR_DIVZERO" in task.error  # the header's lines count


def test_a_header_that_is_not_one_is_refused_with_its_line():
    with pytest.raises(RapidLoadError, match=r"T.mod:2: file header .*got 'MODULE T'"):
        load_program([("%%%\nMODULE T\nENDMODULE\n", "T.mod")])


_UNDO = """  PROC Inner()
    trace := trace + "i";
    {action}
    trace := trace + "x";
  UNDO
    trace := trace + "U";
  ENDPROC
  PROC Outer()
    Inner;
    trace := trace + "o";
  UNDO
    trace := trace + "V";
  ENDPROC"""


def test_undo_handlers_run_innermost_first_on_exit():
    program = load_program([("MODULE T\n  VAR string trace;\n  PROC main()\n    Outer;\n  ENDPROC\n"
                             + _UNDO.format(action="EXIT;") + "\nENDMODULE\n", "T.mod")])
    task = Task(program, Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5) and task.state == "exited"
    assert program.datum("trace", "T").box[0] == "iUV"


def test_undo_runs_when_an_error_leaves_the_routine_not_on_a_normal_end():
    program = load_program([("MODULE T\n  VAR string trace;\n  VAR num z;\n  PROC main()\n    Outer;\n"
                             "    trace := trace + \"m\";\n    EXIT;\n  ERROR\n    trace := trace + \"E\";\n"
                             "    TRYNEXT;\n  ENDPROC\n" + _UNDO.format(action="z := 1 / z;") + "\nENDMODULE\n", "T.mod")])
    task = Task(program, Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5) and task.state == "exited", task.error
    # the error leaves Inner and Outer (their UNDO run), main's handler takes it and goes on
    assert program.datum("trace", "T").box[0] == "iUVEm"
    clean = run("    Outer;", "  VAR string trace;", _UNDO.format(action="trace := trace + \"-\";"))
    assert value(clean, "trace") == "i-xo"


def test_protocol_md_lists_every_instruction_and_function_the_interpreter_runs():
    from pathlib import Path

    from handeye.rapid.interpreter import supported_builtins

    text = (Path(__file__).resolve().parents[2] / "src" / "handeye" / "rapid" / "PROTOCOL.md").read_text()
    listed = text.split("**Every instruction and function**:")[1].split("- **Refused at load**")[0]
    names = {n.strip(" .\n") for n in listed.replace("\n", " ").split(",")}
    assert set(supported_builtins()) <= names, sorted(set(supported_builtins()) - names)


def test_undo_runs_when_the_task_is_stopped_from_outside_and_does_not_wait():
    text = ("MODULE T\n  VAR string trace;\n  PROC main()\n    Outer;\n  ENDPROC\n"
            + _UNDO.format(action="WaitTime 30;").replace('trace := trace + "V";', 'trace := trace + "V";\n    WaitTime 30;')
            + "\nENDMODULE\n")
    program = load_program([(text, "T.mod")])
    task = Task(program, Bindings(motion=FixedArm())).start()
    assert task.wait_idle(10)  # in Inner's WaitTime
    task.stop()
    assert task.finished.wait(10) and task.state == "stopped"
    assert program.datum("trace", "T").box[0] == "iUV"  # both handlers ran; the wait in Outer's ended it
