"""``handeye stereo``: calibrate the stereo head (``calibrate``), or turn its factory (Triclops)
calibration into a stereo file (``triclops``)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, cast

from ...geometry import STATION_CORNERS, STATION_SQUARE_MM
from . import argtypes
from .argtypes import Subcommands

HELP = "calibrate the stereo head from checkerboard pairs, or read its factory (Triclops) calibration"

CALIBRATE_HELP = "calibrate the stereo head from checkerboard image pairs (files or live) -> STEREO.yaml"

CALIBRATE_EPILOG = """\
Pairs, one of:
  --images FOLDER              pairs named alike but for left/right: 000_left.png + 000_right.png,
                               left/01.png + right/01.png, ... (a capture session's images/ too)
  --left 'L*.png' --right 'R*.png'
                               glob patterns (quote them); paired by the part of the name that is
                               not left/right, else in sorted order
  --camera xb3|mock            live from the camera; after each view the command says where to hold
                               the board next (the empty cells of a 3x3 grid of each image, and the
                               tilts still missing: facing, each edge nearer by 20-45 deg) until the
                               coverage is complete and --pairs pairs are in (--save-images DIR keeps
                               them; 'mock' runs the simulated XB3 with a simulated operator)
Ctrl-C stops a live capture; the pairs written with --save-images calibrate later with --images DIR.
Left = camera 1 = the project's 'camera' frame. If the images given as left are the right camera's,
the command says so and stops (a left camera sees every point further right than the right one, so
the board's columns tell; and T must point to the right camera): rerun with --swap.

What it does: the board is found in every image (the detector falls back from its quick search to
OpenCV's full one and findChessboardCornersSB; corners moved off the board's grid by glare are left
out); each camera is calibrated alone (cv2.calibrateCamera, every view it saw), views whose RMS
error is over 3x the median (and over 0.5 px) are dropped with the reason; then the pair
(cv2.stereoCalibrate with the intrinsics fixed, pairs far above the median dropped), then a joint
refinement kept when it helps (--no-refine skips it).

Writes (a folder on the way is created):
  -o STEREO.yaml        OpenCV FileStorage: image_width, image_height, K1, D1, K2, D2, R, T (T in mm,
                        X2 = R X1 + T), plus rms_px, epipolar_rms_px, baseline_mm as notes; the file
                        'handeye triangulate --stereo' and the station config's camera.stereo_model read
  STEREO.json           (or --report FILE) every figure, every pair's use and the reasons
  STEREO_coverage.png   (or --coverage-map FILE) where the board was in both images, and its tilts
Printed: RMS reprojection error (px), epipolar error (px: how far matched corners lie from each
other's epipolar lines; a good head has ~0.1 px), baseline (mm), the cells and tilts still empty.
Good numbers: RMS and epipolar error under 0.3 px, every cell covered; a baseline far from your head's
(an XB3 wide pair: ~240 mm) means a wrong --square-mm.

--factory FILE compares the result with the head's factory calibration (see 'handeye stereo triclops
--help' for the files read).

Examples:
  handeye stereo calibrate --images cal_pairs --board 13x8 --square-mm 30 -o xb3.yaml
  handeye stereo calibrate --left 'cal/L_*.png' --right 'cal/R_*.png' --board 9x6 --square-mm 25 -o s.yaml
  handeye stereo calibrate --camera xb3 --pairs 20 --save-images cal_pairs -o xb3.yaml
  handeye triangulate --left 000_left.png --right 000_right.png --stereo xb3.yaml --json -
"""

TRICLOPS_HELP = "write the factory (Triclops) rectified model as a stereo file"

TRICLOPS_EPILOG = """\
A Bumblebee's factory calibration is a Triclops file whose lens model (warp grids) has no OpenCV
equivalent; what converts is Triclops' RECTIFIED pinhole model: one focal length, one image centre
and the baseline, no distortion. It is exact for images rectified by Triclops, and a nominal model
for raw frames (a head of your own calibration, 'handeye stereo calibrate', is better).

FILE is one of:
  a Triclops .cal file (text): the header lines used are
      SensorResolution W H        FocalLength f/W f/H       ImageCenter cx/W cy/H     BaseLine metres
  a YAML or INI file of the values Triclops' API gives for a rectified resolution:
      image_width: 1280           image_height: 960
      focal_length: 983.0         # triclopsGetFocalLength (pixels)
      center_row: 493.4           # triclopsGetImageCenter(context, &row, &col): ROW first
      center_col: 643.6
      baseline: 0.23998           # triclopsGetBaseline (metres); or baseline_mm: 239.98
    (values of at most 1 for the centre, below 10 for the focal length, are read as fractions of
    the image size, as some Triclops versions give them)

--size WxH scales the model to another image size (and gives the size when the file has none).

Example:
  handeye stereo triclops bumblebee_12345.cal -o factory.yaml
  handeye triangulate --left l.png --right r.png --stereo factory.yaml --json -
"""


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must look like 1280x960; got {text!r}") from None
    if w < 16 or h < 16:
        raise argparse.ArgumentTypeError(f"size must be at least 16x16; got {text}")
    return w, h


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("stereo", help=HELP, description=HELP)
    targets = p.add_subparsers(dest="stereo_action", metavar="ACTION")
    c = targets.add_parser("calibrate", help=CALIBRATE_HELP, description=CALIBRATE_HELP, epilog=CALIBRATE_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    src = c.add_argument_group("pairs (one source)")
    src.add_argument("--images", metavar="FOLDER", help="folder of pairs (*left* / *right*)")
    src.add_argument("--left", metavar="'GLOB'", help="left images (quoted glob pattern)")
    src.add_argument("--right", metavar="'GLOB'", help="right images (quoted glob pattern)")
    src.add_argument("--camera", metavar="BACKEND", help="live capture from a camera back end (xb3, mock)")
    c.add_argument("--board", metavar="NXxNY", type=argtypes.corners_or_target, default=STATION_CORNERS,
                   help="inner corners, long side first (default {}x{}), or charuco[:keys] (partial views by corner id)".format(
                       *STATION_CORNERS))
    c.add_argument("--square-mm", metavar="MM", type=argtypes.positive, default=STATION_SQUARE_MM,
                   help=f"square size in mm (default {STATION_SQUARE_MM:g}): sets the scale of T")
    c.add_argument("-o", "--output", metavar="STEREO.yaml", required=True, help="stereo model to write")
    c.add_argument("--report", metavar="FILE.json", help="JSON report (default: STEREO.json beside the output)")
    c.add_argument("--coverage-map", metavar="FILE.png", help="coverage map (default: STEREO_coverage.png)")
    c.add_argument("--swap", action="store_true", help="the images given as left are the right camera's")
    c.add_argument("--distortion", choices=("k1k2p1p2k3", "k1k2p1p2", "rational"), default="k1k2p1p2k3",
                   help="lens distortion model (default k1k2p1p2k3, OpenCV's default; k1k2p1p2 for few views)")
    c.add_argument("--no-refine", action="store_true", help="skip the joint refinement of intrinsics and extrinsics")
    c.add_argument("--factory", metavar="FILE", help="Triclops factory calibration to compare with")
    c.add_argument("--pairs", type=argtypes.whole_between(5, 500), default=20, metavar="N",
                   help="live: pairs to collect at least (default 20)")
    c.add_argument("--max-grabs", type=argtypes.whole_between(10, 100000), default=600, metavar="N",
                   help="live: frames to grab at most (default 600)")
    c.add_argument("--save-images", metavar="DIR", help="live: write the accepted pairs here")
    c.add_argument("--seed", type=int, default=None, help=argparse.SUPPRESS)  # the mock camera's and operator's
    t = targets.add_parser("triclops", help=TRICLOPS_HELP, description=TRICLOPS_HELP, epilog=TRICLOPS_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    t.add_argument("file", metavar="FILE", help="Triclops .cal file, or YAML/INI with the rectified values")
    t.add_argument("-o", "--output", metavar="STEREO.yaml", required=True, help="stereo model to write")
    t.add_argument("--size", type=_size, metavar="WxH", help="image size of the model (default: the file's)")
    p.set_defaults(_stereo_parser=p)
    return p


def _calibrate(args) -> int:
    from pathlib import Path

    from ...base import UsageError
    from ...drivers import as_board
    from ..progress import progress_bar
    from ..stereo_from_pairs import StereoCalibrationConfig, run_stereo_calibration

    sources = sum(bool(x) for x in (args.images, args.left or args.right, args.camera))
    if sources != 1:
        raise UsageError("give one source of pairs: --images FOLDER, --left and --right patterns, or --camera")
    if bool(args.left) != bool(args.right):
        raise UsageError("give both --left and --right patterns")
    config = StereoCalibrationConfig(
        output=Path(args.output), board=_stereo_board(args.board, args.square_mm),
        images=Path(args.images) if args.images else None, left=args.left, right=args.right, camera=args.camera,
        pairs=args.pairs, max_grabs=args.max_grabs, save_images=Path(args.save_images) if args.save_images else None,
        swap=args.swap, distortion=args.distortion, refine=not args.no_refine,
        factory=Path(args.factory) if args.factory else None,
        report=Path(args.report) if args.report else None,
        coverage_map=Path(args.coverage_map) if args.coverage_map else None)
    say = lambda line: print(line, flush=True)  # noqa: E731
    camera = follow = None
    if args.camera and args.camera.lower() == "mock":
        camera, follow = _mock_camera(config, args.seed)
        say("MOCK camera: a simulated XB3 and a simulated operator who follows the hints")
    try:
        run = run_stereo_calibration(config, say=say, camera=camera, follow=follow, progress=progress_bar)
    finally:
        if camera is not None:
            camera.close()
    _print_summary(run, say)
    return 0


def _mock_camera(config, seed):
    from ...drivers import open_camera
    from ...mocks import BoardOperator, PrintedBoard

    if TYPE_CHECKING:
        from ...mocks import MockCamera

    board = PrintedBoard(config.board, margin_mm=max(15.0, 0.8 * config.board.square_mm))
    camera = cast("MockCamera", open_camera("mock", board=board, seed=seed, output="gray", render_centre=False))  # back end "mock"
    operator = BoardOperator(camera.model, board, seed=seed)
    return camera, lambda hint: operator.follow(camera, hint)


def _print_summary(run, say) -> None:
    cal = run.calibration
    m = cal.model
    left_out = [v for v in cal.views if v.reasons]
    say(f"stereo calibration of {cal.pairs_used} pairs ({run.pairs_given} given{'; refined jointly' if cal.refined else ''})")
    say(f"  RMS {cal.rms_px:.3f} px (left {cal.left.rms_px:.3f}, right {cal.right.rms_px:.3f}), epipolar "
        f"{cal.epipolar_rms_px:.3f} px, baseline {cal.baseline_mm:.2f} mm")
    for side, k in (("left ", m.K1), ("right", m.K2)):
        say(f"  {side} f ({k[0, 0]:.1f}, {k[1, 1]:.1f}) px, centre ({k[0, 2]:.1f}, {k[1, 2]:.1f})")
    cov = run.coverage
    missing = [f"left {c}" for c in cov.to_json()["missing_left"]] + [f"right {c}" for c in cov.to_json()["missing_right"]]
    missing += cov.missing_tilts()
    say(f"  coverage: {cov.summary()}" + (f"; still empty: {', '.join(missing)}" if missing else ""))
    if run.factory:
        f = run.factory
        say(f"  factory (Triclops rectified): baseline {f['factory']['baseline_mm']:.2f} mm; calibrated differs by "
            f"{f['baseline_difference_percent']:+.2f} %")
    for warning in cal.warnings:
        say(f"  note: {warning}")
    if left_out:
        say(f"  {len(left_out)} pair(s) not fully used (reasons in the report):")
        for v in left_out[:8]:
            say(f"    {v.name}: {'; '.join(v.reasons)}")
        if len(left_out) > 8:
            say(f"    ... and {len(left_out) - 8} more")
    files = run.files
    say(f"wrote {files['stereo']}, report {files['report']}, coverage map {files['coverage_map']}")
    say(f"next: handeye triangulate --left L.png --right R.png --stereo {files['stereo']} --json -")


def _triclops(args) -> int:
    from pathlib import Path

    from ...drivers import read_triclops_model
    from ..stereo_from_pairs import write_stereo_file

    model = read_triclops_model(args.file, size=args.size)
    path = write_stereo_file(Path(args.output), model, {"source": model.name})
    k = model.K1
    print(f"{model.image_size[0]}x{model.image_size[1]}: f {k[0, 0]:.2f} px, centre ({k[0, 2]:.2f}, {k[1, 2]:.2f}), "
          f"baseline {model.baseline_mm:.2f} mm, no distortion -> {path}")
    return 0


def run(args: argparse.Namespace) -> int:
    action = getattr(args, "stereo_action", None)
    if action == "calibrate":
        return _calibrate(args)
    if action == "triclops":
        return _triclops(args)
    args._stereo_parser.print_help()
    return 2


def _stereo_board(board, square_mm):
    """The board of ``stereo calibrate``: a ChArUco description keeps its own square size unless
    ``--square-mm`` says otherwise (its default is the checkerboard's)."""
    from ...geometry import BoardGeometry
    from ...geometry import STATION_SQUARE_MM
    from ...drivers import as_board

    if isinstance(board, BoardGeometry) and square_mm == STATION_SQUARE_MM:
        return board
    return as_board(board, square_mm)
