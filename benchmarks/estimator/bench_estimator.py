"""Benchmarks of the default estimator (issue 10) that the method sweeps do not cover.

Run from the repository root:

    python benchmarks/estimator/bench_estimator.py speed        # 100 and 300 postures: time, memory
    python benchmarks/estimator/bench_estimator.py mock [SEEDS]  # the mock station (kinematic errors)

``speed``: synthetic sessions of 100 and 300 postures (IRB 1400, 5 mm camera noise and 0.02 deg joint
noise), five solves each: ``runtime_s`` (the solve alone, as ``handeye calibrate`` reports it) and
the peak memory of a whole ``calibrate`` call (tracemalloc, numpy's allocations included), plus
the process's peak resident size.

``mock``: ``handeye demo`` (the embedded mock station: an arm whose kinematics differ from the
nominal model, rendered XB3 frames through the real detection and triangulation) for each seed;
the recovered camera pose against the hidden mount, per axis in units of the reported one-sigma,
and the RMS of those ratios over all seeds and axes (honest: near 1).
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
    from handeye.calibration.transforms import transform_from_pose

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


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=("speed", "mock"))
    parser.add_argument("seeds", nargs="?", default="1,2,3,4,5,6,7,8,9,10")
    args = parser.parse_args()
    started = time.time()
    if args.what == "speed":
        cache = Path(tempfile.gettempdir()) / "handeye-bench"
        cache.mkdir(exist_ok=True)
        speed(cache)
    else:
        mock([int(s) for s in args.seeds.split(",")])
    print(f"(wall {time.time() - started:.0f} s)")


if __name__ == "__main__":
    main()
