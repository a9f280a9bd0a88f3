"""The RAPID interpreter on small programs: the language's semantics as the shipped modules need them."""

from __future__ import annotations

import time

import pytest

from handeye.rapid.interpreter import (Bindings, FixedArm, MemoryIo, RapidLoadError, Task, load_program,
                                       supported_builtins)


def _module(body: str, data: str = "", extra: str = "") -> str:
    return (f"MODULE T\n{data}\n  VAR num done := 0;\n  PROC main()\n{body}\n    done := 1;\n    EXIT;\n  ENDPROC\n"
            f"{extra}\nENDMODULE\n")


def run(body: str, data: str = "", extra: str = "", io=None, timeout: float = 10.0) -> Task:
    """Run ``main`` of a one-module program to its EXIT; the task (its data readable) is returned."""
    program = load_program([(_module(body, data, extra), "T.mod")], signals=io.signals() if io else None)
    task = Task(program, Bindings(io=io, motion=FixedArm())).start()
    assert task.finished.wait(timeout), "the program did not end"
    assert task.state == "exited", task.error
    return task


def failing(body: str, data: str = "", extra: str = "") -> Task:
    """Run a program that stops on an error; the task (``error`` says what and where) is returned."""
    task = Task(load_program([(_module(body, data, extra), "T.mod")]), Bindings(motion=FixedArm())).start()
    assert task.finished.wait(5), "the program did not end"
    assert task.state == "error"
    return task


def value(task: Task, name: str):
    return task.program.datum(name, "T").box[0]


def load_error(body: str, data: str = "", extra: str = "") -> str:
    with pytest.raises(RapidLoadError) as info:
        load_program([(_module(body, data, extra), "T.mod")])
    return str(info.value)


# ---------------------------------------------------------------------------------------- strings and numbers
def test_string_functions_follow_the_manual():
    task = run("""
    a := StrFind("12 GOTO 3", 1, " ");
    b := StrFind("123x", 1, STR_DIGIT \\NotInSet);
    c := StrFind("123", 1, STR_DIGIT \\NotInSet);
    d := StrMatch("10", 1, "0");
    s := StrPart("12 GOTO 3", 4, 4);
    t := NumToStr(12.5, 4) + "|" + NumToStr(-0.00001, 3) + "|" + NumToStr(955, 3) + "|" + NumToStr(0.7071068, 6);
    ok := StrToVal("-12.25", x) AND (NOT StrToVal("12abc", y)) AND (NOT StrToVal("", y)) AND StrToVal("1e2", z);""",
               "  VAR num a;\n  VAR num b;\n  VAR num c;\n  VAR num d;\n  VAR string s;\n  VAR string t;\n"
               "  VAR bool ok;\n  VAR num x;\n  VAR num y := 7;\n  VAR num z;")
    assert (value(task, "a"), value(task, "b"), value(task, "c"), value(task, "d")) == (3, 4, 4, 2)
    assert value(task, "s") == "GOTO"
    assert value(task, "t") == "12.5|0|955|0.707107"
    assert value(task, "ok") is True and value(task, "x") == -12.25 and value(task, "y") == 7 and value(task, "z") == 100


@pytest.mark.parametrize("call", ['StrFind("", 1, " ")', 'StrLen(StrPart("abc", 3, 2))', 'StrLen(StrPart("abc", 0, 1))',
                                  'StrMatch("abc", 4, "c")'])
def test_positions_outside_the_string_stop_the_program(call):
    task = failing(f"    n := {call};", "  VAR num n;")
    assert "outside the string" in task.error and task.error.startswith("T.mod:")


def test_num_is_float32_and_dnum_double():
    task = run("    n := 16777217;\n    d := 16777217;\n    q := 0.1;",
               "  VAR num n;\n  VAR dnum d;\n  VAR num q;")
    assert value(task, "n") == 16777216.0 and value(task, "d") == 16777217.0
    assert value(task, "q") != 0.1 and abs(value(task, "q") - 0.1) < 1e-8


def test_string_concatenation_over_80_characters_is_err_strtoolng():
    task = failing("""
    s := "0123456789012345678901234567890123456789";
    s := s + s + "x";""", "  VAR string s;")
    assert "ERR_STRTOOLNG" in task.error and task.error.startswith("T.mod:7:")


# ---------------------------------------------------------------------------------------- control flow
def test_for_without_step_counts_down_when_start_exceeds_end():
    task = run("""
    FOR i FROM 1 TO 0 DO
      seen := seen + 1;
    ENDFOR
    FOR i FROM 1 TO 3 STEP 1 DO
      up := up + i;
    ENDFOR
    FOR i FROM 2 TO 1 STEP 1 DO
      none := none + 1;
    ENDFOR""", "  VAR num seen;\n  VAR num up;\n  VAR num none;")
    assert (value(task, "seen"), value(task, "up"), value(task, "none")) == (2, 6, 0)


