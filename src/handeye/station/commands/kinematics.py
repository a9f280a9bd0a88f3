"""``handeye kinematics export``: the identified arm as controller calibration values and a corrected program."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "the arm's kinematics identified with the camera: export joint offsets and a corrected RAPID program"

EPILOG = """\
handeye kinematics export SESSION -o OUT identifies the arm's deviations with the camera (as calibrate
--kinematics) and writes OUT/joint_offsets.txt (the zero offsets of the controller axes, where an
engineer enters them in the controller's calibration data: the exact parameter, unit and sign are in
the controller's manual; a maker's calibrated model, ABB's Absolute Accuracy option, is the supported
route) and OUT/kinematics.json. With
--program DIR, a corrected copy of the program's jointtargets and robtargets (robtargets taken as
tool0 in wobj0) in OUT/program, checked against the cell (--config STATION.yaml, else the built-in
station). Nothing is written to the controller. Refused when the zeros of J2-J5 are not identified.

  handeye kinematics export my_session -o kin_export --program my_program --config station.yaml
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("kinematics", help=HELP, description=HELP)
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    export = actions.add_parser("export", help=HELP, description=HELP, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    export.add_argument("session", metavar="SESSION", help="a captured session (joint angles recorded)")
    export.add_argument("-o", "--output", metavar="OUT", required=True, help="folder to write the export into")
    export.add_argument("--program", metavar="DIR", help="a RAPID program folder whose targets are corrected")
    export.add_argument("--config", metavar="STATION.yaml", help="station configuration for the cell checks")
    return p


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from ...base import UsageError
    from ..config.station import load_config
    from ..kinematics_export import export_kinematics

    if getattr(args, "action", None) != "export":
        raise UsageError("say what to do: handeye kinematics export SESSION -o OUT [--program DIR]")
    if args.program is not None and not Path(args.program).is_dir():
        raise UsageError(f"--program {args.program} is not a folder: give the RAPID program's folder")
    config = load_config(args.config) if args.config else None
    done = export_kinematics(args.session, args.output, args.program, config)
    for path in done["files"]:
        print(f"written: {path}")
    if done["targets_corrected"]:
        print(f"{done['targets_corrected']} targets corrected with the identified arm; all clear of the cell")
    print("nothing was written to the controller: enter the offsets by hand, or run the corrected program")
    return 0
