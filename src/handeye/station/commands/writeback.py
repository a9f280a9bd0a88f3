"""``handeye writeback``: write the calibrated camera frame into the robot's tooldata."""

from __future__ import annotations

import argparse

HELP = "write the session's calibrated camera frame into the robot's PERS tooldata, and read it back"

EPILOG = """\
The session is calibrated (recommended default, or --method) and judged against the quality
thresholds; a failed verdict is refused unless --force. The tool data (frame from the calibration,
mass and centre of gravity from the config's tool section) is validated: unit quaternion, frame
20-500 mm from the flange (thresholds min_camera_offset_mm, max_camera_offset_mm), mass > 0.
--dry-run prints the RAPID literal and stops. Otherwise the
controller's current tool data is saved in the session (a new tooldata_backup_*.yaml each time,
never overwritten), the new one is written, read back and compared to the last digit the
controller keeps (0.001 mm, 1e-6).

SESSION may also be the folder of a check (handeye verify, SESSION-verify-<time>) whose camera
moved: its quick update is written like a calibration, refused when its uncertainty is above the
quality thresholds (max_sigma_translation_mm, max_sigma_rotation_deg) unless --force; the write is
recorded in the history beside the sessions.

Only the controller is opened (the camera may be unplugged or on another PC). --config writes to
the real controller it names and fails with the reason when it cannot be reached; --mock writes to
the embedded mock station's controller, and the output says MOCK; so does a rehearsal config (its
controller is checked to be the standalone mock whose camera camera.mock_arm names). A session
captured on a mock station, or simulated, is never written to a real controller. If the link fails during the write,
the controller may hold either value: run the same command again; it reads back and says which.

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
    p.add_argument("--units", choices=("mm", "m"), default="mm",
                   help="length unit the session was written in (default mm; m converts on reading)")
    return p


def run(args) -> int:
    from ...base import UsageError
    from ...calibration import session_in_mm
    from ...calibration import read_session
    from ..report.assessment import assess
    from ..calibrate import solve_session
    from ..config.station import default_config, load_config
    from ..origin import MOCK, origin_line, session_origin
    from ..report.quality import config_thresholds
    from ..runtime import MOCK_BANNER, check_rehearsal, open_controller_link, rehearsal_banner
    from ..config.station_kind import station_kind
    from ..verify.update import record_update_written, verify_check
    from ..writeback import check_session_origin, side_by_side, writeback

    if not args.dry_run and not args.config and not args.mock:
        raise UsageError("give --config STATION.yaml (the real controller), --mock, or --dry-run")
    config = load_config(args.config) if args.config else default_config()
    if args.mock:
        config = config.as_mock()
    session = read_session(args.session)
    origin = session_origin(session)
    session = session_in_mm(session, args.units)
    mock_controller = station_kind(config) == MOCK  # the embedded mock, or a rehearsal's standalone one
    if not args.dry_run and config.is_rehearsal:
        check_rehearsal(config)  # the controller named is the standalone mock's: a mock session may go there
    if not args.dry_run:
        check_session_origin(origin, mock_controller)
    if origin_line(origin):
        print(origin_line(origin))
    check = verify_check(args.session)
    if check is not None:  # a check's folder: its quick update is the result, judged by its uncertainty
        result, passed, reason = check
        print(f"quick update of handeye verify: {reason}")
    else:
        assessment = assess(solve_session(session, args.session, args.method, origin=origin), config_thresholds(config))
        result, passed, reason = assessment.result, assessment.verdict.passed, assessment.verdict.line()
        print(f"calibration ({result.method}): {reason}")
    common = dict(verdict_passed=passed, verdict_reason=reason, force=args.force, origin=origin,
                  progress=lambda m: print(m, flush=True))
    if args.dry_run:
        outcome = writeback(args.session, config, result, None, dry_run=True, **common)
        print(outcome.literal)
        return 0
    if config.is_mock:
        print(MOCK_BANNER, flush=True)
    elif config.is_rehearsal:
        print(rehearsal_banner(config), flush=True)
    with open_controller_link(config, session_dir=args.session) as link:
        outcome = writeback(args.session, config, result, link.controller, mock_controller=mock_controller, **common)
    if check is not None:
        record_update_written(args.session, outcome)
    tag = "MOCK " if outcome.mock else ""
    print(side_by_side(outcome.old, outcome.new))
    print(outcome.literal)
    print(tag + ("read back: identical to the last digit the controller keeps" if outcome.readback_ok else "read back: DIFFERENT"))
    return 0
