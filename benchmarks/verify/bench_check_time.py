"""A check's robot time against the full capture's, over many seeds, without running the checks.

Per seed: a 30-posture baseline captured and solved on the embedded mock station (as
``bench_verify.py``), then only the posture choice of ``handeye verify`` (``station.verify.check._chosen``,
K = 5) from where the mock arm stands at power-up; the ratio is the chosen path's time (from there
through the postures in their visiting order, synchronised moves) over the capture's
(``verify_plan.capture_time``), which is what the mock arm records for both. One process.

Usage:
    python benchmarks/verify/bench_check_time.py [--seeds 300-399] [--out check_time.jsonl]
    python benchmarks/verify/bench_check_time.py --summary check_time.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from handeye.robot.kinematics import load_robot
from handeye.calibration.session import read_session
from handeye.mocks.station import DEFAULT_START
from handeye.station.capture.loop import capture
from handeye.station.config.station import default_config
from handeye.station.runtime import open_station
from handeye.station.verify.check import _chosen, session_baseline
from handeye.station.verify.plan import capture_time, path_time_along


def one_seed(seed: int) -> dict:
    config = default_config().as_mock()
    config = replace(config, mock=replace(config.mock, seed=seed), plan=replace(config.plan, seed=seed))
    robot = load_robot(config.robot)
    here = np.asarray(DEFAULT_START, float)
    with tempfile.TemporaryDirectory(prefix="bench-check-time-") as tmp:
        folder = Path(tmp) / "base"
        with open_station(config, session_dir=folder) as link:
            capture(config, folder, link)
            motion = link.mock.arm.motion_s
        session = read_session(folder)
        base = session_baseline(config, session, folder)
        notes: list = []
        numbers, joints = _chosen(config, session, base, robot, here, 5, notes.append)
        full = capture_time(robot, session.extra["capture"])
    return {"seed": seed, "ratio": path_time_along(robot, here, joints) / full, "numbers": numbers,
            "capture_time_s": full, "capture_motion_s": motion, "notes": notes}


def summary(path: Path) -> str:
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    ratio = np.array([r["ratio"] for r in rows])
    return (f"{len(rows)} seeds: check / capture robot time median {np.median(ratio):.3f}, max {ratio.max():.3f}, "
            f"above 0.18: {int(np.sum(ratio > 0.18))}, above 0.2: {int(np.sum(ratio >= 0.2))}, "
            f"with a note: {sum(1 for r in rows if r['notes'])}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="300-399", help="first-last")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/verify/check_time.jsonl"))
    parser.add_argument("--summary", type=Path)
    args = parser.parse_args(argv)
    if args.summary:
        print(summary(args.summary))
        return 0
    first, last = (int(v) for v in args.seeds.split("-"))
    for seed in range(first, last + 1):
        row = one_seed(seed)
        with args.out.open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(row) + "\n")
        print(seed, round(row["ratio"], 4), row["notes"], flush=True)
    print(summary(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
