"""The classic AX = XB solvers of calibration/classic next to OpenCV's five, on synthetic and real data.

Prints markdown tables (copied into README.md beside this script):

1. synthetic camera noise: median rotation / translation error against the truth and median solve
   time (each the fastest of 3 runs), over ``--trials`` draws (scene seed = noise seed = trial index);
2. the real data sets of ../shared/datasets: distance to the published reference (another tool's
   estimate, not truth), d_org of three target-frame points (eq. 22), and how far the answer moves
   when the same data are given in metres instead of millimetres.

Usage (from the repository root, with the package installed)::

    python benchmarks/classic/compare_classic.py --trials 20 --postures 30 --sigma-cam 5
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from handeye.calibration.classic import CLASSIC_METHODS
from handeye.base.errors import CalibrationError
from handeye.calibration.metrics import d_org, fixed_points
from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from handeye.geometry.transforms import invert_transforms, rotation_error_deg, translation_error_mm

DATASETS = Path(__file__).resolve().parents[2].parent / "shared" / "datasets"


def opencv_solvers():
    """OpenCV's five methods as ``name -> solve(hand, target2cam)``, or {} without calibrateHandEye."""
    from handeye.station.opencv_reference import OPENCV_METHODS, opencv_available, solve_opencv

    if not opencv_available():
        return {}
    return {f"opencv-{name}": (lambda hand, target2cam, name=name: solve_opencv(hand, target2cam, name))
            for name in OPENCV_METHODS}


def all_solvers():
    return {**CLASSIC_METHODS, **opencv_solvers()}


