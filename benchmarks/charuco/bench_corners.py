"""Per-corner accuracy of ChArUco corners against checkerboard corners on the mock's renders (issue 37).

The same random board poses (0.9-1.25 m, 10-45 deg tilt, the demo's range) and the same sensor noise are
rendered for the station's checkerboard (13x8 corners of 30 mm) and its ChArUco board (14x9 squares of
30 mm, 22 mm markers: the same 104 corners at the same places); each left image is detected (the
checkerboard path, and the ChArUco path: OpenCV's ``CharucoDetector`` followed by this package's
refinement with the markers painted out) and every corner compared with its true projection. The rows:
the error (px) of the checkerboard corners, of the ChArUco corners as OpenCV refines them, and of the
ChArUco corners as the package returns them.

    python benchmarks/charuco/bench_corners.py [--poses 24] [--seed 1] [--colour]

``--colour``: the demo's colour head (GBRG mosaic packed into an XB3 frame and decoded by the driver, through
``MockCamera.grab``) instead of a mono head's grey plane.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import cv2
import numpy as np

from handeye.drivers.camera import charuco
from handeye.drivers.camera.checkerboard import detect_board
from handeye.geometry import STATION_BOARD
from handeye.geometry.targets import STATION_CHARUCO
from handeye.mocks.camera import MockCamera, StereoRenderer
from handeye.mocks.world import PrintedBoard


def random_pose(rng) -> np.ndarray:
    """``target2cam`` ``(4, 4)``: board centre 0.9-1.25 m ahead, tilted 10-45 deg about a random axis."""
    axis = rng.normal(size=3) * [1.0, 1.0, 0.3]
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(axis / np.linalg.norm(axis) * np.radians(rng.uniform(10, 45)))[0]
    pose[:3, 3] = [rng.uniform(-150, 150), rng.uniform(-100, 100), rng.uniform(900, 1250)]
    pose[:3, 3] -= pose[:3, :3] @ STATION_BOARD.grid().mean(axis=0)
    return pose


def colour_left(board, pose: np.ndarray, seed: int) -> np.ndarray:
    """The left image of a mock colour XB3 frame (``MockCamera.grab``: mosaic, XB3 packing, decode) of ``board``."""
    camera = MockCamera(board=PrintedBoard(board), seed=seed + 4, render_centre=False)
    with camera:
        camera.set_scene(target2base=np.eye(4), cam2base=np.linalg.inv(pose))
        return camera.grab().left


def summary(errors: list) -> dict:
    e = np.linalg.norm(np.concatenate(errors), axis=1)
    return {"corners": int(len(e)), "rms_px": float(np.sqrt(np.mean(e**2))), "median_px": float(np.median(e)),
            "p95_px": float(np.percentile(e, 95)), "max_px": float(e.max())}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=24)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--colour", action="store_true", help="the colour head's decoded frames (the demo's)")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    poses = [random_pose(rng) for _ in range(args.poses)]
    plain, marked = (StereoRenderer(board=PrintedBoard(b), seed=args.seed + 4) for b in (STATION_BOARD, STATION_CHARUCO))
    grid = STATION_BOARD.grid()
    rows: dict = {"checkerboard": [], "charuco, OpenCV's refinement": [], "charuco, markers painted out": []}
    original = charuco.refine_without_markers
    for pose in poses:
        truth = plain.model.project(grid @ pose[:3, :3].T + pose[:3, 3], "left")
        if args.colour:
            cb, ch = (colour_left(b, pose, args.seed) for b in (STATION_BOARD, STATION_CHARUCO))
        else:
            cb = plain.planes(pose, ("left",), replace(plain.options, colour=False))["left"]
            ch = marked.planes(pose, ("left",), replace(marked.options, colour=False))["left"]
        rows["checkerboard"].append(detect_board(cb, STATION_BOARD).corners_px - truth)
        try:
            charuco.refine_without_markers = lambda gray, px, *rest: px  # OpenCV's corners as they come
            det = charuco.detect_charuco(ch, STATION_CHARUCO)
        finally:
            charuco.refine_without_markers = original
        rows["charuco, OpenCV's refinement"].append(det.corners_px - truth[det.ids])
        det = charuco.detect_charuco(ch, STATION_CHARUCO)
        rows["charuco, markers painted out"].append(det.corners_px - truth[det.ids])
    print(f"{args.poses} poses (seed {args.seed}), {'colour' if args.colour else 'mono'} head, left image, error against the true projection (px):")
    for name, errors in rows.items():
        s = summary(errors)
        print(f"  {name:30s} {s['corners']:5d} corners  RMS {s['rms_px']:.4f}  median {s['median_px']:.4f}  "
              f"p95 {s['p95_px']:.4f}  max {s['max_px']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
