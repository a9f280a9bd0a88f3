"""``handeye writeback``: write the calibrated camera frame into the robot's tooldata."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "write the session's calibrated camera frame into the robot's PERS tooldata, and read it back"

EPILOG = """\
The session's saved result (SESSION/result.yaml, written by handeye calibrate) is written: the pose the
report showed, never a new solve. A result older than the session's postures (postures added, removed
or edited since) is refused: run handeye calibrate SESSION. A session without result.yaml is solved
with the recommended method (or --method), the output says so, and the result is saved first;
--method with a result of another method is refused (calibrate with that --method first). The result
is judged against the config's quality thresholds; a failed verdict is refused unless --force. The tool data (frame from the calibration,
mass and centre of gravity from the config's tool section) is validated: unit quaternion, frame
20-500 mm from the flange (thresholds min_camera_offset_mm, max_camera_offset_mm), mass > 0.
--dry-run prints the RAPID literal and stops. Otherwise the
controller's current tool data is saved in the session (a new tooldata_backup_*.yaml each time,
never overwritten), the new one is written, read back and compared to the last digit the
controller keeps (0.001 mm, 1e-6).

SESSION may also be the folder of a check (handeye verify, SESSION-verify-<time>) whose camera
moved: its quick update is written like a calibration, refused when its uncertainty is above the
quality thresholds (max_sigma_translation_mm, max_sigma_rotation_deg) unless --force; the write is
recorded in the history beside the sessions (so is every write-back: handeye verify follows the
latest one).

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


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("writeback", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", metavar="SESSION")
    p.add_argument("--config", metavar="STATION.yaml", help="station configuration (controller, tool mass, thresholds)")
    p.add_argument("--mock", action="store_true", help="write to the embedded mock controller")
    p.add_argument("--dry-run", action="store_true", help="print the RAPID literal only")
    p.add_argument("--force", action="store_true", help="write even when the quality verdict failed")
    p.add_argument("--method", metavar="NAME", help="the method the saved result must hold (default: whichever calibrate saved)")
    p.add_argument("--units", choices=("mm", "m"), default="mm",
                   help="length unit the session was written in (default mm; m converts on reading)")
    return p


def run(args: argparse.Namespace) -> int:
    from ...base import UsageError
    from ..writeback_flow import WritebackRequest, run_writeback

    if not args.dry_run and not args.config and not args.mock:
        raise UsageError("give --config STATION.yaml (the real controller), --mock, or --dry-run")
    return run_writeback(WritebackRequest(args.session, args.config, args.mock, args.dry_run, args.force, args.method,
                                          args.units))
