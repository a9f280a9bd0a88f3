"""``handeye benchmark``: the paper's section-4 comparison, reproduced on synthetic data."""

from __future__ import annotations

import argparse

from . import argtypes
from .argtypes import Subcommands

HELP = "compare every method over sweeps of robot noise, camera noise, posture count and pose noise"

EPILOG = """\
Each trial draws its own IRB 1400 posture set around the 8x13 board and its own noise; every method
solves the same data. Written to OUTPUT: results.csv (one row per trial and method), summary.md
(median tables; means for pose_noise; for methods with an uncertainty, the RMS of error / one-sigma),
and one PNG per sweep (rotation/translation error to truth, d_org, d_back).

Sweeps (--sweep, any of them; default all four):
  sigma_cam   camera noise 0..20 mm (paper model), no robot noise
  sigma_rob   joint noise 0..0.4 deg, no camera noise
  postures    8..50 postures at 5 mm camera noise
  pose_noise  OpenCV's own hand-eye test model: random poses, board poses only, 0.002 rad / 5 mm
              noise on target2cam and 0.001 rad / 1 mm on gripper2base, 10 poses, 100 trials
              (--pose-trials), means

Examples:
  handeye benchmark -o benchmarks/paper                 # the full study (20 trials per cell)
  handeye benchmark -o /tmp/quick --quick               # a 2-minute smoke run
  handeye benchmark --sweep sigma_cam --methods mcb,robust,tsai,opencv_park --trials 30
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("benchmark", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--output", default="benchmark_results", help="output folder (default benchmark_results)")
    p.add_argument("--sweep", action="append", choices=("sigma_cam", "sigma_rob", "postures", "pose_noise"),
                   help="sweep to run (repeatable; default all)")
    p.add_argument("--trials", type=int, default=20, help="trials per cell (default 20)")
    p.add_argument("--pose-trials", type=int, default=100, help="trials of the pose_noise sweep (default 100)")
    p.add_argument("--methods", help="comma-separated method names (default: all, plus OpenCV's as opencv_<name>)")
    p.add_argument("--sigma-cam", type=argtypes.floats, metavar="LIST", help="camera noise values, mm")
    p.add_argument("--sigma-rob", type=argtypes.floats, metavar="LIST", help="joint noise values, deg")
    p.add_argument("--postures", type=argtypes.floats, metavar="LIST", help="posture counts")
    p.add_argument("--camera-noise", choices=("paper", "gaussian"), default="paper")
    p.add_argument("--no-opencv", action="store_true", help="leave OpenCV's methods out")
    p.add_argument("--no-plots", action="store_true")
    p.add_argument("--quick", action="store_true", help="3 trials, 3 values per sweep: a smoke run")
    p.add_argument("--seed", type=int, default=0)
    return p


def run(args: argparse.Namespace) -> int:
    from ...base import UsageError
    from ..benchmark import BenchmarkOptions, benchmark
    from ..progress import progress_bar

    options = BenchmarkOptions(output=args.output,
                               sweeps=tuple(args.sweep or ("sigma_cam", "sigma_rob", "postures", "pose_noise")),
                               trials=args.trials, camera_model=args.camera_noise, opencv=not args.no_opencv,
                               plots=not args.no_plots, seed=args.seed, pose_noise_trials=args.pose_trials)
    if args.quick:
        options = BenchmarkOptions(**{**options.__dict__, "trials": min(args.trials, 3), "sigma_cam_values": (0.0, 5.0, 20.0),
                                      "sigma_rob_values": (0.0, 0.1, 0.2), "postures_values": (10, 30),
                                      "pose_noise_trials": min(args.pose_trials, 10)})
    changes = {}
    if args.sigma_cam:
        changes["sigma_cam_values"] = args.sigma_cam
    if args.sigma_rob:
        changes["sigma_rob_values"] = args.sigma_rob
    if args.postures:
        if any(v < 3 or v != int(v) for v in args.postures):
            raise UsageError("--postures values must be whole numbers >= 3")
        changes["postures_values"] = tuple(int(v) for v in args.postures)
    if args.methods:
        changes["methods"] = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    if args.trials < 1 or args.pose_trials < 1:
        raise UsageError("--trials and --pose-trials must be at least 1")
    options = BenchmarkOptions(**{**options.__dict__, **changes})
    with progress_bar("benchmark") as update:
        summary = benchmark(options, update)
    print(f"{summary['rows']} results in {summary['folder']} ({summary['wall_s']:.0f} s): results.csv, summary.md"
          + (", " + ", ".join(p.split("/")[-1] for p in summary["plots"]) if summary["plots"] else ""))
    for method, (count, reason) in summary["failures"].items():
        print(f"{method}: {count} trial(s) not solved, left out of its medians (summary.md lists them): {reason}")
    return 0
