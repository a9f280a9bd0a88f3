"""``handeye verify``: revisit a few postures of a calibrated session and say whether, and what, changed."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "check a calibration on the station: revisit K postures, test for drift, say what changed"

EPILOG = """\
The check is against SESSION's saved result (SESSION/result.yaml of handeye calibrate: refused when
older than SESSION's postures; solved and saved first, saying so, when missing), or against the
quick update written after it when that is the latest write-back in the history beside the sessions
(the output says so; a tooldata finding never advises undoing a write-back).

The controller's camera tooldata is read and compared with that result; then K (default 5) of
SESSION's postures, chosen to tell the explanations apart (spread rotation axes and distances, the
shortest path clear of the cell), are revisited with the same RAPID program and links as capture,
and the board measured at each is compared with where SESSION's calibration predicts it. The test's
false-alarm rate (--level, default 1 %) comes from the noise the calibration estimated (camera,
robot, the covariance of X and of the board), not from a constant.

DRIFT needs both: a discrepancy beyond the noise (the test) and a change larger than the station's
tolerance (verify.tolerance_mm / tolerance_deg of the config; by default the quality thresholds
max_sigma_translation_mm / max_sigma_rotation_deg, 0.2 mm / 0.02 deg). A change the test detects
but within the tolerance is OK, and the output says so with its size; the JSON keys "size",
"tolerance", "beyond_tolerance" and test.statistically_detectable hold both.

A drift is explained: camera (moved on the flange), board (moved), joint N (its zero moved),
tooldata (the controller holds another one: DRIFT only when it differs from SESSION's by more than
the same tolerance; its difference and the tolerance are printed), with the size and how much more likely it is than the
next explanation; explanations these data cannot tell apart are named together (a joint-1 zero
shift looks like a board turn about base z, a joint-6 one like a camera turn about the flange axis).
When the camera moved, a quick update of X is given with its uncertainty: handeye writeback
CHECK_FOLDER writes it like a calibration (same refusals, backup, read-back).

The measurements are a session beside SESSION (SESSION-verify-<time>); every check appends one
record to history.jsonl beside the sessions; --history prints it, --report draws the trend.

Exit status: 0 ok, 3 drift, 4 inconclusive (board not seen, too few postures measured, a link
fault), 1 errors (nothing written), 2 usage errors.

