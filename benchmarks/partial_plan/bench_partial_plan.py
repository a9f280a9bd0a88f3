"""How much the planner's ChArUco partial views widen the rotation spread (issue 37).

For each seed, the planner plans the same postures twice at the embedded mock station's start posture
(its board, nominal mount, default sampling, no cell): a checkerboard plan (whole board in every view,
as before) and a ChArUco plan (``station.capture.partial_plan``: partial views swapped in where they
widen the rotation-axis spread). Prints per seed the two spreads, the partial postures and their share
of the board in view, and the predicted accuracy of both plans (the planner's simulated sessions); the
medians at the end.

    python benchmarks/partial_plan/bench_partial_plan.py [--seeds 0 1 2 ...] [--postures 30] [--cone 35]
        [--json benchmarks/partial_plan/results.json]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from handeye.geometry import STATION_BOARD, STATION_CHARUCO, invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.robot import ViewSampling, load_robot
from handeye.station.capture.planning import plan_postures


def _plan(robot, board, seed: int, postures: int, cone: float):
    start_view = invert_transforms(robot.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    centre = DEFAULT_BOARD[:3, 3]
    side = -np.array([centre[0], centre[1], 0.0])
    sampling = ViewSampling(cone_deg=cone, side=tuple(side / np.linalg.norm(side)))
    return plan_postures(robot, DEFAULT_START, start_view, DEFAULT_MOUNT, board, postures, sampling, seed=seed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    parser.add_argument("--postures", type=int, default=30)
    parser.add_argument("--cone", type=float, default=35.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    robot = load_robot("IRB1400")
    rows = []
    for seed in args.seeds:
        started = time.perf_counter()
        whole = _plan(robot, STATION_BOARD, seed, args.postures, args.cone)
        t_whole = time.perf_counter() - started
        started = time.perf_counter()
        charuco = _plan(robot, STATION_CHARUCO, seed, args.postures, args.cone)
        t_charuco = time.perf_counter() - started
        row = {"seed": seed, "spread_whole_deg": whole.score.rotation_axis_spread_deg,
               "spread_charuco_deg": charuco.score.rotation_axis_spread_deg, "partial": len(charuco.partial),
               "in_view": [round(p.in_view, 3) for p in charuco.partial],
               "sigma_mm_whole": whole.score.predicted_sigma_mm, "sigma_mm_charuco": charuco.score.predicted_sigma_mm,
               "sigma_deg_whole": whole.score.predicted_sigma_deg, "sigma_deg_charuco": charuco.score.predicted_sigma_deg,
               "plan_s_whole": t_whole, "plan_s_charuco": t_charuco}
        rows.append(row)
        print(f"seed {seed}: spread {row['spread_whole_deg']:.1f} -> {row['spread_charuco_deg']:.1f} deg; "
              f"{row['partial']} partial postures ({', '.join(f'{100 * v:.0f} %' for v in row['in_view'])} in view); "
              f"predicted {row['sigma_mm_whole']:.3f} -> {row['sigma_mm_charuco']:.3f} mm, "
              f"{row['sigma_deg_whole']:.4f} -> {row['sigma_deg_charuco']:.4f} deg; plan {t_whole:.1f} s / {t_charuco:.1f} s",
              flush=True)
    med = lambda key: float(np.median([r[key] for r in rows]))  # noqa: E731
    summary = {k: med(k) for k in ("spread_whole_deg", "spread_charuco_deg", "partial", "sigma_mm_whole",
                                   "sigma_mm_charuco", "sigma_deg_whole", "sigma_deg_charuco", "plan_s_whole",
                                   "plan_s_charuco")}
    summary["in_view_min"] = float(min((v for r in rows for v in r["in_view"]), default=1.0))
    print("median: " + ", ".join(f"{k} {v:.4g}" for k, v in summary.items()))
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"args": vars(args), "rows": rows, "median": summary}, handle, indent=1)


if __name__ == "__main__":
    main()