def timed(solve, hand, target2cam, repeats=3):
    """The answer and the fastest of ``repeats`` solve times (the machine is shared: the minimum
    is the least disturbed measurement)."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        x = solve(hand, target2cam)
        best = min(best, time.perf_counter() - start)
    return x, best


def synthetic_table(args) -> str:
    solvers = all_solvers()
    rows = {name: {"rot": [], "trans": [], "time": []} for name in solvers}
    for trial in range(args.trials):
        scene = make_scene(SceneConfig(postures=args.postures, setup=args.setup, seed=trial))
        noise = NoiseConfig(sigma_cam_mm=args.sigma_cam, sigma_rob_deg=args.sigma_rob, camera_model=args.camera_model, seed=trial)
        problem = problem_from_session(sample_session(scene, noise))
        for name, solve in solvers.items():
            x, seconds = timed(solve, problem.hand, problem.target2cam)
            rows[name]["rot"].append(rotation_error_deg(x, scene.x_true))
            rows[name]["trans"].append(translation_error_mm(x, scene.x_true))
            rows[name]["time"].append(seconds)
    lines = [
        (f"Synthetic {args.setup}, {args.postures} postures, sigma_cam = {args.sigma_cam:g} mm ({args.camera_model} model), "
         f"sigma_rob = {args.sigma_rob:g} deg, {args.trials} trials; medians (90th percentile in brackets)."),
        "",
        "| method | rotation error (deg) | translation error (mm) | solve time (ms) |",
        "|---|---|---|---|",
    ]
    for name, r in rows.items():
        lines.append(
            f"| {name} | {np.median(r['rot']):.3f} ({np.percentile(r['rot'], 90):.3f}) | "
            f"{np.median(r['trans']):.2f} ({np.percentile(r['trans'], 90):.2f}) | {1000 * np.median(r['time']):.2f} |"
        )
    return "\n".join(lines)


# ------------------------------------------------------------------ minimal readers of the real sets
# (kept here until `handeye import` exists; the tests carry their own copy)


def _mm(poses):
    out = np.array(poses, dtype=float)
    out[:, :3, 3] *= 1000.0
    return out


def _pose_vector(path):
    v = np.array(yaml.safe_load(path.read_text())["data"], dtype=float).ravel()
    out = np.eye(4)
    out[:3, :3] = Rotation.from_rotvec(v[3:]).as_matrix()
    out[:3, 3] = 1000.0 * v[:3]
    return out


def _reference(rotation, translation_m):
    out = np.eye(4)
    out[:3, :3] = rotation.as_matrix()
    out[:3, 3] = 1000.0 * np.asarray(translation_m)
    return out


def read_moveit():
    samples = json.loads((DATASETS / "moveit-calibration" / "pose_samples.json").read_text())
    hand = invert_transforms(_mm([s[0] for s in samples]))  # eye-to-hand: base2tool0
    ref = _reference(Rotation.from_euler("XYZ", [0.230, -2.540, 1.950]), [0.659, -0.249, 0.830])
    return hand, _mm([s[1] for s in samples]), ref


def read_visp():
    folder = DATASETS / "visp-eye-in-hand"
    count = len(list(folder.glob("pose_fPe_*.yaml")))
    hand = np.array([_pose_vector(folder / f"pose_fPe_{i}.yaml") for i in range(1, count + 1)])
    board = np.array([_pose_vector(folder / f"pose_cPo_{i}.yaml") for i in range(1, count + 1)])
    ref = _reference(Rotation.from_rotvec([-0.02347, -0.07939, 1.57459]), [0.05346, -0.00952, -0.04510])
    return hand, board, ref


def read_camodocal():
    import cv2

    storage = cv2.FileStorage(str(DATASETS / "camodocal-ar-tag" / "TransformPairsInput.yml"), cv2.FILE_STORAGE_READ)
    count = int(storage.getNode("frameCount").real())
    hand = invert_transforms(_mm([storage.getNode(f"T1_{i}").mat() for i in range(count)]))
    board = _mm([storage.getNode(f"T2_{i}").mat() for i in range(count)])
    storage.release()
    return hand, board, None


def _metres(poses):
    out = np.array(poses, dtype=float)
    out[:, :3, 3] /= 1000.0
    return out


def real_table() -> str:
    if not DATASETS.is_dir():
        return "(../shared/datasets not found: real-data table skipped)"
    solvers = all_solvers()
    lines = [
        "| data set | method | vs reference (deg / mm) | d_org (mm) | mm vs m input (deg / mm) |",
        "|---|---|---|---|---|",
    ]
    readers = (("moveit-calibration", read_moveit), ("visp-eye-in-hand", read_visp), ("camodocal-ar-tag", read_camodocal))
    for name, reader in readers:
        hand, board, ref = reader()
        length = 100.0
        target_points = np.array([[0.0, 0.0, 0.0], [length, 0.0, 0.0], [0.0, length, 0.0]])
        points_cam = np.einsum("nij,mj->nmi", board[:, :3, :3], target_points) + board[:, None, :3, 3]
        for method, solve in solvers.items():
            try:
                x = solve(hand, board)
                x_m = solve(_metres(hand), _metres(board))
            except CalibrationError as exc:
                lines.append(f"| {name} | {method} | refused: {exc} | | |")
                continue
            x_m = x_m.copy()
            x_m[:3, 3] *= 1000.0
            vs_ref = "-" if ref is None else f"{rotation_error_deg(x, ref):.3f} / {translation_error_mm(x, ref):.2f}"
            dorg = d_org(fixed_points(hand, x, points_cam)) if np.all(np.isfinite(x)) else float("nan")
            unit = f"{rotation_error_deg(x, x_m):.2g} / {translation_error_mm(x, x_m):.2g}"
            lines.append(f"| {name} | {method} | {vs_ref} | {dorg:.2f} | {unit} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--postures", type=int, default=30)
    parser.add_argument("--sigma-cam", type=float, default=5.0, help="camera noise, mm (default 5)")
    parser.add_argument("--sigma-rob", type=float, default=0.0, help="joint-angle noise, deg (default 0)")
    parser.add_argument("--camera-model", default="paper", choices=("paper", "gaussian"))
    parser.add_argument("--setup", default="eye_in_hand", choices=("eye_in_hand", "eye_to_hand"))
    parser.add_argument("--no-real", action="store_true", help="skip the real data sets")
    args = parser.parse_args(argv)
    print(synthetic_table(args))
    if not args.no_real:
        print()
        print(real_table())


if __name__ == "__main__":
    main()
