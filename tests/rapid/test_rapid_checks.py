"""Our own RAPID checks find what they are meant to find."""

from __future__ import annotations

import pytest

from handeye.rapid.checks import check_program, string_length, tokenize
from handeye.rapid.generate import IO_SIGNALS, render_program
from handeye.rapid.station import default_station


@pytest.fixture(scope="module")
def socket_program():
    return [(m.name, m.text) for m in render_program(default_station(), protocol="socket")]


def _check(modules, **kw):
    kw.setdefault("approved", default_station().postures_array)
    kw.setdefault("external", IO_SIGNALS)
    return [str(f) for f in check_program(modules, **kw)]


def _edit(modules, name, old, new):
    out = []
    for n, text in modules:
        if n == name:
            assert old in text, old
            text = text.replace(old, new, 1)
        out.append((n, text))
    return out


def test_string_length_counts_rapid_escapes():
    assert string_length('"abc"') == 3
    assert string_length('"a""b"') == 3
    assert string_length('"line\\0A"') == 5
    assert string_length('"back\\\\slash"') == 10


@pytest.mark.parametrize("name, old, new, message", [
    ("HeSocket", 'HeSendLine "0 ERR 1 line too long";', 'HeSendLine "' + "x" * 81 + '";', "string literal of 81"),
    ("HeMain", "VAR num heTarget := 0;", "VAR num heTargetWithAVeryLongNameIndeedMoreThan32 := 0;", "limit 32"),
    ("HeMain", "    heState := HE_READY;\n    hePosture := 0;", "    heState := HE_UNKNOWN;\n    hePosture := 0;",
     "'HE_UNKNOWN' is used before"),
    ("HeMain", "  VAR num heState := 0;\n", "", "'heState' is used before"),
    ("HeMain", "MoveAbsJ jtHePost3, vHeMove, fine, tool0;", "MoveL jtHePost3, vHeMove, fine, tool0;",
     "MoveL is not allowed"),
    ("HeMain", "MoveAbsJ jtHePost3, vHeMove, fine, tool0;", "MoveAbsJ CJointT(), vHeMove, fine, tool0;",
     "only CONST jointtargets"),
    ("HeMain", "MoveAbsJ jtHePost3, vHeMove, fine, tool0;", "MoveAbsJ jtHePost3, vHeMove, z10, tool0;", "zone 'fine'"),
    ("HeMain", "[[-5.59,-23.42,", "[[-5.58,-23.42,", "not an approved posture"),
    ("HeMain", "[[-5.59,-23.42,", "[[-175,-23.42,", "outside the IRB1400 limits"),
    ("HeMain", "  VAR num heState := 0;\n", "  VAR num heState := 0;\n  VAR num heState := 1;\n", "declared twice"),
])
def test_checks_catch_each_fault(socket_program, name, old, new, message):
    broken = _edit(socket_program, name, old, new)
    findings = _check(broken)
    assert any(message in f for f in findings), findings


def test_a_module_that_cannot_be_read_is_named_with_its_line(socket_program):
    broken = _edit(socket_program, "HeSocket", "ENDMODULE", "  x := 1 ~ 2;\nENDMODULE")
    findings = _check(broken)
    assert len(findings) == 1 and findings[0].startswith("HeSocket:0: line "), findings
    assert "cannot read '~" in findings[0]


def test_local_data_is_not_visible_from_other_modules(socket_program):
    broken = _edit(socket_program, "HeMain", "    HeLinkOpen;\n", "    HeLinkOpen;\n    heConnected := TRUE;\n")
    assert any("'heConnected' is used before" in f for f in _check(broken))


def test_io_signals_must_come_from_the_io_configuration():
    modules = [(m.name, m.text) for m in render_program(default_station(), protocol="modbus")]
    assert _check(modules) == []
    assert any("'goHeState'" in f for f in _check(modules, external=()))


def test_tokenizer_skips_comments_and_keeps_strings():
    tokens = tokenize('x := "a ! not a comment"; ! comment "quoted"\ny := 9E9;')
    assert [t.text for t in tokens] == ["x", ":=", '"a ! not a comment"', ";", "y", ":=", "9E9", ";"]
    assert tokens[-1].line == 2


def test_one_lexer_and_one_list_of_names_for_the_checks_and_the_interpreter():
    from handeye.rapid.checks import RAPID_BUILTINS, RAPID_KEYWORDS
    from handeye.rapid.interpreter import supported_builtins
    from handeye.rapid.interpreter.lexer import KEYWORDS

    assert RAPID_KEYWORDS is KEYWORDS
    assert {name.lower() for name in supported_builtins()} <= RAPID_BUILTINS  # every instruction the interpreter runs
    # a name the interpreter does not know is not accepted by the checks either
    modules = [("M", "MODULE M\n  PROC main()\n    MoveC p1, p2, v100, fine, tool0;\n    Frobnicate;\n  ENDPROC\n"
                     "ENDMODULE\n")]
    assert any("'Frobnicate' is used before" in f for f in _check(modules))
    # RobotStudio's byte order mark and header are read by both
    assert _check([("M", "\ufeff%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\nMODULE M\nENDMODULE\n")]) == []


@pytest.mark.parametrize("condition, warned", [
    ("NOT a AND b", True), ("NOT (a AND b)", False), ("(NOT a) AND b", False), ("NOT a OR b", False),
    ("a AND NOT b", False), ("NOT a AND b OR c", True), ("b OR NOT (a) AND c", True), ("NOT Fn(a, b AND c)", False),
])
def test_the_checks_warn_where_not_reaches_over_an_and(condition, warned):
    text = (f"MODULE M\n  VAR bool a;\n  VAR bool b;\n  VAR bool c;\n  FUNC bool Fn(bool x, bool y)\n    RETURN x;\n"
            f"  ENDFUNC\n  PROC main()\n    IF {condition} THEN\n      a := TRUE;\n    ENDIF\n  ENDPROC\nENDMODULE\n")
    findings = check_program([("M", text)])
    warnings = [f for f in findings if f.severity == "warning"]
    assert [f for f in findings if f.severity != "warning"] == []
    assert len(warnings) == int(warned)
    if warned:
        assert str(warnings[0]).startswith("M:9: warning: NOT ... AND: RAPID gives NOT the lowest priority")
