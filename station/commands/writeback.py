"""``handeye writeback``: write the calibrated camera frame into the robot's tooldata."""

from __future__ import annotations

import argparse

HELP = "write the session's calibrated camera frame into the robot's PERS tooldata, and read it back"

EPILOG = """\
The session is calibrated (recommended default, or --method) and judged against the quality
thresholds; a failed verdict is refused unless --force. The tool data (frame from the calibration,
mass and centre of gravity from the config's tool section) is validated: unit quaternion, frame
within 1 m of the flange, mass > 0. --dry-run prints the RAPID literal and stops. Otherwise the
controller's current tool data is saved in the session (tooldata_backup_*.yaml), the new one is
written, read back and compared to the last digit the controller keeps (0.001 mm, 1e-6).

Examples:
  handeye writeback my_session --config station.yaml --dry-run
  handeye writeback my_session --config station.yaml
"""


def add_parser(sub):
    p = sub.add_parser("writeback", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", metavar="SESSION")
    p.add_argument("--config", metavar="STATION.yaml", help="station configuration (controller, tool mass, thresholds)")
    p.add_argument("--mock", action="store_true", help="write to the embedded mock controller")
    p.add_argument("--dry-run", action="store_true", help="print the RAPID literal only")
    p.add_argument("--force", action="store_true", help="write even when the quality verdict failed")
    p.add_argument("--method", metavar="NAME", help="calibration method (default: the recommended one)")
    return p


def run(args) -> int:
    from ...calibration.errors import HandEyeError
    from ...calibration.session import read_session
    from ...calibration.solve import calibrate, problem_from_session
    from ..config import default_config, load_config
    from ..demo import station_verdict
    from ..runtime import open_station
    from ..writeback import side_by_side, writeback

    if not args.dry_run and not args.config and not args.mock:
        raise HandEyeError("give --config STATION.yaml (the real controller), --mock, or --dry-run")
    config = load_config(args.config) if args.config else default_config()
    session = read_session(args.session)
    problem = problem_from_session(session)
    result = calibrate(problem, args.method)
    verdict = station_verdict(result, problem, config)
    print(f"calibration ({result.method}): {verdict.line()}")
    common = dict(verdict_passed=verdict.passed, verdict_reason=verdict.line(), force=args.force,
                  progress=lambda m: print(m, flush=True))
    if args.dry_run:
        outcome = writeback(args.session, config, result, None, dry_run=True, **common)
        print(outcome.literal)
        return 0
    with open_station(config, mock=args.mock or config.camera.backend == "mock") as link:
        outcome = writeback(args.session, config, result, link.controller, **common)
    print(side_by_side(outcome.old, outcome.new))
    print(outcome.literal)
    print("read back: identical to the last digit the controller keeps" if outcome.readback_ok else "read back: DIFFERENT")
    return 0
