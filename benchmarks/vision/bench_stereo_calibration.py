"""Stereo calibration benchmark: ``handeye stereo calibrate`` against plain OpenCV and the rendering truth.

Run from the repository root (after ``pip install -e .``)::

    python benchmarks/vision/bench_stereo_calibration.py --pairs 24 --seeds 1 2 3 \\
        --json benchmarks/vision/stereo_calibration.json

Per seed: ``--pairs`` stereo pairs are rendered by the mock XB3 through a raw (unrectified) head with
lens distortion (K1 = 990/985 px at (650, 480), K2 = 975/978 px at (630, 500), k1 = -0.08 / -0.07,
R = 1.3 deg, T = (-240.5, 1.2, -0.8) mm), a 9x6-corner board with 30 mm squares 0.45-1.0 m away,
tilted up to 45 deg, up to 300 px off centre, made hard the way real images are
(``mocks.camera.hard_options``: blur, uneven light, glare or shadow, noise, JPEG). Then:

- **ours**: ``station.stereo_from_pairs.run_stereo_calibration`` on the folder, exactly what
  ``handeye stereo calibrate --images DIR --board 9x6 --square-mm 30 -o s.yaml`` does (files written);
- **plain OpenCV**: ``findChessboardCorners`` (default flags) + ``cornerSubPix`` (11x11), the grid put
  in the canonical order by the printed pattern (OpenCV leaves the start corner open), then
  ``calibrateCamera`` for each camera and ``stereoCalibrate`` (``CALIB_FIX_INTRINSIC``), default flags,
  on the pairs it found in both images; and ours on those same pairs (the RMS ratio and baseline
  comparison of the requirement);
- **plain OpenCV on our corners**: the same OpenCV calls on every pair we used (the calibration
  procedures compared on identical input);
- **truth**: focal lengths, principal points, baseline, rotation, and the largest difference of
  projected points both cameras see (0.6-0.9 m) between the recovered and the rendering model;
- **triangulation at 0.5 m**: 5 boards 0.48-0.52 m away measured with our file through
  ``observe_board`` (rectified rows + disparity) against OpenCV's own triangulation
  (``undistortPoints`` + ``triangulatePoints``) of the same corners with the same file, with plain
  OpenCV's calibration, and against the true corners (RMS, mm).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.drivers.camera.board_pattern import canonical_orderings, pattern_score
from handeye.drivers.camera.checkerboard import observe_board
from handeye.drivers.camera.stereo import StereoModel, load_stereo_model
from handeye.drivers.camera.stereo_fit import calibrate_stereo
from handeye.mocks.camera import StereoRenderer, hard_options
from handeye.mocks.world import PrintedBoard, sample_board_views
from handeye.station.stereo_from_pairs import StereoCalibrationConfig, detect_pairs, find_pairs, run_stereo_calibration

BOARD = PrintedBoard(BoardGeometry((9, 6), 30.0), 20.0)
OBJ = board_corners(BOARD.corners, BOARD.square_mm).astype(np.float32)
SIZE = (1280, 960)


def truth_model() -> StereoModel:
    k1 = np.array([[990.0, 0.0, 650.0], [0.0, 985.0, 480.0], [0.0, 0.0, 1.0]])
    k2 = np.array([[975.0, 0.0, 630.0], [0.0, 978.0, 500.0], [0.0, 0.0, 1.0]])
    r = Rotation.from_euler("xyz", [0.4, -1.2, 0.3], degrees=True).as_matrix()
    return StereoModel(SIZE, k1, [-0.08, 0.05, 0.0005, -0.0003, 0.0], k2, [-0.07, 0.04, -0.0002, 0.0004, 0.0], r,
                       [-240.5, 1.2, -0.8], name="rendering truth")


def opencv_corners(image):
    found, corners = cv2.findChessboardCorners(image, BOARD.corners)
    if not found:
        return None
    corners = cv2.cornerSubPix(image, corners, (11, 11), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001))
    nx, ny = BOARD.corners
    options = canonical_orderings(corners.reshape(ny, nx, 2).astype(np.float64))
    return max(options, key=lambda g: pattern_score(g, image)).reshape(-1, 2)


def opencv_stereo(lefts, rights) -> dict:
    obj = [OBJ] * len(lefts)
    lp = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in lefts]
    rp = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in rights]
    _, k1, d1, _, _ = cv2.calibrateCamera(obj, lp, SIZE, None, None)
    _, k2, d2, _, _ = cv2.calibrateCamera(obj, rp, SIZE, None, None)
    rms, k1, d1, k2, d2, r, t, _, _ = cv2.stereoCalibrate(obj, lp, rp, k1, d1, k2, d2, SIZE, flags=cv2.CALIB_FIX_INTRINSIC)
    return {"rms": float(rms), "K1": k1, "D1": d1.ravel(), "K2": k2, "D2": d2.ravel(), "R": r, "T": t.ravel()}


def opencv_triangulate(p: dict, left_px, right_px) -> np.ndarray:
    ul = cv2.undistortPoints(np.asarray(left_px, np.float64).reshape(-1, 1, 2), p["K1"], p["D1"])
    ur = cv2.undistortPoints(np.asarray(right_px, np.float64).reshape(-1, 1, 2), p["K2"], p["D2"])
    h = cv2.triangulatePoints(np.hstack([np.eye(3), np.zeros((3, 1))]), np.hstack([p["R"], p["T"].reshape(3, 1)]),
                              ul.reshape(-1, 2).T, ur.reshape(-1, 2).T)
    return (h[:3] / h[3]).T


def vs_truth(p: dict, truth: StereoModel) -> dict:
    m = StereoModel(SIZE, p["K1"], p["D1"], p["K2"], p["D2"], p["R"], p["T"])
    pts = np.array([[x, y, z] for x in (-50.0, 100.0, 250.0) for y in (-150.0, 0.0, 150.0) for z in (600.0, 900.0)])
    proj = max(np.abs(m.project(pts, v) - truth.project(pts, v)).max() for v in ("left", "right"))
    return {"focal_error_percent": float(100 * max(abs(m.K1[0, 0] / truth.K1[0, 0] - 1), abs(m.K1[1, 1] / truth.K1[1, 1] - 1),
                                                   abs(m.K2[0, 0] / truth.K2[0, 0] - 1), abs(m.K2[1, 1] / truth.K2[1, 1] - 1))),
            "centre_error_px": float(max(np.abs(m.K1[:2, 2] - truth.K1[:2, 2]).max(), np.abs(m.K2[:2, 2] - truth.K2[:2, 2]).max())),
            "baseline_error_percent": float(100 * (m.baseline_mm / truth.baseline_mm - 1)),
            "rotation_error_deg": float(np.degrees(np.linalg.norm(cv2.Rodrigues(m.R.T @ truth.R)[0]))),
            "projection_error_px": float(proj)}


def rms(a, b) -> float:
    return float(np.sqrt(np.mean(np.sum((np.asarray(a) - np.asarray(b)) ** 2, axis=1))))


def one_seed(n: int, seed: int) -> dict:
    truth = truth_model()
    rng = np.random.default_rng(seed)
    poses = sample_board_views(n, truth, BOARD, seed=seed, distance_mm=(450, 1000), tilt_deg=(0, 45), offset_px=300,
                               views=("left", "right"), border_px=2)
    renderer = StereoRenderer(truth, BOARD, seed=seed)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        plain_corners = []
        for k, pose in enumerate(poses):
            renderer.options = hard_options(rng, BOARD)
            left, right = renderer.gray_pair(pose)
            cv2.imwrite(str(folder / f"{k:03d}_left.png"), left)
            cv2.imwrite(str(folder / f"{k:03d}_right.png"), right)
            plain_corners.append((opencv_corners(left), opencv_corners(right)))
        config = StereoCalibrationConfig(output=folder / "out" / "s.yaml", board=BOARD.geometry, images=folder)
        t0 = time.perf_counter()
        run = run_stereo_calibration(config, say=lambda line: None)
        command_s = time.perf_counter() - t0
        ours = run.calibration
        model = load_stereo_model(run.files["stereo"])
        views, _ = detect_pairs(find_pairs(folder), BOARD.geometry)
    same = [k for k, (a, b) in enumerate(plain_corners) if a is not None and b is not None]
    plain = opencv_stereo([plain_corners[k][0] for k in same], [plain_corners[k][1] for k in same])
    ours_same = calibrate_stereo([views[k] for k in same], BOARD.geometry, SIZE)
    used = [v for v, r in zip(views, ours.views) if r.used_pair]
    plain_ours = opencv_stereo([v.left for v in used], [v.right for v in used])
    as_dict = lambda m: {"K1": m.K1, "D1": m.D1, "K2": m.K2, "D2": m.D2, "R": m.R, "T": m.T}  # noqa: E731
    tri = {"ours_vs_opencv_same_file_mm": [], "ours_vs_plain_opencv_mm": [], "ours_vs_plain_opencv_on_our_corners_mm": [],
           "ours_vs_truth_mm": [], "plain_opencv_vs_truth_mm": []}
    near = sample_board_views(5, truth, BOARD, seed=seed + 100, distance_mm=(480, 520), tilt_deg=(0, 30), offset_px=60,
                              views=("left", "right"))
    clean = StereoRenderer(truth, BOARD, seed=seed + 100)
    for pose in near:
        left, right = clean.gray_pair(pose)
        obs = observe_board(left, right, model, BOARD.geometry)
        true_pts = OBJ.astype(float) @ pose[:3, :3].T + pose[:3, 3]
        lp, rp = obs.left.corners_px, obs.right.corners_px
        tri["ours_vs_opencv_same_file_mm"].append(rms(obs.points_mm, opencv_triangulate(as_dict(model), lp, rp)))
        tri["ours_vs_plain_opencv_mm"].append(rms(obs.points_mm, opencv_triangulate(plain, lp, rp)))
        tri["ours_vs_plain_opencv_on_our_corners_mm"].append(rms(obs.points_mm, opencv_triangulate(plain_ours, lp, rp)))
        tri["ours_vs_truth_mm"].append(rms(obs.points_mm, true_pts))
        tri["plain_opencv_vs_truth_mm"].append(rms(opencv_triangulate(plain, lp, rp), true_pts))
    return {
        "seed": seed, "pairs": n, "command_s": command_s,
        "ours": {"pairs_used": ours.pairs_used, "rms_px": ours.rms_px, "baseline_mm": ours.baseline_mm,
                 "epipolar_rms_px": ours.epipolar_rms_px, "refined": ours.refined,
                 "left_out": {v.name: v.reasons for v in ours.views if v.reasons}, "truth": vs_truth(as_dict(model), truth)},
        "same_pairs": {"pairs": len(same), "opencv_rms_px": plain["rms"], "ours_rms_px": ours_same.rms_px,
                       "rms_ratio": ours_same.rms_px / plain["rms"],
                       "baseline_difference_percent": 100 * (ours_same.baseline_mm / np.linalg.norm(plain["T"]) - 1),
                       "opencv_truth": vs_truth(plain, truth)},
        "our_corners": {"pairs": len(used), "opencv_rms_px": plain_ours["rms"], "rms_ratio": ours.rms_px / plain_ours["rms"],
                        "baseline_difference_percent": 100 * (ours.baseline_mm / np.linalg.norm(plain_ours["T"]) - 1)},
        "triangulation_0_5m": {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in tri.items()},
    }


def markdown(rows: list) -> str:
    lines = ["| seed | pairs (ours used) | ours RMS px | epipolar px | baseline mm | OpenCV same pairs: pairs, RMS px | "
             "RMS ratio | baseline diff | on our corners: RMS ratio, baseline diff | command s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        o, s, c = r["ours"], r["same_pairs"], r["our_corners"]
        lines.append(f"| {r['seed']} | {r['pairs']} ({o['pairs_used']}) | {o['rms_px']:.3f} | {o['epipolar_rms_px']:.3f} | "
                     f"{o['baseline_mm']:.2f} | {s['pairs']}, {s['opencv_rms_px']:.3f} | **{s['rms_ratio']:.2f}** | "
                     f"**{s['baseline_difference_percent']:+.3f} %** | {c['rms_ratio']:.2f}, {c['baseline_difference_percent']:+.3f} % | "
                     f"{r['command_s']:.1f} |")
    lines += ["", "| seed | vs truth | focal err | centre err | baseline err | rotation err | projection err |",
              "|---|---|---|---|---|---|---|"]
    for r in rows:
        for label, t in (("ours", r["ours"]["truth"]), ("plain OpenCV", r["same_pairs"]["opencv_truth"])):
            lines.append(f"| {r['seed']} | {label} | {t['focal_error_percent']:.3f} % | {t['centre_error_px']:.2f} px | "
                         f"{t['baseline_error_percent']:+.3f} % | {t['rotation_error_deg']:.3f} deg | {t['projection_error_px']:.2f} px |")
    lines += ["", "| seed | triangulation at 0.5 m (RMS, mm): ours vs OpenCV triangulatePoints, same file | vs plain OpenCV "
              "calibration | vs plain OpenCV on our corners | ours vs truth | plain OpenCV vs truth |", "|---|---|---|---|---|---|"]
    for r in rows:
        t = r["triangulation_0_5m"]
        lines.append(f"| {r['seed']} | **{t['ours_vs_opencv_same_file_mm']:.4f}** | {t['ours_vs_plain_opencv_mm']:.3f} | "
                     f"{t['ours_vs_plain_opencv_on_our_corners_mm']:.3f} | **{t['ours_vs_truth_mm']:.3f}** | "
                     f"{t['plain_opencv_vs_truth_mm']:.3f} |")
    left_out = [f"seed {r['seed']} pair {k}: {'; '.join(v)}" for r in rows for k, v in r["ours"]["left_out"].items()]
    if left_out:
        lines += ["", "Left out by ours (reasons as reported):", ""] + [f"- {line}" for line in left_out]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, default=24)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args(argv)
    rows = [one_seed(args.pairs, seed) for seed in args.seeds]
    print(markdown(rows))
    if args.json:
        out = {"machine": {"python": sys.version.split()[0], "opencv": cv2.__version__, "numpy": np.__version__,
                           "platform": platform.platform()}, "seeds": rows}
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
