"""``handeye calibrate``: solve a session and print or write the camera pose."""

from __future__ import annotations

import argparse

HELP = "solve a session for the camera pose (cam2tool0, or cam2base eye-to-hand)"

EPILOG = """\
Methods (--method); without it the recommended default runs:
  robust  (default) mcb, then outlier postures detected and excluded, a robust refinement of the
          point consistency over the inliers, and a one-sigma uncertainty of the pose
The paper's variants (Deniz & Cakir):
  mc    all postures at once (Horn least squares over every pair; no selection)
  mcb   best triplet by back-projection d_back, eq. 23 (mean distance between the same board point
        seen from two postures)
  mco   best triplet by d_org, eq. 22 (mean distance to the mean point)
  mcr   best triplet by the rotation residual of AX = XB (eq. 16)
  mct   best triplet by the translation residual of AX = XB (eq. 16)
  mcy   best triplet by the distance to the true board points (synthetic sessions only)
Classic AX = XB solvers (calibration/classic/README.md says what each minimises):
  tsai, park, horaud, andreff, daniilidis, chou, lu, liang

The text report gives the pose as a RAPID tframe literal, the quality figures and each posture's
residual. --json FILE writes the machine-readable result ('-' for standard output).

Example:
  handeye calibrate my_session --method mcb --json result.json
"""


def add_parser(sub):
    p = sub.add_parser("calibrate", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", metavar="SESSION", help="session folder (handeye-session/1)")
    p.add_argument("--method", metavar="NAME", help="solver (see below); default: the recommended one")
    p.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' = stdout)")
    p.add_argument("--quiet", action="store_true", help="no text report (with --json FILE)")
    return p


def run(args) -> int:
    from ..calibrate import calibrate_session_folder
    from ..report_text import calibration_summary
    from ..output import write_json

    outcome = calibrate_session_folder(args.session, args.method)
    if args.json:
        write_json(args.json, outcome.result.to_json())
    if not args.quiet and args.json != "-":
        print(calibration_summary(outcome))
    return 0
