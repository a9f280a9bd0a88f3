"""Usage errors exit 2, other errors 1 (README; issue 25, finding 7f).

Every leaf command of ``handeye`` (``import``, ``mock controller``, ``stereo calibrate`` ...) is found
from the parser itself, so a command added later is covered: an unknown option, a missing required
argument and a value outside an option's choices exit 2 with one line. The usage checks of the
commands' own code (flags that exclude each other, a flag that does not apply, a value out of range)
exit 2 as well; a missing input file still exits 1.
"""

from __future__ import annotations

import argparse

import pytest

from handeye.station import cli


def _leaves(parser, path=()):
    """``(argv prefix, parser)`` of every command that takes options (sub-commands walked)."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if path and not subs:
        return [(path, parser)]
    out = [(path, parser)] if path and any(a.option_strings and a.dest != "help" for a in parser._actions) else []
    for action in subs:
        for name, child in action.choices.items():
            out += _leaves(child, path + (name,))
    return out


LEAVES = _leaves(cli.build_parser())
NAMES = [" ".join(p) for p, _ in LEAVES]


def _required(parser) -> list:
    """Stand-in values for the required positionals and options of ``parser`` (to reach the checks)."""
    argv = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) or action.dest == "help":
            continue
        value = action.choices[0] if action.choices else "x"
        if not action.option_strings:
            argv += [str(value)] * (1 if action.nargs in (None, "+") else 0)
        elif action.required:
            argv += [action.option_strings[0], str(value)]
    return argv


def _run(capsys, argv):
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    err = capsys.readouterr().err
    return code, err


def test_every_command_is_covered():
    top = {e if isinstance(e, str) else e[0] for e in cli.COMMANDS}
    assert top <= {p[0] for p, _ in LEAVES}
    assert {"mock controller", "stereo calibrate", "robot joints", "rapid generate"} <= set(NAMES)


@pytest.mark.parametrize("path, parser", LEAVES, ids=NAMES)
def test_unknown_option_exits_2(capsys, path, parser):
    code, err = _run(capsys, [*path, *_required(parser), "--no-such-option"])
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "--no-such-option" in err


@pytest.mark.parametrize("path, parser", LEAVES, ids=NAMES)
def test_missing_required_argument_exits_2(capsys, path, parser):
    needed = [a for a in parser._actions if (a.required or (not a.option_strings and a.nargs not in ("?", "*")))
              and not isinstance(a, argparse._SubParsersAction) and a.dest != "help"]
    if not needed:
        pytest.skip("no required argument")
    code, err = _run(capsys, list(path))
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "required" in err


@pytest.mark.parametrize("path, parser", LEAVES, ids=NAMES)
def test_bad_choice_exits_2(capsys, path, parser):
    options = [a for a in parser._actions if a.option_strings and a.choices]
    if not options:
        pytest.skip("no option with choices")
    for action in options:
        code, err = _run(capsys, [*path, *_required(parser), action.option_strings[0], "not-a-choice"])
        assert code == 2, (action.option_strings, err)
        assert len(err.strip().splitlines()) == 1 and ("invalid choice" in err or "invalid int value" in err)


def _moveit_file(tmp_path):
    path = tmp_path / "pose_samples.json"
    path.write_text("[]")
    return path


#: Usage refused by the commands' own code (not argparse): argv (``{d}`` = a temporary folder), message.
OWN_CHECKS = [
    (["capture", "--session", "{d}/s"], "give --config STATION.yaml"),
    (["capture", "--mock", "--session", "{d}/s", "--postures", "2"], "--postures must be between 3 and 255"),
    (["demo", "--postures", "2"], "--postures must be between 3 and 255"),
    (["writeback", "{d}/s"], "give --config STATION.yaml"),
    (["benchmark", "--postures", "2", "-o", "{d}/b"], "--postures values must be whole numbers >= 3"),
    (["simulate", "-o", "{d}/s", "--joint-offset", "1,2,3"], "--joint-offset needs 6 values"),
    (["import", "{moveit}", "-o", "{d}/s", "--square-mm", "30"], "--square-mm needs --board"),
    (["import", "{moveit}", "-o", "{d}/s", "--format", "moveit", "--max-postures", "10"],
     "--max-postures does not apply to moveit files"),
    (["import", "{moveit}", "{moveit}", "-o", "{d}/s", "--format", "moveit"], "moveit reads one file; got 2"),
    (["triangulate", "--left", "{d}/l.png", "--json", "{d}/o.json"], "give both --left and --right"),
    (["triangulate", "--left", "{d}/l.png", "--right", "{d}/r.png", "--xb3-raw", "{d}/f.raw", "--json", "{d}/o.json"],
     "give either"),
    (["stereo", "calibrate", "--board", "9x6", "--square-mm", "30", "-o", "{d}/s.yaml"], "give one source of pairs"),
    (["stereo", "calibrate", "--left", "{d}/*.png", "--board", "9x6", "--square-mm", "30", "-o", "{d}/s.yaml"],
     "give both --left and --right"),
    (["mock", "controller", "--port", "0", "--idle-timeout", "60", "--duration", "0.1"], "--idle-timeout must be"),
]


@pytest.mark.parametrize("argv, message", OWN_CHECKS, ids=[" ".join(a[:2]) + ": " + m for a, m in OWN_CHECKS])
def test_usage_refused_by_our_own_checks_exits_2(tmp_path, capsys, argv, message):
    moveit = _moveit_file(tmp_path)
    code, err = _run(capsys, [a.format(d=tmp_path, moveit=moveit) for a in argv])
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and lines[0].startswith(f"handeye {argv[0]}: error: ")


def test_other_errors_still_exit_1(tmp_path, capsys):
    code, err = _run(capsys, ["import", tmp_path / "missing.json", "-o", tmp_path / "s"])
    assert code == 1 and "no such file" in err
    code, err = _run(capsys, ["calibrate", tmp_path / "no-session"])
    assert code == 1, err
