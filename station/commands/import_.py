"""``handeye import``: other tools' hand-eye samples -> a session folder (handeye-session/1).

The module is ``import_`` because ``import`` is a Python keyword; ``cli.COMMANDS`` maps the command
name to it.
"""

from __future__ import annotations

import argparse

from . import argtypes
import sys

HELP = "turn MoveIt, ViSP, OpenCV/camodocal, easy_handeye, CSV stream or plain CSV/JSON samples into a session"

EPILOG = """\
Formats (--format; detected from the files when omitted):
  moveit        MoveIt Calibration pose_samples.json: [[T_base_eef, T_cam_target], ...], 4x4, metres
  visp          folder of ViSP pose_fPe_<i>.yaml (or <robot>_pose_rPe_<i>.yaml) + pose_cPo_<i>.yaml,
                [tx ty tz θux θuy θuz] metres/radians
  opencv        OpenCV FileStorage T1_<i> = end effector in base, T2_<i> = marker in camera (camodocal)
  stream        two CSV streams "t,x,y,z,qx,qy,qz,qw": robot (hand in base) then camera (default: camera
                in target, the ETH layout; --camera-pose target_in_camera otherwise); each camera sample
                pairs with the nearest robot stamp within --tolerance-ms; --max-postures keeps the
                slowest pair per time window; --rest-mm-s/--rest-deg-s keep only a hand at rest
  plain         CSV with a header: index,tool0_x,tool0_y,tool0_z,tool0_qw,tool0_qx,tool0_qy,tool0_qz,
                target_x,...,target_qz (tool0 in base, target in camera; q1..q4 columns follow
                --quaternion-order); or JSON {"postures": [{"tool0_in_base": {"position": [..],
                "quaternion": [..]}, "target_in_camera": {"matrix": [[..4x4..]]}}, ...]}
  easy_handeye  easy_handeye2 .samples (YAML; calibration_type sets the set-up)

Set-up: --setup wins; else what the file says; else the data decide when they fit one set-up
clearly better (relative rotation axes); else the format's default (moveit, opencv: eye_to_hand;
others: eye_in_hand). Units: --units wins; else each side is detected from its values (median
length under 20 -> metres). The session is written in mm, quaternions (w, x, y, z).

The import checks the data and warns, one line each, about duplicated postures, stale board poses,
mixed units, board poses flipped 180 deg, gross outliers, and a set-up the data contradict.

Examples:
  handeye import pose_samples.json -o moveit_session
  handeye import TransformPairsInput.yml -o camodocal --format opencv
  handeye import hand.csv target.csv -o eth --format stream --tolerance-ms 20 --max-postures 30
  handeye import poses.csv -o mine --units mm --board 13x8 --square-mm 30
"""


#: The importers' names (station.importers.FORMAT_NAMES; repeated here so that building the parser
#: imports nothing heavy; a test keeps the two equal).
FORMAT_NAMES = ("moveit", "visp", "opencv", "stream", "plain", "easy_handeye", "log")


def add_parser(sub):
    p = sub.add_parser("import", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sources", nargs="+", metavar="SOURCE", help="input file(s) or folder")
    p.add_argument("-o", "--output", required=True, metavar="SESSION", help="session folder to create")
    p.add_argument("--format", choices=FORMAT_NAMES, help="input format (default: detected)")
    p.add_argument("--setup", choices=("eye_in_hand", "eye_to_hand"), help="force the set-up (default: inferred)")
    p.add_argument("--units", choices=("m", "mm"), help="length unit of the input (default: inferred)")
    p.add_argument("--robot-pose", choices=("flange_in_base", "base_in_flange"),
                   help="what the robot poses are (default: inferred)")
    p.add_argument("--camera-pose", choices=("target_in_camera", "camera_in_target"),
                   help="what the camera poses are (default: inferred)")
    p.add_argument("--euler", action="append", metavar="SPEC",
                   help="rotation convention of 6-number poses: ZYX (rotating axes) / xyz (static axes) with :deg or "
                        ":rad, rotvec, rvec-tvec, or a vendor: abb, kuka, fanuc, ur, ros, visp, opencv; robot:SPEC or "
                        "camera:SPEC for one side (log format; default: inferred)")
    p.add_argument("--quaternion-order", choices=("wxyz", "xyzw"),
                   help="quaternion order of 7-number poses (default: inferred; names such as qw decide)")
    p.add_argument("--board", type=argtypes.corners, metavar="NXxNY", help="target inner corners, e.g. 9x6 (optional)")
    p.add_argument("--square-mm", type=argtypes.positive, metavar="MM", help="target square size in mm (with --board)")
    p.add_argument("--skip-invalid", action="store_true", help="drop malformed entries (reported) instead of stopping")
    p.add_argument("--overwrite", action="store_true", help="replace a session already in the folder")
    stream = p.add_argument_group("stream options")
    stream.add_argument("--tolerance-ms", type=argtypes.positive, metavar="MS", help="largest stamp difference of a pair (default 30)")
    stream.add_argument("--max-postures", type=argtypes.count, metavar="N",
                        help="keep the slowest pair in each of N time windows (default 40; 0 = keep all)")
    stream.add_argument("--rest-mm-s", type=argtypes.positive, metavar="V", help="keep only pairs with the hand slower than V mm/s")
    stream.add_argument("--rest-deg-s", type=argtypes.positive, metavar="W", help="keep only pairs with the hand turning slower than W deg/s")
    visp = p.add_argument_group("visp options")
    visp.add_argument("--tag-mm", type=argtypes.positive, metavar="MM",
                      help="app folder with images of an AprilTag 36h11: the tag's side in mm (its black square)")
    opencv = p.add_argument_group("opencv options")
    opencv.add_argument("--robot-prefix", metavar="NAME", help="robot matrices are NAME_<i> (default T1)")
    opencv.add_argument("--camera-prefix", metavar="NAME", help="camera matrices are NAME_<i> (default T2)")
    return p


def run(args) -> int:
    from ..import_session import ImportOptions, import_summary, import_to_session

    options = ImportOptions(
        sources=tuple(args.sources), output=args.output, format=args.format, setup=args.setup, units=args.units,
        quaternion_order=args.quaternion_order, board=args.board, square_mm=args.square_mm,
        skip_invalid=args.skip_invalid, overwrite=args.overwrite, robot_pose=args.robot_pose,
        camera_pose=args.camera_pose,
        format_options={
            "tolerance_s": None if args.tolerance_ms is None else args.tolerance_ms / 1000.0,
            "max_postures": args.max_postures, "rest_mm_s": args.rest_mm_s, "rest_deg_s": args.rest_deg_s,
            "robot_prefix": args.robot_prefix, "camera_prefix": args.camera_prefix, "euler": args.euler,
            "tag_mm": args.tag_mm,
        },
    )
    outcome = import_to_session(options)
    for message in outcome.warnings:
        print(f"handeye import: warning: {message}", file=sys.stderr)
    print("\n".join(import_summary(outcome)))
    return 0