def test_test_case_default_and_strings():
    task = run("""
    FOR i FROM 1 TO 4 DO
      TEST words{i}
      CASE "PING", "PONG":
        out := out + "p";
      CASE "GOTO":
        out := out + "g";
      DEFAULT:
        out := out + "?";
      ENDTEST
    ENDFOR""", '  VAR string words{4} := ["PING", "GOTO", "PONG", "x"];\n  VAR string out;')
    assert value(task, "out") == "pgp?"


def test_records_arrays_and_value_semantics():
    task = run("""
    t := tool0;
    t.tframe.trans := [1, 2, 3];
    t.tload.mass := 1.5;
    u := t;
    u.tframe.trans.x := 99;
    n := VectMagn(t.tframe.trans);
    q := NOrient([2, 0, 0, 0]);
    arr{2} := 5;""", "  VAR tooldata t;\n  VAR tooldata u;\n  VAR num n;\n  VAR orient q;\n  VAR num arr{3};")
    t = value(task, "t")
    assert t.fields["tframe"].fields["trans"].fields == {"x": 1, "y": 2, "z": 3}
    assert value(task, "u").fields["tframe"].fields["trans"].fields["x"] == 99
    assert abs(value(task, "n") - 14 ** 0.5) < 1e-6 and value(task, "q").fields["q1"] == 1
    assert list(value(task, "arr")) == [0, 5, 0]


# ---------------------------------------------------------------------------------------- error handlers
def test_error_handlers_retry_trynext_return_raise():
    task = run("""
    Risky;
    Skip;
    Outer;""", "  VAR num tries;\n  VAR num after;\n  VAR num caught;\n  VAR num d;", extra="""
  PROC Risky()
    tries := tries + 1;
    d := 1 / (tries - 1);
  ERROR
    IF ERRNO = ERR_DIVZERO THEN
      tries := tries + 1;
      RETRY;
    ENDIF
  ENDPROC

  PROC Skip()
    d := 1 / 0;
    after := 1;
  ERROR
    TRYNEXT;
  ENDPROC

  PROC Outer()
    Inner;
    caught := -1;
  ERROR
    caught := ERRNO;
    RETURN;
  ENDPROC

  PROC Inner()
    d := 1 / 0;
  ERROR
    RAISE;
  ENDPROC""")
    from handeye.rapid.interpreter import ERROR_NUMBERS

    assert value(task, "tries") == 2 and value(task, "d") == 1 and value(task, "after") == 1
    assert value(task, "caught") == ERROR_NUMBERS["ERR_DIVZERO"]


def test_an_unhandled_error_stops_the_task_and_names_where():
    task = failing("    Deep;", extra="  PROC Deep()\n    TPWrite \"x\" \\Num:=1 / 0;\n  ENDPROC")
    assert task.error.startswith("T.mod:10:") and "ERR_DIVZERO" in task.error


# ---------------------------------------------------------------------------------------- interrupts and I/O
def test_timer_interrupt_runs_its_trap_while_the_program_waits():
    io = MemoryIo({"goBeat": "signalgo", "diGo": "signaldi"})
    program = load_program([(_module("""
    IDelete timer;
    CONNECT timer WITH Tick;
    ITimer 0.02, timer;
    WaitDI diGo, 1;
    IDelete timer;""", "  VAR intnum timer;\n  VAR num beats;", extra="""
  TRAP Tick
    beats := beats + 1;
    SetGO goBeat, beats;
  ENDTRAP"""), "T.mod")], signals=io.signals())
    task = Task(program, Bindings(io=io)).start()
    time.sleep(0.3)
    io.write("diGo", 1)
    assert task.finished.wait(5) and task.state == "exited", task.error
    assert 5 <= io.read("goBeat") <= 30


def test_waituntil_polls_and_times_out_with_a_flag():
    io = MemoryIo({"giReq": "signalgi"})
    start = time.monotonic()
    task = run("    WaitUntil GInput(giReq) <> 0 OR FALSE \\MaxTime:=0.25 \\TimeFlag:=late;",
               "  VAR bool late;", io=io)
    assert value(task, "late") is True and time.monotonic() - start >= 0.25



def test_waituntil_accepts_the_manuals_lowest_poll_rate_and_refuses_less():
    """0.01 s is the manual's lowest \\PollRate; a num holds it as float32 (a hair below 0.01), still allowed."""
    task = run("    WaitUntil TRUE \\PollRate:=0.01;\n    x := 1;", "  VAR num x;")
    assert value(task, "x") == 1
    assert "PollRate must be >= 0.01 s" in failing("    WaitUntil TRUE \\PollRate:=0.005;").error


# ---------------------------------------------------------------------------------------- load-time checks
@pytest.mark.parametrize("body, data, message", [
    ("    MoveC p, p, v100, fine, tool0;", "", "T.mod:5: unknown instruction MoveC"),
    ("    x := Frobnicate(1);", "  VAR num x;", "Frobnicate() is not a function"),
    ("    x := y;", "  VAR num x;", "'y' is not declared"),
    ('    x := "a";', "  VAR num x;", "expected num, got string"),
    ("    c := 2;", "  CONST num c := 1;", "c is a CONST"),
    ("    TPWrite;", "", "missing argument(s) String"),
    ("    TPWrite \"a\" \\Numm:=1;", "", "no optional argument \\Numm"),
    ("    GOTO here;", "", "GOTO is not supported"),
    ("    RETRY;", "", "RETRY is for error handlers"),
    ("    x := 1", "  VAR num x;", "expected ';'"),
])
def test_what_the_interpreter_cannot_run_is_refused_naming_the_line(body, data, message):
    assert message in load_error(body, data)


