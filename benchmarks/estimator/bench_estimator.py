"""Benchmarks of the default estimator (issue 10) that the method sweeps do not cover.

Run from the repository root:

    python benchmarks/estimator/bench_estimator.py speed        # 100 and 300 postures: time, memory
    python benchmarks/estimator/bench_estimator.py mock [SEEDS]  # the mock station (kinematic errors)
    python benchmarks/estimator/bench_estimator.py small        # outliers in small sets of board poses

``speed``: synthetic sessions of 100 and 300 postures (IRB 1400, 5 mm camera noise and 0.02 deg joint
noise), five solves each: ``runtime_s`` (the solve alone, as ``handeye calibrate`` reports it) and
the peak memory of a whole ``calibrate`` call (tracemalloc, numpy's allocations included), plus
the process's peak resident size.

``mock``: ``handeye demo`` (the embedded mock station: an arm whose kinematics differ from the
nominal model, rendered XB3 frames through the real detection and triangulation) for each seed;
the recovered camera pose against the hidden mount, per axis in units of the reported one-sigma,
and the RMS of those ratios over all seeds and axes (honest: near 1).

``small``: OpenCV's pose-noise model (``src/handeye/calibration/synthetic_poses.py``) with 6, 8, 10 and 20 poses,
100 clean sets each: in how many the default excludes a posture, and its mean error; then 30 sets
of 8 poses with one gross error at posture 2 (a 3 deg board turn, a 25 mm or a 50 mm shift on each
axis): how often it is found, what else is excluded, and the mean error.
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
import tracemalloc
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session


def speed(cache: Path) -> None:
    path = cache / "scene300.npz"
    if path.exists():
        data = np.load(path)
        scene = make_scene(SceneConfig(postures=3, seed=0))
        scene = replace(scene, joints_deg=data["joints"], config=replace(scene.config, postures=len(data["joints"])))
    else:
        scene = make_scene(SceneConfig(postures=300, seed=1))
        np.savez(path, joints=scene.joints_deg)
    print("| postures | solve (s), median of 5 | max of 5 | peak memory, tracemalloc (MB) | outliers | start |")
    print("|---|---|---|---|---|---|")
    for n in (100, 300):
        sc = replace(scene, joints_deg=scene.joints_deg[:n], config=replace(scene.config, postures=n))
        problem = problem_from_session(sample_session(sc, NoiseConfig(sigma_rob_deg=0.02, sigma_cam_mm=5.0, seed=2)))
        times = [calibrate(problem).runtime_s for _ in range(5)]
        tracemalloc.start()
        result = calibrate(problem)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        start = result.details["start"]
        print(f"| {n} | {np.median(times):.3f} | {np.max(times):.3f} | {peak / 1e6:.0f} | {len(result.outliers)} "
              f"| {start['method']} on {start['postures']} postures ({start.get('candidates', 0)} triplets) |")
    print(f"\nprocess peak resident size {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB; "
          f"load average {os.getloadavg()[0]:.2f} (2 cores)")


def mock(seeds) -> None:
    from handeye.station.demo import DemoOptions, run_demo
    from handeye.geometry.transforms import transform_from_pose

    z_all = []
    print("| seed | error (mm) | error (deg) | one-sigma x/y/z (mm) | error/sigma x, y, z, rx, ry, rz | kinematics modelled | CV RMS (mm) |")
    print("|---|---|---|---|---|---|---|")
    for seed in seeds:
        with tempfile.TemporaryDirectory() as tmp:
            res = run_demo(DemoOptions(session=str(Path(tmp) / "demo"), seed=seed, report=False))
            from handeye.calibration.session import read_session

            problem = problem_from_session(read_session(res["session"]))
            result = calibrate(problem)
        truth = transform_from_pose(res["truth_camera_pose"]["position_mm"], res["truth_camera_pose"]["quaternion_wxyz"])
        et = result.x[:3, 3] - truth[:3, 3]
        er = np.degrees(Rotation.from_matrix(result.x[:3, :3] @ truth[:3, :3].T).as_rotvec())
        u = result.uncertainty
        z = np.concatenate([et / u["translation_mm"], er / u["rotation_deg"]])
        z_all.append(z)
        cv = result.cross_validation or {}
        print(f"| {seed} | {np.linalg.norm(et):.3f} | {np.linalg.norm(er):.4f} | "
              f"{' / '.join(f'{v:.3f}' for v in u['translation_mm'])} | {', '.join(f'{v:+.2f}' for v in z)} | "
              f"{result.details['kinematics'].get('modelled')} | {cv.get('rms_mm', float('nan')):.3f} |")
    z_all = np.array(z_all)
    print(f"\nRMS of error / one-sigma over {len(seeds)} seeds x 6 axes: {np.sqrt(np.mean(z_all**2)):.2f} "
          f"(translation {np.sqrt(np.mean(z_all[:, :3]**2)):.2f}, rotation {np.sqrt(np.mean(z_all[:, 3:]**2)):.2f}); "
          f"load average {os.getloadavg()[0]:.2f}")


def small() -> None:
    import sys  # noqa: PLC0415

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
    from test_robust_default import _corrupt  # noqa: PLC0415 (the suite's gross-error helper)

    from handeye.calibration.eiv import solve_eiv  # noqa: PLC0415
    from handeye.calibration.metrics import errors_against_truth  # noqa: PLC0415
    from handeye.calibration.synthetic_poses import opencv_test_problem  # noqa: PLC0415

    def solve(problem, truth):
        sol = solve_eiv(problem, folds=0)
        return sol.outliers, errors_against_truth(sol.x, truth["x"])["translation_error_mm"]

    print("| poses | clean sets losing a posture, of 100 | mean error (mm) |")
    print("|---|---|---|")
    for poses in (6, 8, 10, 20):
        runs = [solve(*opencv_test_problem(np.random.default_rng(1000 + seed), poses)) for seed in range(100)]
        print(f"| {poses} | {sum(bool(o.any()) for o, _ in runs)} | {np.mean([e for _, e in runs]):.3f} |")
    print("\n| gross error at posture 2 of 8 | found, of 30 | other postures excluded | mean error (mm) |")
    print("|---|---|---|---|")
    for label, shift, turn in (("3 deg board turn", 0.0, 3.0), ("25 mm shift per axis", 25.0, 0.0),
                               ("50 mm shift per axis", 50.0, 0.0)):
        runs = []
        for seed in range(30):
            problem, truth = opencv_test_problem(np.random.default_rng(2000 + seed), 8)
            runs.append(solve(_corrupt(problem, [2], shift, turn), truth))
        found = sum(bool(o[2]) for o, _ in runs)
        others = sum(int(o.sum() - o[2]) for o, _ in runs)
        print(f"| {label} | {found} | {others} | {np.mean([e for _, e in runs]):.2f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=("speed", "mock", "small"))
    parser.add_argument("seeds", nargs="?", default="1,2,3,4,5,6,7,8,9,10")
    args = parser.parse_args()
    started = time.time()
    if args.what == "speed":
        cache = Path(tempfile.gettempdir()) / "handeye-bench"
        cache.mkdir(exist_ok=True)
        speed(cache)
    elif args.what == "small":
        small()
    else:
        mock([int(s) for s in args.seeds.split(",")])
    print(f"(wall {time.time() - started:.0f} s)")


if __name__ == "__main__":
    main()
