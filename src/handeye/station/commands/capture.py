"""``handeye capture``: guided posture capture into a session (resumable)."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "visit the planned postures (or the operator's, --guided), measure the board at each, write the session (resumes)"

EPILOG = """\
A new session: the robot must stand where the camera sees the whole board (about 0.9 m away; the
config's plan.start_joints_deg, or wherever it stands). The board is measured there, N postures are
planned around it (reachable with a margin, board in view of both cameras, rotation axes spread over
all directions, ordered for short moves), scored, and the RAPID program is written to SESSION/rapid.
Then, posture by posture: move (MoveAbsJ fine), read joints and flange pose (checked against the
kinematics), grab, triangulate, judge quality (retry or skip with the reason), write the posture
file atomically, acknowledge.

The plan keeps clear of the cell (the config's cell section: keep-out volumes, the floor, what the
flange carries, the board's stand): every posture and every move between two postures, sampled
along the joint-interpolated path MoveAbsJ runs, keeps the whole arm (links 1-3 and the
wrist) and the carried bodies cell.margin_mm away, and the robot file's self-collision pairs (the
camera against link 3, ...) as far apart; postures or moves that do not are replaced or
reordered, and the plan line says how many were rejected and why ("camera against link 3"). A start
posture inside (or within the margin of) a volume is refused. SESSION/preview.png shows the cell
from above and from the side with the arm, the flange path and the numbered postures; --plan-only writes the plan, the preview and the RAPID program and stops.

At a real station the first move waits for your yes (or --yes, for scripts); the mock says it moves
without asking.

--guided: for cells that calibrate by jogging. Over a line (socket or serial) and over Modbus the
capture writes and loads the guided RAPID program (SESSION/rapid, as rapid generate --guided): the
FlexPendant shows what the set still lacks (guided.prompt: fk = TPReadFK, messagebox = UIMessageBox);
press Capture, jog to a new posture with the board in view, press Start: the posture is captured,
or refused with the reason (too close to one captured, board not seen, within the margin of a
keep-out volume), and the pendant says what to do next, then GOOD ENOUGH; Done ends the run. Over
Robot Web Services no program is needed: the PC reads the joints and captures each time the arm
rests (guided.still_s) somewhere new. Either way the command says what is still missing (postures,
rotation-axis spread and which way to turn next, relative rotation angles, distance spread, where
in the image the board has not been); stop with Ctrl-C, the same command resumes. A run that ends
with fewer than 3 postures on disk (what a calibration needs) exits 1 and says what to do. With --mock
nobody holds a pendant: a simulated operator jogs the embedded arm (joints read, as over RWS)
through --postures N postures around the board (lines "MOCK operator (simulated): ..."), then ends
the run. A rehearsal (camera.mock_arm) is played through the standalone mock's --pendant-port.

--view: serve a live page while capturing (planned or guided) on 127.0.0.1, a free port, printed as
"live view: http://127.0.0.1:PORT/?token=..." (the token is new each run; a request without it gets
403). Open it in a browser at the station: the latest left and right images with the corners found
(and, once the postures allow a calibration, red crosses where it predicts them), live frames while
the robot moves, the board position in the 3x3 image grid, the rotation axes on a sphere with the
next turn as an arrow, the distance spread, the posture list with each posture's quality or why it
was skipped, what is still missing, the progress, GOOD ENOUGH, and for a planned capture the plan
with the current posture and the time left; when the run is over, FINISHED (or STOPPED) with the
last lines printed here. --view-host ADDRESS (IPv4 or IPv6, e.g. ::1) binds elsewhere (another
machine may then watch; warned). The page loads nothing from the internet.

Each posture is named by the number of its file (postures/NNN.yaml -> NNN, from 0) in these lines,
the preview, the RAPID program's comments (the controller's jtHePost<k> is posture k - 1) and by
calibrate and its report.

A config whose output names a folder (output: sessions) puts a relative --session DIR in it
(sessions/DIR, under the folder the command runs in); an absolute DIR, or one already starting with
that folder, is used as given.

Interrupted (Ctrl-C, kill, lost link)? Run the same command again: it resumes, and every posture
ends up on disk exactly once; a preview or RAPID modules the interruption left unwritten are
written then (what cannot be rebuilt is named in one line).

--config runs the real station it names (controller.protocol and camera.backend are required);
when the controller or the camera cannot be reached, capture stops with the reason: it never falls
back to the mock. --mock runs the embedded mock station (a simulated IRB 1400 behind a real
TCP/Modbus server and a simulated XB3 on its flange), with the config's settings if one is given;
so does a config whose controller.protocol and camera.backend are both mock. A rehearsal config
(camera.backend: mock with camera.mock_arm: HOST:PORT, the controller section pointing at
`handeye mock controller --camera-port PORT`) runs the real drivers against that standalone mock,
which executes the session's RAPID. Every line it prints then starts with MOCK, and the session
records that it came from a mock station.

