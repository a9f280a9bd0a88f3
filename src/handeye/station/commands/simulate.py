"""``handeye simulate``: a synthetic session like the paper's section 4, with its truth."""

from __future__ import annotations

import argparse

from ..simulate import MAX_POSTURES, SimulateOptions
from . import argtypes
from .argtypes import Subcommands

HELP = "write a synthetic session (IRB 1400, 13x8 board, chosen noise) with its truth"

EPILOG = """\
The postures are reachable IRB 1400 configurations from which the camera sees the whole board at
0.7-1.2 m, with the board placed anywhere in the image. Noise as in the paper:
  --sigma-rob  N(0, sigma) degrees on every reported joint angle (the flange pose follows)
  --sigma-cam  each corner moves by N(0, sigma) mm along a random direction U/|U|, U in [-1,1]^3
               (--camera-noise gaussian: N(0, sigma) on each coordinate instead)
The truth (camera mount and board pose) is written to SESSION/truth.yaml; `handeye calibrate`
reads it and reports the errors against it.

Example:
  handeye simulate -o s5 --sigma-cam 5 && handeye calibrate s5
"""


WHY = " (a calibration uses 15-60 postures; sampling takes about 0.05 s each)"


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("simulate", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--output", required=True, metavar="SESSION", help="session folder to create")
    p.add_argument("--postures", type=argtypes.whole_between(3, MAX_POSTURES, WHY), default=30,
                   help=f"number of postures, 3..{MAX_POSTURES} (default 30)")
    p.add_argument("--sigma-rob", type=argtypes.non_negative, default=0.0, metavar="DEG", help="joint-angle noise, degrees (default 0)")
    p.add_argument("--sigma-cam", type=argtypes.non_negative, default=0.0, metavar="MM", help="camera point noise, mm (default 0)")
    p.add_argument("--camera-noise", choices=("paper", "gaussian"), default="paper", help="camera noise model (default paper)")
    p.add_argument("--joint-offset", type=argtypes.floats, default=None, metavar="A1,..,An",
                   help="systematic offset added to every reported joint angle, degrees (one value per robot axis)")
    p.add_argument("--setup", choices=("eye_in_hand", "eye_to_hand"), default="eye_in_hand")
    p.add_argument("--corners", type=argtypes.corners, default=SimulateOptions.corners, metavar="NXxNY",
                   help="inner corners (default {}x{})".format(*SimulateOptions.corners))
    p.add_argument("--square-mm", type=float, default=30.0, help="square size in mm (default 30)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.add_argument("--scene-seed", type=int, default=0, help="posture-set seed (default 0)")
    p.add_argument("--overwrite", action="store_true", help="replace a session already in the folder")
    return p


def run(args: argparse.Namespace) -> int:
    from ..simulate import SimulateOptions, simulate_session

    options = SimulateOptions(
        output=args.output, postures=args.postures, sigma_rob_deg=args.sigma_rob, sigma_cam_mm=args.sigma_cam,
        camera_noise=args.camera_noise, joint_offset_deg=args.joint_offset, setup=args.setup,
        corners=args.corners, square_mm=args.square_mm, seed=args.seed, scene_seed=args.scene_seed,
        overwrite=args.overwrite,
    )
    path = simulate_session(options, progress=print)
    print(f"session written to {path}; next: handeye calibrate {path}")
    return 0
