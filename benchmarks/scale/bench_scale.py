"""Wall time and peak memory of `handeye import` and `handeye calibrate` on large inputs.

    python benchmarks/scale/bench_scale.py [--postures 10000] [--stream-rows 300000] [--keep DIR]

Three runs, each a fresh `python -m handeye.station` process whose wall time and peak resident
memory (``ru_maxrss`` of that child, from ``os.wait4``) are printed:

1. ``handeye import`` of a headerless CSV log of ``--postures`` rows (robot pose + camera pose,
   position in metres and quaternion x y z w each, the conventions left to the inference);
2. ``handeye calibrate`` of the session that import wrote (the default method, no ``--method``);
3. ``handeye import`` of a time-stamped stream pair (ETH layout, ``t,x,y,z,qx,qy,qz,qw``) of
   ``--stream-rows`` rows per file, 250 Hz, which the import decimates.

The poses are drawn directly (no inverse kinematics, so that drawing 10,000 postures takes a
fraction of a second): a camera mounted on the flange looks at a fixed board from 450-900 mm,
tilted up to 35 deg and turned about its axis up to 90 deg either way; 0.3 mm and 0.03 deg of
noise on the board poses, 0.05 mm and 0.005 deg on the robot's.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.geometry.transforms import invert_transforms, transform_from_rotation_translation

#: The camera in the flange (cam2tool0) and the board in the base (target2base), mm.
CAM2TOOL0 = transform_from_rotation_translation(Rotation.from_euler("xyz", [3.0, -2.0, 91.0], degrees=True).as_matrix(),
                                                np.array([42.0, -75.0, 118.0]))
TARGET2BASE = transform_from_rotation_translation(Rotation.from_euler("xyz", [180.0, 0.0, 4.0], degrees=True).as_matrix(),
                                                  np.array([1050.0, 80.0, 150.0]))


def board_views(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` board poses in the camera frame (target2cam), shape (n, 4, 4), mm: in front of the camera."""
    tilt = Rotation.from_rotvec(np.column_stack([rng.uniform(-1, 1, (n, 2)), np.zeros(n)])
                                * np.radians(rng.uniform(0, 35, (n, 1))) / np.sqrt(2))
    roll = Rotation.from_euler("z", rng.uniform(-90, 90, (n, 1)), degrees=True)
    position = np.column_stack([rng.uniform(-120, 120, (n, 2)), rng.uniform(450, 900, n)])
    return transform_from_rotation_translation((tilt * roll).as_matrix(), position)


def noisy(rng: np.random.Generator, poses: np.ndarray, sigma_mm: float, sigma_deg: float) -> np.ndarray:
    """``poses`` (n, 4, 4) with Gaussian noise on the position (mm) and the rotation vector (deg)."""
    turn = Rotation.from_rotvec(np.radians(rng.normal(0, sigma_deg, (len(poses), 3)))).as_matrix()
    out = poses.copy()
    out[:, :3, :3] = poses[:, :3, :3] @ turn
    out[:, :3, 3] += rng.normal(0, sigma_mm, (len(poses), 3))
    return out


