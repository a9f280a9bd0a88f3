"""``handeye cell check``: a program's robot targets checked against the cell and against the arm itself."""

from __future__ import annotations

import argparse
import sys

from .argtypes import Subcommands

HELP = "check robot targets (axis angles) against the cell's keep-out volumes and the arm's own links"

EPILOG = """\
JOINTS.csv holds one posture a line: the robot's axis angles in deg (a1, ..., a6 for the IRB 1400),
comma-separated, finite numbers (no nan/inf, no digit separators such as 1_000); blank lines and
# comments are skipped, and so is one header line before the first row, only if none of its fields
looks like a number (a1,a2,...: the output says which line it took as the header; a first row with a
typo is refused, never skipped). Each row is checked as the
planner checks a posture: every link of the arm (base, links 1-3, the wrist) and what the flange
carries (cell.carried) against every keep-out volume (cell.keep_out), and the robot file's
self-collision pairs (the camera against link 3, link 4 against link 1, ...), all within
cell.margin_mm. With --moves each joint-interpolated move (MoveAbsJ, MoveJ) between consecutive rows
is checked too, sampled as the planner samples it (cell.path_step_mm). The board's stand is not
checked (its pose comes from a capture). The planner, the mock arm and this command call the same check.

For each row and move: clear, or the closest pair (body - volume, or body - body) and the distance
(negative: inside). Exit status: 0 all clear, 3 any not clear, 1 errors, 2 usage errors.

--json FILE writes {"clear": ..., "margin_mm": ..., "header_line": n or null, "postures": [{"row": i, "line": n, "clear": true|false,
"closest": "camera - link 3", "distance_mm": d, "kind": "cell"|"self"|"limits", "text": ...}],
"moves": [{"from_row": i, "to_row": i + 1, "clear": ..., "closest": ..., "distance_mm": ..., "at": s, ...}]}
(row 0-based; at: the fraction of the move where it comes closest, or first too close).

Examples:
  handeye cell check --config station.yaml targets.csv
  handeye cell check --config station.yaml targets.csv --moves --json check.json
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("cell", help=HELP, description=HELP)
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    check = actions.add_parser("check", help=HELP, description=HELP, epilog=EPILOG,
                               formatter_class=argparse.RawDescriptionHelpFormatter)
    check.add_argument("joints", metavar="JOINTS.csv", help="axis angles (deg), one posture a line")
    check.add_argument("--config", metavar="STATION.yaml", help="station configuration (its cell section and robot); "
                       "default: the built-in station")
    check.add_argument("--moves", action="store_true", help="check the moves between consecutive rows too")
    check.add_argument("--json", metavar="FILE", help="write every verdict as JSON ('-': standard output)")
    return p


def run(args: argparse.Namespace) -> int:
    from ...base import UsageError
    from ...robot import load_robot
    from ..cell.plan import cell_check
    from ..cell.check import check_joints, read_joints_csv
    from ..config.station import default_config, load_config
    from ..output import check_output_file, write_json

    if getattr(args, "action", None) != "check":
        raise UsageError("say what to do: handeye cell check --config STATION.yaml JOINTS.csv [--moves] [--json FILE]")
    if args.json:
        check_output_file(args.json)
    config = load_config(args.config) if args.config else default_config()
    robot = load_robot(config.robot)
    joints, lines, header = read_joints_csv(args.joints, robot.dof)
    result = check_joints(robot, cell_check(config).guard(robot), joints, lines, moves=args.moves)
    if header is not None:  # said on stderr when the JSON goes to standard output
        print(f"line {header[0]} taken as a header (no number in it), not checked: {header[1][:60]!r}",
              file=sys.stdout if args.json != "-" else sys.stderr)
    if args.json != "-":
        print("\n".join(result.lines()))
    if args.json:
        write_json(args.json, {**result.to_dict(), "header_line": None if header is None else header[0]})
    return 0 if result.clear else 3
