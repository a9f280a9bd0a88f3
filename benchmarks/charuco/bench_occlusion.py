"""ChArUco against the checkerboard with occluded postures (issue 37): the whole ``handeye demo`` job.

Four demo runs on the embedded mock station (same seed, same plan settings): the checkerboard and the
ChArUco board, each unoccluded and with ``mock.occlude`` = 30 % of the postures covered by a band over
a drawn 20-40 % of the board. Prints, per run, the postures captured, the corners per posture, the
recovered mount's error against the hidden truth and the verdict; then the ratio of the occluded
ChArUco session's error to the unoccluded checkerboard demo's (target <= 1.1, rotation and translation).

    python benchmarks/charuco/bench_occlusion.py [--seeds 7 8 9] [--json benchmarks/charuco/results.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from handeye.calibration.session import read_session
from handeye.geometry.targets import STATION_CHARUCO
from handeye.mocks.printed_targets import Occlusion
from handeye.station.demo import DemoOptions, run_demo

RUNS = (("checkerboard", None, None), ("checkerboard, 30 % occluded", None, Occlusion(0.3, (0.2, 0.4))),
        ("charuco", STATION_CHARUCO, None), ("charuco, 30 % occluded", STATION_CHARUCO, Occlusion(0.3, (0.2, 0.4))))


def one_run(name: str, board, occlude, seed: int, folder: Path) -> dict:
    out = run_demo(DemoOptions(str(folder / f"{name.replace(' ', '_').replace(',', '').replace('%', 'pct')}_{seed}"),
                               30, seed=seed, report=False, board=board, occlude=occlude))
    session = read_session(out["session"])
    corners = [len(p.points_mm) for p in session.postures]
    return {"run": name, "seed": seed, "postures_captured": out["postures_captured"],
            "partial_postures": sum(1 for p in session.postures if p.corner_ids is not None and len(p.points_mm) < 104),
            "corners_min": min(corners), "corners_median": sorted(corners)[len(corners) // 2],
            "rotation_error_deg": out["errors"]["rotation_error_deg"],
            "translation_error_mm": out["errors"]["translation_error_mm"], "passed": out["verdict"]["passed"]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[7])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--only", help="run only the runs whose name starts with this (e.g. charuco)")
    parser.add_argument("--runs", nargs="+", type=int, help="run only these runs (0-3: checkerboard, occluded "
                        "checkerboard, charuco, occluded charuco)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in args.seeds:
            for k, (name, board, occlude) in enumerate(RUNS):
                if (args.only and not name.startswith(args.only)) or (args.runs and k not in args.runs):
                    continue
                row = one_run(name, board, occlude, seed, Path(tmp))
                rows.append(row)
                print(f"seed {seed}  {name:28s} captured {row['postures_captured']:2d} (partial {row['partial_postures']:2d}), "
                      f"corners min {row['corners_min']:3d} median {row['corners_median']:3d}; error "
                      f"{row['rotation_error_deg']:.4f} deg, {row['translation_error_mm']:.3f} mm; "
                      f"{'PASS' if row['passed'] else 'FAIL'}", flush=True)
    for seed in args.seeds if not (args.only or args.runs) else ():
        by = {r["run"]: r for r in rows if r["seed"] == seed}
        base, occ = by["checkerboard"], by["charuco, 30 % occluded"]
        print(f"seed {seed}: occluded ChArUco / unoccluded checkerboard: rotation "
              f"{occ['rotation_error_deg'] / base['rotation_error_deg']:.2f}x, translation "
              f"{occ['translation_error_mm'] / base['translation_error_mm']:.2f}x (target <= 1.1); checkerboard "
              f"occluded captured {by['checkerboard, 30 % occluded']['postures_captured']} of 30")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
