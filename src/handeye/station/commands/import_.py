"""``handeye import``: other tools' hand-eye samples -> a session folder (handeye-session/1).

The module is ``import_`` because ``import`` is a Python keyword; ``cli.COMMANDS`` maps the command
name to it.
"""

from __future__ import annotations

import argparse

from . import argtypes
import sys

from .argtypes import Subcommands

HELP = "turn any hand-eye log (MoveIt, ViSP, camodocal, easy_handeye, streams, CSV/JSON/YAML tables) into a session"

EPILOG = """\
Formats (--format; detected from the files when omitted; src/handeye/station/importers/FORMATS.md has details):
  moveit        MoveIt Calibration pose_samples.json: [[T_base_eef, T_cam_target], ...], 4x4, metres
  visp          folder of ViSP pose_fPe_<i>.yaml (or <robot>_pose_rPe_<i>.yaml) + pose_cPo_<i>.yaml,
                [tx ty tz θux θuy θuz] metres/radians; an app folder of <robot>_image-<i>.png measures
                the chessboard (chessboard-data.txt, or --board/--square-mm) or an AprilTag
                (apriltag-data.txt, or --tag-mm)
  opencv        OpenCV FileStorage T1_<i> = end effector in base, T2_<i> = marker in camera (camodocal)
                (or camodocal's folder: its result file CalibratedTransform.yml is skipped and named)
  stream        two CSV streams "t,x,y,z,qx,qy,qz,qw": robot (hand in base) then camera (camera in
                target, the ETH layout); each camera sample pairs with the nearest robot stamp within
                --tolerance-ms; --max-postures keeps the slowest pair per time window;
                --rest-mm-s/--rest-deg-s keep only a hand at rest
  plain         CSV with a header: index,tool0_x,tool0_y,tool0_z,tool0_qw,tool0_qx,tool0_qy,tool0_qz,
                target_x,...,target_qz (tool0 in base, target in camera); or JSON {"postures": [...]}
  easy_handeye  easy_handeye2 .samples (YAML; calibration_type says the set-up)
  log           anything else: CSV/TSV/space tables with or without a header (one posture per row,
                or robot and camera poses in two blocks or two files, or matrices over 4 lines), JSON
                or YAML of any nesting. A pose is 16/12 numbers (matrix), 7 (position + quaternion)
                or 6 (position + rotation vector or Euler angles, any of the 24 conventions).
                The layout is searched too: rows tagged by a leading word or letter (hand/eye,
                robot:/camera:, P + three C rows of a 3x4), matrices over 3-4 rows (blank lines,
                count lines, sections), one file per side in any order, camera-calibration rows per
                image (the 3x3 that is a rotation and the translation beside it), extra columns;
                each reading is scored by the invariants and printed with the runner-up; when two
                fit within the noise, or the content cannot tell the robot's list, the import is
                refused naming --robot-rows. A JSON/YAML tool log: every pair of per-posture lists
                is scored, frame names ("camera to tool0", "attached on robot") hint the set-up,
                and the tool's own result is compared with ours in the output (never input)

The reading is inferred from the data and printed with a table of the candidates: the rotation
convention of each side, whether the robot poses are the flange in the base or the base in the
flange, the camera poses the target in the camera or the camera in the target, the set-up and the
units. Every reading is scored by the X-free invariants of AX = XB (relative rotation angles,
rotation axes, translations) and by plausibility (the camera or board on the flange is near it;
the board is in front of the camera); what the file says (MoveIt's T_cam_target, ViSP's cPo,
column names like qw or a b c) breaks ties. When the data cannot decide, the import is refused
naming the flag that does. Flags always win; a flag the data contradict is a warning with the
numbers:
  --robot-pose flange_in_base|base_in_flange     --camera-pose target_in_camera|camera_in_target
  --setup eye_in_hand|eye_to_hand                --units m|mm
  --quaternion-order wxyz|xyzw
  --euler SPEC: ZYX (uppercase: rotating axes) or xyz (lowercase: static axes), :deg or :rad;
    rotvec; rvec-tvec; or a vendor: abb (quaternion wxyz), kuka (A B C = ZYX rotating, deg),
    fanuc (W P R = XYZ static, deg), ur (rotation vector), ros (quaternion xyzw, RPY = XYZ static,
    rad), visp (theta-u), opencv (rvec, tvec); robot:SPEC or camera:SPEC for one side
The session is written in mm, quaternions (w, x, y, z); session.yaml keeps the conventions in words
and the candidates under import:.

The import checks the data and warns, one line each, about duplicated postures, stale board poses,
mixed units, board poses flipped 180 deg and gross outliers. calibrate checks the invariants again
and refuses a session no rigid camera mount fits.

Examples:
  handeye import pose_samples.json -o moveit_session
  handeye import TransformPairsInput.yml -o camodocal --format opencv
  handeye import hand.csv target.csv -o eth --format stream --tolerance-ms 20 --max-postures 30
  handeye import kuka_log.csv -o cell3                       # X Y Z A B C + camera rvec tvec, inferred
  handeye import robot.txt marker.txt -o cell4 --euler robot:kuka --camera-pose camera_in_target
  handeye import data-eye-to-hand/ -o visp_eth --tag-mm 120
"""


#: The importers' names (station.importers.FORMAT_NAMES; repeated here so that building the parser
#: imports nothing heavy; a test keeps the two equal).
FORMAT_NAMES = ("moveit", "visp", "opencv", "stream", "plain", "easy_handeye", "log")


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
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
    p.add_argument("--robot-rows", metavar="NAME",
                   help="which list holds the robot poses when the content cannot tell: its tag (hand, P, robot), "
                        "key or file name, or first/second in the file (log format; default: inferred)")
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


def run(args: argparse.Namespace) -> int:
    from ..import_session import ImportOptions, import_summary, import_to_session
    from ..importers.ambiguity import AmbiguousReading

    options = ImportOptions(
        sources=tuple(args.sources), output=args.output, format=args.format, setup=args.setup, units=args.units,
        quaternion_order=args.quaternion_order, board=args.board, square_mm=args.square_mm,
        skip_invalid=args.skip_invalid, overwrite=args.overwrite, robot_pose=args.robot_pose,
        camera_pose=args.camera_pose,
        format_options={
            "tolerance_s": None if args.tolerance_ms is None else args.tolerance_ms / 1000.0,
            "max_postures": args.max_postures, "rest_mm_s": args.rest_mm_s, "rest_deg_s": args.rest_deg_s,
            "robot_prefix": args.robot_prefix, "camera_prefix": args.camera_prefix, "euler": args.euler,
            "tag_mm": args.tag_mm, "robot_rows": args.robot_rows,
        },
    )
    try:
        outcome = import_to_session(options)
    except AmbiguousReading as exc:  # what each reading would give, so that the user can recognise theirs
        print("the readings the data cannot tell apart, with the flags that choose each and the camera mount it gives:")
        print("\n".join(f"  {line}" for line in exc.choices))
        raise
    for message in outcome.warnings:
        print(f"handeye import: warning: {message}", file=sys.stderr)
    print("\n".join(import_summary(outcome)))
    return 0
