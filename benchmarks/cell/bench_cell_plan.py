"""Planning time with the cell checks: 30 postures around the mock station's board, per cell.

Each run plans from the embedded mock station's start view (``station.capture.planning.plan_postures``, the
capture's own planner): drawing the postures, the cell's veto, the shortest-motion order repaired
so every move is clear, and the plan's score (five simulated calibrations). Cells: none (the
planner before the cell checks), the built-in station's (the floor and the board's stand), the
cell of the tests (floor, stand, a cabinet beside the board) and a narrow lane between two walls.
The figure is the median wall-clock time of ``--runs`` plans per cell (seeds 0, 1, ...), with
``time.perf_counter``.

Usage:
    python benchmarks/cell/bench_cell_plan.py [--runs 3] [--postures 30] [--json results.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

from handeye.robot.cell import Box, CellModel, Floor
from handeye.geometry.board import BoardGeometry
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.cell.plan import CellCheck
from handeye.station.config.cell import DEFAULT_CARRIED, DEFAULT_KEEP_OUT
from handeye.station.capture.planning import plan_postures

TARGET_S = 10.0
CELLS = {
    "none (no cell checks)": None,
    "built-in: floor + board stand": CellModel(DEFAULT_KEEP_OUT, DEFAULT_CARRIED),
    "tests: floor + stand + cabinet beside the board": CellModel(
        (Floor("floor", 0.0), Box("cabinet beside the board", (500, 250, 0), (1200, 700, 1400))), DEFAULT_CARRIED),
    "narrow lane between two walls": CellModel(
        (Floor("floor", 0.0), Box("left wall", (380, 200, 0), (2000, 1500, 2500)),
         Box("right wall", (380, -1500, 0), (2000, -250, 2500))), DEFAULT_CARRIED),
}


def plan_once(cell, postures: int, seed: int):
    robot = load_robot("IRB1400")
    view = invert_transforms(robot.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    started = time.perf_counter()
    plan = plan_postures(robot, DEFAULT_START, view, DEFAULT_MOUNT, BoardGeometry((13, 8), 30.0), count=postures,
                         seed=seed, cell=None if cell is None else CellCheck(cell))
    return time.perf_counter() - started, plan


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--postures", type=int, default=30)
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args(argv)
    rows = []
    for name, cell in CELLS.items():
        times, planned, postures, moves = [], [], [], []
        for seed in range(args.runs):
            seconds, plan = plan_once(cell, args.postures, seed)
            times.append(seconds)
            planned.append(len(plan.joints_deg))
            postures.append(plan.score.rejected_postures)
            moves.append(plan.score.rejected_moves)
        rows.append({"cell": name, "median_s": statistics.median(times), "max_s": max(times), "postures": planned,
                     "rejected_postures": postures, "rejected_moves": moves})
    print(f"planning {args.postures} postures, {args.runs} runs per cell; {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    print("| cell | median s | max s | postures planned | rejected postures | rejected moves |")
    print("|---|---:|---:|---|---|---|")
    for r in rows:
        print(f"| {r['cell']} | {r['median_s']:.2f} | {r['max_s']:.2f} | {r['postures']} | {r['rejected_postures']} | "
              f"{r['rejected_moves']} |")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"postures": args.postures, "runs": args.runs, "rows": rows}, handle, indent=2)
    slow = [r["cell"] for r in rows if r["median_s"] > TARGET_S]
    if slow:
        print(f"above the {TARGET_S:g} s target: {', '.join(slow)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
