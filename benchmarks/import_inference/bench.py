"""How long `handeye import` takes on a 100-posture log, the convention inference included.

    python benchmarks/import_inference/bench.py [--postures 100] [--repeats 5]

A noisy synthetic station (the package's IRB 1400 scene, 0.5 mm camera noise, 0.01 deg per joint)
is written as logs of unknown convention, the hardest first: a headerless CSV of 6 + 6 numbers
(49 readings per side: a rotation vector, 24 Euler conventions in degrees and in radians, rvec-tvec;
2401 rotation pairs to screen, then eight direction/set-up readings per surviving pair), with the
robot poses inverted and the camera poses inverted; then proper Euler angles on both sides (the
axis relabellings of zxz share its angle gap, so about a hundred rotation pairs survive the screen
and are fitted in full). Each log is imported `--repeats` times with
`read_any` (reading, inference, session in memory: what the 2-s budget is about), as many times with
`import_to_session` (the same plus the import checks and writing the session folder: 100 posture
files, each written atomically and synced to disk), and once with the command `handeye import` in a
fresh process (Python start-up and imports included). Median times are printed per log, and the
reading the import chose is checked against the truth.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.compact_points import compact_points_from_corners
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from handeye.geometry.transforms import invert_transforms
from handeye.station.import_session import ImportOptions, import_to_session
from handeye.station.importers import read_any


def encode(poses, kind: str, unit: str, invert: bool = False) -> np.ndarray:
    poses = invert_transforms(poses) if invert else poses
    t = poses[:, :3, 3] / (1000.0 if unit == "m" else 1.0)
    r = Rotation.from_matrix(poses[:, :3, :3])
    if kind == "kuka":
        return np.hstack([t, r.as_euler("ZYX", degrees=True)])
    if kind == "zxz":
        return np.hstack([t, r.as_euler("zxz", degrees=True)])
    if kind == "rotvec":
        return np.hstack([t, r.as_rotvec()])
    if kind == "xyzw":
        return np.hstack([t, r.as_quat()])
    m = poses.copy()
    m[:, :3, 3] = t
    return m.reshape(len(m), 16)


def table(*blocks) -> str:
    return "\n".join(",".join(f"{v:.12g}" for v in row) for row in np.hstack(blocks)) + "\n"


def station(postures: int):
    scene = make_scene(SceneConfig(postures=postures, setup="eye_in_hand", seed=7))
    session = sample_session(scene, NoiseConfig(sigma_cam_mm=0.5, sigma_rob_deg=0.01, seed=1))
    tool0 = np.array([p.tool0_in_base for p in session.postures])
    target = compact_points_from_corners(np.array([p.points_mm for p in session.postures]), scene.board).target2cam
    return tool0, target


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--postures", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    tool0, target = station(args.postures)
    logs = {
        "CSV 6+6, KUKA robot (mm) + rotation vector camera (m)": table(encode(tool0, "kuka", "mm"),
                                                                       encode(target, "rotvec", "m")),
        "  same, robot poses inverted (base in flange)": table(encode(tool0, "kuka", "mm", True),
                                                               encode(target, "rotvec", "m")),
        "  same, camera poses inverted (camera in target)": table(encode(tool0, "kuka", "mm"),
                                                                  encode(target, "rotvec", "m", True)),
        "CSV 6+6, proper Euler zxz (static, deg) on both sides, both inverted": table(
            encode(tool0, "zxz", "mm", True), encode(target, "zxz", "m", True)),
        "CSV 7+7, quaternions x y z w, metres": table(encode(tool0, "xyzw", "m"), encode(target, "xyzw", "m")),
        "CSV 16+16, 4x4 matrices, metres": table(encode(tool0, "matrix", "m"), encode(target, "matrix", "m")),
    }
    print(f"{args.postures} postures; read_any: median of {args.repeats}; command: one run in a fresh process\n")
    print("| log | read + inference (s) | + checks + writing the session (s) | `handeye import` command (s) | "
          "reading right |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, text) in enumerate(logs.items()):
            path = Path(tmp) / f"log{k}.csv"
            path.write_text(text)
            times = []
            for _ in range(args.repeats):
                start = time.perf_counter()
                session = read_any(path)
                times.append(time.perf_counter() - start)
            got = np.array([p.tool0_in_base for p in session.postures])
            right = bool(np.max(np.abs(got - tool0)) < 1e-6 and session.setup == "eye_in_hand")
            written = []
            for r in range(args.repeats):
                start = time.perf_counter()
                import_to_session(ImportOptions(sources=(str(path),), output=str(Path(tmp) / f"w{k}_{r}")))
                written.append(time.perf_counter() - start)
            start = time.perf_counter()
            done = subprocess.run([sys.executable, "-m", "handeye.station", "import", str(path), "-o",
                                   str(Path(tmp) / f"s{k}")], capture_output=True, text=True)
            command = time.perf_counter() - start
            if done.returncode != 0:
                raise SystemExit(f"handeye import failed on {name}: {done.stderr.strip()}")
            print(f"| {name} | {statistics.median(times):.2f} | {statistics.median(written):.2f} | {command:.2f} | "
                  f"{'yes' if right else 'NO'} |")
    print("\n" + json.dumps({"postures": args.postures, "python": sys.version.split()[0]}))


if __name__ == "__main__":
    main()
