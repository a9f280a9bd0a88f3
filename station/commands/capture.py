"""``handeye capture``: guided posture capture into a session (resumable)."""

from __future__ import annotations

import argparse

HELP = "visit the planned postures, measure the board at each, and write the session (resumes)"

EPILOG = """\
A new session: the robot must stand where the camera sees the whole board (about 0.9 m away; the
config's plan.start_joints_deg, or wherever it stands). The board is measured there, N postures are
planned around it (reachable with a margin, board in view of both cameras, rotation axes spread over
all directions, ordered for short moves), scored, and the RAPID program is written to SESSION/rapid.
Then, posture by posture: move (MoveAbsJ fine), read joints and flange pose (checked against the
kinematics), grab, triangulate, judge quality (retry or skip with the reason), write the posture
file atomically, acknowledge.

Interrupted (Ctrl-C, kill, lost link)? Run the same command again: it resumes, and every posture
ends up on disk exactly once.

--config runs the real station it names (controller.protocol and camera.backend are required);
when the controller or the camera cannot be reached, capture stops with the reason: it never falls
back to the mock. --mock runs the embedded mock station (a simulated IRB 1400 behind a real
TCP/Modbus server and a simulated XB3 on its flange), with the config's settings if one is given;
so does a config whose controller.protocol and camera.backend are both mock. Every line it prints
then starts with MOCK, and the session records that it came from the mock station.

Examples:
  handeye capture --mock --session cal_2026_11_21
  handeye capture --config station.yaml --session cal_2026_11_21
  handeye calibrate cal_2026_11_21 --report
"""


def add_parser(sub):
    p = sub.add_parser("capture", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", metavar="STATION.yaml", help="station configuration (see station/example_station.yaml)")
    p.add_argument("--mock", action="store_true", help="use the embedded mock robot and camera")
    p.add_argument("--session", required=True, metavar="DIR", help="session folder (created, or resumed)")
    p.add_argument("--postures", type=int, help="number of postures to plan (default: the config's, 30)")
    return p


def run(args) -> int:
    from dataclasses import replace

    from ...calibration.errors import HandEyeError
    from ..capture import capture
    from ..config import default_config, load_config
    from ..progress import progress_bar
    from ..runtime import MOCK_BANNER, open_station

    if not args.config and not args.mock:
        raise HandEyeError("give --config STATION.yaml for a real station or --mock for the embedded one")
    config = load_config(args.config) if args.config else default_config()
    if args.mock:
        config = config.as_mock()
    if args.postures is not None:
        if not 3 <= args.postures <= 255:
            raise HandEyeError(f"--postures must be between 3 and 255; got {args.postures}")
        config = replace(config, plan=replace(config.plan, postures=args.postures))
    tag = "MOCK " if config.is_mock else ""
    say = lambda message: print(tag + message, flush=True)  # noqa: E731
    if config.is_mock:
        print(MOCK_BANNER, flush=True)
    with open_station(config) as link, progress_bar("capture") as update:
        def on_posture(report):
            say(("  ok    " if report.ok else "  SKIP  ") + report.message + f"  ({report.elapsed_s:.1f} s)")
            update(report.k, report.total, f"posture {report.k}/{report.total}")

        summary = capture(config, args.session, link, progress=say, on_posture=on_posture)
    have = len(summary.captured) + len(summary.already)
    say(f"{have} of {summary.planned} postures in {summary.session} ({len(summary.captured)} this run, "
        f"{summary.duration_s:.0f} s)")
    if summary.skipped:
        say(f"skipped: {', '.join(map(str, summary.skipped))}: run capture again to retry them")
    say(f"next: handeye calibrate {summary.session} --report")
    return 0 if summary.complete or have >= 3 else 1