def station(n: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """``(tool0_in_base, target_in_camera)``, each (n, 4, 4) mm, consistent with one camera mount."""
    rng = np.random.default_rng(seed)
    target2cam = board_views(rng, n)
    tool02base = TARGET2BASE @ invert_transforms(target2cam) @ invert_transforms(CAM2TOOL0)
    return noisy(rng, tool02base, 0.05, 0.005), noisy(rng, target2cam, 0.3, 0.03)


def pose_columns(poses: np.ndarray) -> np.ndarray:
    """Position in metres and quaternion x y z w: (n, 7)."""
    return np.hstack([poses[:, :3, 3] / 1000.0, Rotation.from_matrix(poses[:, :3, :3]).as_quat()])


def write_csv(path: Path, columns: np.ndarray) -> None:
    np.savetxt(path, columns, delimiter=",", fmt="%.9g")


def write_log(path: Path, n: int) -> None:
    """A headerless CSV of ``n`` rows: robot pose then camera pose, 7 numbers each."""
    tool0, target = station(n)
    write_csv(path, np.hstack([pose_columns(tool0), pose_columns(target)]))


def write_stream(folder: Path, rows: int, rate_hz: float = 250.0) -> tuple[Path, Path]:
    """Robot (hand in base) and camera (camera in target) streams of ``rows`` samples each.

    The hand stops at a new view every 2 s for 1 s and moves between views in a straight line
    (slerp for the rotation), as a logged robot program would.
    """
    t = np.arange(rows) / rate_hz
    stops = int(np.ceil(t[-1] / 2.0)) + 2
    tool0, target = station(stops, seed=11)
    segment = np.minimum(t // 2.0, stops - 2).astype(int)
    phase = np.clip((t - 2.0 * segment - 1.0), 0.0, 1.0)  # 0 during the stop, then 0..1 on the way
    hand = np.empty((rows, 4, 4))
    hand[:] = np.eye(4)
    for k in np.unique(segment):
        at = segment == k
        between = Rotation.from_matrix(tool0[[k, k + 1], :3, :3])
        turn = (between[0].inv() * between[1]).as_rotvec()
        hand[at, :3, :3] = (between[0] * Rotation.from_rotvec(phase[at, None] * turn)).as_matrix()
        hand[at, :3, 3] = tool0[k, :3, 3] + phase[at, None] * (tool0[k + 1, :3, 3] - tool0[k, :3, 3])
    camera2target = invert_transforms(TARGET2BASE) @ hand @ CAM2TOOL0
    robot_path, camera_path = folder / "hand_base_link.csv", folder / "camera_target.csv"
    write_csv(robot_path, np.column_stack([t, pose_columns(hand)]))
    write_csv(camera_path, np.column_stack([t + 0.001, pose_columns(camera2target)]))
    return robot_path, camera_path


def run(argv: list) -> tuple[float, float, subprocess.CompletedProcess]:
    """Wall time (s) and peak resident memory (MB) of ``handeye ARGV`` in a fresh process."""
    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        child = subprocess.Popen([sys.executable, "-m", "handeye.station", *argv], stdout=out, stderr=err, text=True)
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - start
        out.seek(0)
        err.seek(0)
        done = subprocess.CompletedProcess(argv, child.returncode, out.read(), err.read())
    return wall, usage.ru_maxrss / 1024.0, done


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=10000)
    parser.add_argument("--stream-rows", type=int, default=300000)
    parser.add_argument("--keep", metavar="DIR", help="write the inputs and sessions here (default: a temporary folder)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        log = folder / f"log_{args.postures}.csv"
        write_log(log, args.postures)
        streams = folder / "stream"
        streams.mkdir(exist_ok=True)
        write_stream(streams, args.stream_rows)
        session = folder / f"session_{args.postures}"
        runs = [(f"import of a {args.postures}-posture log ({log.stat().st_size / 1e6:.1f} MB)",
                 ["import", str(log), "-o", str(session), "--overwrite"]),
                (f"calibrate of the {args.postures}-posture session", ["calibrate", str(session)]),
                (f"import of a {args.stream_rows}-row stream pair",
                 ["import", str(streams), "-o", str(folder / "session_stream"), "--overwrite"])]
        print("| run | wall (s) | peak memory (MB) | exit |")
        print("|---|---|---|---|")
        for name, argv in runs:
            wall, peak, done = run(argv)
            print(f"| {name} | {wall:.1f} | {peak:.0f} | {done.returncode} |", flush=True)
            if done.returncode:
                print(f"    stderr: {done.stderr.strip()[-400:]}")
            last = [line for line in done.stdout.splitlines() if line.strip()]
            for line in last[-4:]:
                print(f"    {line}")


if __name__ == "__main__":
    main()
