"""``handeye triangulate``: checkerboard corners in millimetres from one stereo frame."""

from __future__ import annotations

import argparse

from ...geometry import STATION_CORNERS
from . import argtypes
from .argtypes import Subcommands

HELP = "board corners in mm (camera frame) from a stereo image pair or a raw XB3 frame"

EPILOG = """\
Input, one of:
  --left L.png --right R.png   the left (camera 1, the reference 'camera' frame) and right images
                               (grey or colour; as captured, not rectified)
  --xb3-raw FRAME              one raw Bumblebee XB3 Format_7 frame, 3-sensor RGB8 layout (per pixel
                               byte 0 = right, 1 = centre, 2 = left sensor; GBRG mosaics, or grey
                               planes with --mono); the wide left-right pair is used

--stereo STEREO.yaml is an OpenCV FileStorage file with image_width, image_height, K1, D1, K2, D2,
R, T (stereoCalibrate meaning, T in mm; camera 1 = left). Without --stereo the nominal XB3 wide
pair is used: f = 983 px, (cx, cy) = (643.6, 493.4), baseline 239.98 mm, no distortion (a
factory-rectified 3.8 mm head at 1280x960); give your head's own file for real measurements.

--board is the number of INNER corners, long side first, e.g. 13x8 for a board of 14x9 squares
(8x13 is refused: it would name another corner order). --square-mm is checked against the
measured corners: more than 5 % off (a wrong size, or a stereo model not in mm) is refused.
The corners come out in the target frame's order (conventions.md): origin at a corner of the
grid, x along the long side from the edge whose corner squares are black towards the edge whose
corner squares are white, z into the board; index = row * 13 + col.

--json OUT writes {"points_mm": [[x, y, z], ...], "runtime_s": ..., "quality": {...}} ('-' =
standard output). runtime_s is decoding + detection + triangulation (not file reading).
quality: corner counts, row_disagreement_rms_px (rectified rows, left vs right: large = wrong
stereo file or not one frame), plane_rms_mm (flatness), distance_mm, tilt_deg, square_mm_measured.

Example:
  handeye triangulate --left 000_left.png --right 000_right.png --stereo xb3.yaml \\
      --board 13x8 --square-mm 30 --json 000.json
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("triangulate", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--left", metavar="L.png", help="left image (camera 1)")
    p.add_argument("--right", metavar="R.png", help="right image (camera 2)")
    p.add_argument("--xb3-raw", metavar="FRAME", help="raw XB3 frame (3-sensor RGB8 layout)")
    p.add_argument("--stereo", metavar="STEREO.yaml", help="stereo model (default: nominal XB3 wide pair)")
    p.add_argument("--board", metavar="NXxNY", type=argtypes.corners_or_target, default=STATION_CORNERS,
                   help="inner corners, long side first (default {}x{}), or charuco[:keys] / circles (corners by id)".format(
                       *STATION_CORNERS))
    p.add_argument("--square-mm", metavar="MM", type=argtypes.positive, default=30.0,
                   help="square size in mm (default 30); corners measured more than 5%% apart from it are refused")
    p.add_argument("--mono", action="store_true", help="--xb3-raw frame of a mono head (planes are grey, not Bayer)")
    p.add_argument("--json", metavar="OUT", help="write the result as JSON ('-' = stdout)")
    return p


def run(args: argparse.Namespace) -> int:
    from ...drivers import triangulate_files
    from ..output import write_json

    from .stereo import _stereo_board

    board = _stereo_board(args.board, args.square_mm) if not isinstance(args.board, tuple) else args.board
    result = triangulate_files(left=args.left, right=args.right, xb3_raw=args.xb3_raw, stereo=args.stereo,
                               board=board, square_mm=board.square_mm if not isinstance(board, tuple) else args.square_mm,
                               colour=not args.mono)
    if args.json:
        write_json(args.json, result.to_json())
    if args.json != "-":
        q = result.quality
        nx, ny = result.board.corners
        print(f"{q['corners']} corners ({nx}x{ny}) at {q['distance_mm']:.0f} mm, tilt {q['tilt_deg']:.1f} deg; "
              f"rows {q['row_disagreement_rms_px']:.3f} px RMS, plane {q['plane_rms_mm']:.3f} mm RMS, "
              f"square {q['square_mm_measured']:.2f} mm; {1000 * result.runtime_s:.0f} ms"
              + (f" -> {args.json}" if args.json else ""))
    return 0
