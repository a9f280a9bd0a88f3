"""Planning time with the whole arm checked: 30 postures in the benchmark cell of issue 21.

The cell: the floor, a cabinet beside the robot's base where the upper arm swings (behind and beside
axis 1), a post the upper arm passes, and the board's stand (from the board's pose). Every link of the arm
(base, links 1-3 and the wrist) and what the flange carries are checked against every
volume, and the robot file's self-collision pairs (the camera against link 3, ...), by the
capture's own planner (``station.capture.planning.plan_postures``): drawing, veto, the moves' conservative
advancement, the order repaired, the score (five simulated calibrations). The figure is the median
wall-clock time (``time.perf_counter``) of ``--runs`` plans (seeds 0, 1, ...); each plan's processor time
(``time.process_time``) is printed beside it (what the plan costs when other jobs share the cores).

Usage:
    python benchmarks/whole_arm/bench_whole_arm.py [--runs 3] [--postures 30] [--json results.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

from handeye.robot.cell import DEFAULT_CARRIED, Box, CellModel, Cylinder, Floor
from handeye.geometry.board import BoardGeometry
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.cell.plan import CellCheck
from handeye.station.capture.planning import plan_postures

TARGET_S = 10.0
BOARD = BoardGeometry((13, 8), 30.0)
#: The benchmark cell of issue 21 (the tests use the same one).
CELL = CellModel((Floor("floor", 0.0),
                  Box("cabinet beside the base", (-700.0, -900.0, 0.0), (-100.0, -420.0, 1600.0)),
                  Cylinder("post", (380.0, -380.0), 50.0, (0.0, 1400.0))),
                 DEFAULT_CARRIED, stand_margin_mm=50.0, stand_depth_mm=100.0)


def plan_once(postures: int, seed: int, cell: CellModel = CELL):
    """One plan in ``cell`` from the mock station's start view: ``(seconds, processor seconds, plan)``."""
    robot = load_robot("IRB1400")
    view = invert_transforms(robot.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    started, cpu = time.perf_counter(), time.process_time()
    plan = plan_postures(robot, DEFAULT_START, view, DEFAULT_MOUNT, BOARD, count=postures, seed=seed,
                         cell=CellCheck(cell))
    return time.perf_counter() - started, time.process_time() - cpu, plan


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--postures", type=int, default=30)
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args(argv)
    times, rows = [], []
    for seed in range(args.runs):
        seconds, cpu, plan = plan_once(args.postures, seed)
        times.append(seconds)
        rows.append({"seed": seed, "seconds": round(seconds, 2), "cpu_s": round(cpu, 2), "postures": len(plan.joints_deg),
                     "rejected_postures": plan.score.rejected_postures, "rejected_moves": plan.score.rejected_moves,
                     "rejections": list(plan.score.rejections)})
        print(f"seed {seed}: {seconds:.2f} s ({cpu:.2f} s of processor), {len(plan.joints_deg)} postures, {plan.score.rejected_postures} postures "
              f"and {plan.score.rejected_moves} moves rejected ({'; '.join(plan.score.rejections)})")
    median = statistics.median(times)
    print(f"median {median:.2f} s, max {max(times):.2f} s for {args.postures} postures (target < {TARGET_S:g} s); "
          f"load average {os.getloadavg()[0]:.1f}, {os.cpu_count()} cores, Python {platform.python_version()}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump({"median_s": round(median, 2), "max_s": round(max(times), 2), "runs": rows,
                       "load_average": os.getloadavg()[0], "cores": os.cpu_count()}, out, indent=1)
    return 0 if median < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