def test_locals_of_another_module_are_not_visible():
    a = "MODULE A\n  LOCAL VAR num hidden := 1;\n  VAR num shown := 2;\nENDMODULE\n"
    b = "MODULE B\n  PROC main()\n    shown := hidden;\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(RapidLoadError, match="B.mod:3: 'hidden' is not declared"):
        load_program([(a, "A.mod"), (b, "B.mod")])


def test_the_builtins_the_brief_names_are_supported():
    names = set(supported_builtins())
    needed = {"StrLen", "StrFind", "StrPart", "StrMatch", "StrToVal", "NumToStr", "ValToStr", "Round", "Abs", "Sqrt",
              "VectMagn", "NOrient", "SocketCreate", "SocketBind", "SocketListen", "SocketAccept", "SocketReceive",
              "SocketSend", "SocketClose", "SocketGetStatus", "Open", "ReadStr", "WriteStrBin", "ClearIOBuff", "Close",
              "SetDO", "SetGO", "SetAO", "DInput", "GInput", "GInputDnum", "AInput", "WaitDI", "WaitUntil", "ITimer",
              "IDelete", "MoveAbsJ", "CJointT", "CRobT", "WaitTime", "TPWrite", "ClkReset", "ClkStart", "ClkRead",
              "WZBoxDef", "WZCylDef", "WZLimSup", "WZHomeJointDef", "WZDOSet", "GetSysInfo", "Stop"}
    assert needed <= names, needed - names


# ---------------------------------------------------------------------------------------- the parser vs rapidchecker
def _shipped_modules():
    from handeye.rapid.generate import render_key, render_program
    from handeye.rapid.station import default_station

    station = default_station().with_(write_key="Cell7-key_2024")
    out = {}
    for protocol in ("socket", "serial", "modbus"):
        for m in render_program(station, protocol=protocol):
            out[m.filename] = m.text
    out["HeKey.sys"] = render_key(station).text
    return out


MUTATIONS = {
    "lost ';'": ("heConnected := FALSE;", "heConnected := FALSE"),
    "'=' for ':='": ("heConnected := FALSE;", "heConnected = FALSE;"),
    "ENDIF lost": ("      HeAccept waitTime;\n      RETURN;\n    ENDIF\n", "      HeAccept waitTime;\n      RETURN;\n"),
    "open parenthesis": ("WHILE (heState = HE_AT) OR (heState = HE_LATE) DO", "WHILE (heState = HE_AT OR (heState = HE_LATE) DO"),
    "misspelt ENDPROC": ("    heRxTail := \"\";\n  ENDPROC", "    heRxTail := \"\";\n  ENDPROCX"),
}


pytestmark_rapidchecker = pytest.mark.filterwarnings("ignore::DeprecationWarning")  # pyparsing names it uses


@pytestmark_rapidchecker
def test_the_parser_accepts_what_rapidchecker_accepts_on_the_shipped_modules():
    from rapidchecker.check import check_format

    from handeye.rapid.checks import for_rapidchecker
    from handeye.rapid.interpreter import parse_module

    for name, text in _shipped_modules().items():
        assert check_format(for_rapidchecker(text)) == [], name
        assert parse_module(text, name).name == name.split(".")[0]


@pytestmark_rapidchecker
@pytest.mark.parametrize("mutation", sorted(MUTATIONS))
def test_the_parser_refuses_what_rapidchecker_refuses(mutation):
    from rapidchecker.check import check_format

    from handeye.rapid.interpreter import parse_module

    old, new = MUTATIONS[mutation]
    text = _shipped_modules()["HeSocket.mod"]
    assert old in text, "the template changed: update the mutation"
    broken = text.replace(old, new, 1)
    assert check_format(broken), f"rapidchecker accepts {mutation}"
    with pytest.raises(RapidLoadError, match=r"^HeSocket\.mod:\d+: "):
        parse_module(broken, "HeSocket.mod")


def test_records_of_the_program_local_data_and_functions():
    task = run("""
    p.name := "cam";
    p.pose.trans := [1, 2, 3];
    n := Twice(p.pose.trans.z) + counter;
    Bump counter;
    Bump counter;""", """  RECORD part
    string name;
    pose pose;
  ENDRECORD
  LOCAL VAR part p;
  LOCAL PERS num counter := 10;
  VAR num n;""", extra="""
  LOCAL FUNC num Twice(num x)
    RETURN 2 * x;
  ENDFUNC

  PROC Bump(INOUT num value)
    value := value + 1;
  ENDPROC""")
    assert value(task, "p").fields["name"] == "cam" and value(task, "n") == 16 and value(task, "counter") == 12