Examples:
  handeye verify --config station.yaml --against cal_01
  handeye verify --mock --against cal_01 --json check.json --report
  handeye verify --config station.yaml --against cal_01 --history
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("verify", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", metavar="STATION.yaml", help="station configuration (controller, camera, cell, mock)")
    p.add_argument("--mock", action="store_true", help="the embedded mock station")
    p.add_argument("--against", metavar="SESSION", required=True, help="the calibrated session to check")
    p.add_argument("--postures", metavar="K", type=int, default=5, help="postures to revisit (default 5, at least 3)")
    p.add_argument("--level", type=float, default=0.01,
                   help="false-alarm rate of the test (default 0.01, from 1e-06 to 0.2)")
    p.add_argument("--json", metavar="FILE", help="write the outcome as JSON")
    p.add_argument("--report", metavar="FILE", nargs="?", const="",
                   help="HTML report with the history's trend (default: CHECK_FOLDER/verify_report.html)")
    p.add_argument("--history", action="store_true", help="print the history of checks beside SESSION and stop")
    p.add_argument("--yes", action="store_true", help="move a real robot without asking (scripts)")
    return p


def _history(args, config) -> int:
    import sys

    from ..report.quality import config_thresholds
    from ..verify.history import history_lines, history_path, load_history
    from ..verify.page import write_history_report

    path = history_path(args.against)
    history = load_history(path)
    print(f"history of checks: {path}")
    for line in history_lines(history.records):
        print("  " + line)
    if history.skipped:
        print(history.skipped_line(), file=sys.stderr)
    if args.report is not None:
        target = args.report or str(path.with_suffix(".html"))
        print(f"report: {write_history_report(target, history, config_thresholds(config), None)}")
    return 0


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import sys

    from ...base import HandEyeError, UsageError
    from ...calibration import DEFAULT_LEVEL, LEVEL_RANGE, MIN_VERIFY_POSTURES
    from ..config.station import default_config, load_config
    from ..runtime import MOCK_BANNER, open_station, rehearsal_banner
    from ..config.station_kind import station_tag

    if not args.config and not args.mock:
        raise UsageError("give --config STATION.yaml (the station) or --mock (the embedded mock station)")
    low, high = LEVEL_RANGE
    if not low <= args.level <= high:  # NaN too
        raise UsageError(f"--level must be between {low:g} and {high:g} (the test's false-alarm rate; default "
                         f"{DEFAULT_LEVEL:g}); got {args.level:g}")
    if args.postures < MIN_VERIFY_POSTURES:
        raise UsageError(f"--postures {args.postures} is too few: the test and its diagnosis need at least "
                         f"{MIN_VERIFY_POSTURES} revisited postures")
    config = load_config(args.config) if args.config else default_config()
    if args.mock:
        config = config.as_mock()
    if args.history:
        return _history(args, config)
    from ..verify.check import EXIT_CODES, check_request

    check_request(config, Path(args.against), args.postures)  # refusals before anything opens or moves
    if not config.is_mock and not args.yes and not sys.stdin.isatty():
        raise HandEyeError("the check moves the robot and needs the operator's yes: run it at a terminal, or give "
                           "--yes (scripts); nothing moved")
    if config.is_mock:
        print(MOCK_BANNER, flush=True)
    elif config.is_rehearsal:
        print(rehearsal_banner(config), flush=True)
    with open_station(config, session_dir=args.against) as link:
        verdict = _check(args, config, link, station_tag(config, link))  # the link's own parts too
    return EXIT_CODES[verdict]


def _check(args, config, link, tag: str) -> str:
    from ...base import HandEyeError, write_text_atomic
    from ..report.quality import config_thresholds
    from ..verify.check import verify
    from ..verify.history import append_record, check_record, history_path, load_history
    from ..verify.page import write_history_report
    from ..origin import MOCK
    from ..config.station_kind import station_kind
    from ..verify.result import advice, outcome_json, outcome_lines

    import json
    import sys

    def say(message: str) -> None:
        print(tag + message, flush=True)

    confirm = (lambda question: True) if args.yes else _ask
    outcome = verify(config, args.against, link, args.postures, args.level, progress=say, confirm=confirm,
                     on_posture=lambda r: say(("  ok    " if r.ok else "  SKIP  ") + r.message))
    thresholds = config_thresholds(config)
    data = outcome_json(outcome, str(args.against), thresholds)
    config_arg = f"--config {args.config}" if args.config and not args.mock else "--mock"
    for line in outcome_lines(data, advice(outcome, data["diagnosis"], str(args.against), config_arg)):
        say(line)
    station = "mock" if station_kind(config, link) == MOCK else str(getattr(config, "source", "station"))
    path = history_path(args.against)

    def record() -> None:
        append_record(path, check_record(data, station))
        say(f"history: {path}")

    def report() -> None:
        history = load_history(path)
        if history.skipped:
            print(history.skipped_line(), file=sys.stderr)
        folder = outcome.folder
        if args.report:
            target = args.report
        elif folder is not None:
            target = str(folder / "verify_report.html")
        else:  # verify() always makes the check's folder
            raise HandEyeError("the check wrote no folder to put its report in: give --report FILE")
        say(f"report: {write_history_report(target, history, thresholds, data)}")

    _after_check(record, "the check was not added to the history")
    if args.json:
        write_text_atomic(args.json, json.dumps(data, indent=1) + "\n")
    if outcome.folder is not None and outcome.folder.is_dir():
        write_text_atomic(outcome.folder / "verify.json", json.dumps(data, indent=1) + "\n")
    if args.report is not None:
        _after_check(report, "no report was written")
    from ..plant.hooks import after_verify  # the plant's broker, when the config has plant:

    after_verify(args, config, data)
    return outcome.verdict


def _after_check(step, what: str) -> None:
    """Run one output step after the check: an error it raises is said in one line on stderr, and the
    check's verdict (its exit status) stands."""
    import sys

    from ...base import HandEyeError

    try:
        step()
    except HandEyeError as exc:
        print(f"{exc}: {what}; the verdict above stands", file=sys.stderr)


def _ask(question: str) -> bool:
    import sys

    if not sys.stdin.isatty():
        return False
    return input(question + " [y/N] ").strip().lower() in ("y", "yes")