Examples:
  handeye capture --mock --session cal_2026_11_21
  handeye capture --config station.yaml --session cal_2026_11_21 --plan-only   # look at preview.png
  handeye capture --config station.yaml --session cal_2026_11_21               # asks, then moves
  handeye capture --config station.yaml --session cal_2026_11_22 --guided      # you jog, it captures
  handeye calibrate cal_2026_11_21 --report
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("capture", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", metavar="STATION.yaml", help="station configuration (see src/handeye/station/config/example_station.yaml)")
    p.add_argument("--mock", action="store_true", help="use the embedded mock robot and camera")
    p.add_argument("--session", required=True, metavar="DIR", help="session folder (created, or resumed); a relative "
                   "one inside the config's output folder when it names one")
    p.add_argument("--postures", type=int, help="number of postures to plan (default: the config's, 30)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--plan-only", action="store_true", help="plan, write the preview and the RAPID program; move nothing")
    mode.add_argument("--guided", action="store_true",
                      help="the operator jogs: the guided RAPID program prompts on the pendant (over RWS and --mock: "
                           "capture whenever the arm rests somewhere new)")
    p.add_argument("--yes", action="store_true", help="move without asking (scripts; a real station asks otherwise)")
    p.add_argument("--view", action="store_true", help="serve a live page of the capture (URL with a token printed)")
    p.add_argument("--view-host", metavar="ADDRESS", help="with --view: listen on ADDRESS instead of 127.0.0.1 "
                   "(other machines may then reach the page; warned)")
    return p


def _view(config, args, link, say):
    """The live view's context (``station.view.live_view``) with --view, else one that yields None."""
    import contextlib

    from ...base import HandEyeError, UsageError

    if not args.view:
        if args.view_host:
            raise UsageError("--view-host needs --view")
        return contextlib.nullcontext()
    from ..view import live_view

    @contextlib.contextmanager
    def opened():
        try:
            context = live_view(config, link, args.session, host=args.view_host or "127.0.0.1", progress=say)
            view = context.__enter__()
        except OSError as exc:
            raise HandEyeError(f"the live view cannot listen on {args.view_host or '127.0.0.1'} ({exc.strerror or exc}): "
                               "give --view-host an address of this machine, or leave --view out") from None
        try:
            yield view
        finally:
            context.__exit__(None, None, None)

    return opened()


def _ask(question: str) -> bool:
    """The operator's yes at the terminal."""
    answer = input(f"{question} [y/N] ")
    return answer.strip().lower() in ("y", "yes")


def _confirmation(args):
    """How the first move is confirmed: --yes, a prompt at a terminal, or nothing (the capture refuses)."""
    import sys

    if args.yes:
        return lambda question: True
    return _ask if sys.stdin is not None and sys.stdin.isatty() else None


class _Say:
    """Prints a message a line, each after the station's tag (``MOCK `` on a mock station:
    ``station.config.station_kind``), from any thread (the mock's simulated operator speaks from its own)."""

    def __init__(self, config):
        import threading

        from ..config.station_kind import station_tag

        self.config, self.tag, self.lock = config, station_tag(config), threading.Lock()

    def __call__(self, message: str) -> None:
        with self.lock:
            print(self.tag + message, flush=True)

    def station(self, link):
        """Decide the tag again with the open link's parts (a driver may say it talks to a simulation); a link
        that makes a real config a mock station says so first, in one line. A context that does nothing more."""
        import contextlib

        from ..config.station_kind import mock_parts, station_tag

        tag = station_tag(self.config, link)
        if tag and not self.tag:
            print(f"MOCK: {'; '.join(mock_parts(self.config, link))}: a mock station; its sessions are recorded as "
                  "mock ones, never written to a real robot", flush=True)
        self.tag = tag
        return contextlib.nullcontext(link)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from ...base import UsageError
    from ..capture.loop import capture
    from ..config.station import default_config, load_config
    from ..progress import progress_bar
    from ..runtime import MOCK_BANNER, open_station, rehearsal_banner

    if not args.config and not args.mock:
        raise UsageError("give --config STATION.yaml for a real station or --mock for the embedded one")
    config = load_config(args.config) if args.config else default_config()
    if args.mock:
        config = config.as_mock()
    if args.postures is not None:
        if not 3 <= args.postures <= 255:
            raise UsageError(f"--postures must be between 3 and 255; got {args.postures}")
        config = replace(config, plan=replace(config.plan, postures=args.postures))
    args.session = str(config.session_folder(args.session))  # the config's output folder, when it names one
    say = _Say(config)
    if config.is_mock:
        print(MOCK_BANNER, flush=True)
    elif config.is_rehearsal:
        print(rehearsal_banner(config), flush=True)
    if args.guided:
        return _run_guided(config, args, say)
    with open_station(config, session_dir=args.session) as link, say.station(link), \
            _view(config, args, link, say) as view, progress_bar("capture") as update:
        def on_posture(report):
            say(("  ok    " if report.ok else "  SKIP  ") + report.message + f"  ({report.elapsed_s:.1f} s)")
            update(report.done, report.total, f"posture {report.index}")

        summary = capture(config, args.session, link, progress=say, on_posture=on_posture, plan_only=args.plan_only,
                          confirm=_confirmation(args), observer=None if view is None else view.observer)
        if args.plan_only:
            say((f"next: look at {summary.preview}, then " if summary.preview is not None else "next: ")
                + "the same command without --plan-only")
            return 0
        have = len(summary.captured) + len(summary.already)
        lines = [f"{have} of {summary.planned} postures in {summary.session} ({len(summary.captured)} this run, "
                 f"{summary.duration_s:.0f} s)"]
        if summary.skipped:
            lines.append(f"skipped: {', '.join(map(str, summary.skipped))}: run capture again to retry them")
        lines.append(f"next: handeye calibrate {summary.session} --report")
        _end(lines, say, view, ok=summary.complete or have >= 3)
    return 0 if summary.complete or have >= 3 else 1


def _end(lines: list, say, view, error: str | None = None, ok: bool | None = None) -> None:
    """Say the run's last lines, and show them on the live view (when open) in place of the next step, with
    ``error`` (the command's error line, said by the caller) and ``ok`` (default: no error)."""
    for line in lines:
        say(line)
    if view is not None:
        view.finish("; ".join(lines + ([error] if error else [])), error is None if ok is None else ok)


def _guided_ending(session, captured: int, already: int, what: str) -> tuple[list, str | None]:
    """The last lines of a guided run (``what``: what was captured and what is missing), and the error when
    the session holds fewer postures than a calibration needs (None: enough)."""
    from ...calibration import MIN_POSTURES

    total = captured + already
    if total == 0:
        return [what], (f"nothing was captured into {session}: no posture on disk (a calibration needs "
                        f"{MIN_POSTURES}); show the camera the whole board, about 0.9 m away, and run the same "
                        "command again")
    if total < MIN_POSTURES:
        return [what], (f"{total} posture{'s' if total != 1 else ''} on disk in {session}: a calibration needs "
                        f"{MIN_POSTURES}; run the same command to add more")
    return [what, f"next: handeye calibrate {session} --report"], None


def _run_guided(config, args, say) -> int:
    import threading

    from ...base import HandEyeError
    from ..guided.capture import guided_capture
    from ..guided.pendant import pendant_guided_capture, uses_guided_program
    from ..guided.operator import mock_operator
    from ..runtime import open_station

    stop = threading.Event()  # the embedded mock's simulated operator sets it when done
    with open_station(config, session_dir=args.session) as link, say.station(link), \
            _view(config, args, link, say) as view, mock_operator(config, link, stop, say) as operator:
        def on_posture(report):
            say("  ok    " + report.message)
            if operator is not None:
                operator.captured(report)

        try:
            observer = None if view is None else view.observer
            if uses_guided_program(config, link):
                summary = pendant_guided_capture(config, args.session, link, progress=say, on_posture=on_posture,
                                                 stop=stop, observer=observer)
            else:
                summary = guided_capture(config, args.session, link, progress=say, on_posture=on_posture, stop=stop,
                                         observer=observer)
            lines, error = _guided_ending(summary.session, len(summary.captured), summary.already,
                                          f"{len(summary.captured)} postures captured this run ({summary.already} "
                                          "before); " + ("good enough" if summary.good_enough else "still missing: "
                                                         + "; ".join(m.line() for m in summary.missing)))
        except KeyboardInterrupt:
            lines, error = _guided_ending(args.session, _postures_on_disk(args.session), 0,
                                          f"stopped; the postures on disk stay in {args.session}: run the same "
                                          "command to add more")
        _end(lines, say, view, error)
    if error is not None:
        raise HandEyeError(error)
    return 0


def _postures_on_disk(session) -> int:
    """How many postures the session folder holds (0 when it holds no session)."""
    from pathlib import Path

    from ...calibration import read_session

    return len(read_session(session).postures) if (Path(session) / "session.yaml").is_file() else 0
