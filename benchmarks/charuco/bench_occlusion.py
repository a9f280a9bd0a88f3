"""ChArUco against the checkerboard with occluded postures (issue 37): the whole ``handeye demo`` job.

Four demo runs on the embedded mock station (same seed, same plan settings): the checkerboard and the
ChArUco board, each unoccluded and with ``mock.occlude`` = 30 % of the postures covered by a band over
a drawn 20-40 % of the board. Prints, per run, the postures captured, the corners per posture, the
recovered mount's error against the hidden truth and the verdict; then the ratio of the occluded
ChArUco session's error to the unoccluded checkerboard demo's (target <= 1.1, rotation and translation).

    python benchmarks/charuco/bench_occlusion.py [--seeds 7 8 9] [--json benchmarks/charuco/results.json]
    python benchmarks/charuco/bench_occlusion.py --rows benchmarks/charuco/results_seeds.json   # summary only

Over many seeds (the errors are a few thousandths of a degree, and differ from seed to seed as much as
between boards) the comparison is of the RMS and the median over seeds of each run's error, with a 95 %
bootstrap interval of the ratio (seeds resampled with their pairs: the same seed's two runs share the arm
errors and the plan).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from handeye.calibration.session import read_session
from handeye.geometry import STATION_BOARD
from handeye.geometry.targets import STATION_CHARUCO, STATION_CIRCLES
from handeye.mocks.printed_targets import Occlusion
from handeye.station.demo import DemoOptions, run_demo

RUNS = (("checkerboard", None, None), ("checkerboard, 30 % occluded", None, Occlusion(0.3, (0.2, 0.4))),
        ("charuco", STATION_CHARUCO, None), ("charuco, 30 % occluded", STATION_CHARUCO, Occlusion(0.3, (0.2, 0.4))),
        ("circles", STATION_CIRCLES, None))
#: The runs of a default call (the circle grid, 4 x 11 circles 40 mm apart, by ``--runs 4``).
DEFAULT_RUNS = (0, 1, 2, 3)


def one_run(name: str, board, occlude, seed: int, folder: Path) -> dict:
    out = run_demo(DemoOptions(str(folder / f"{name.replace(' ', '_').replace(',', '').replace('%', 'pct')}_{seed}"),
                               30, seed=seed, report=False, board=board, occlude=occlude))
    session = read_session(out["session"])
    corners = [len(p.points_mm) for p in session.postures]
    return {"run": name, "seed": seed, "postures_captured": out["postures_captured"],
            "partial_postures": sum(1 for p in session.postures if p.corner_ids is not None
                                   and len(p.points_mm) < (board or STATION_BOARD).count),
            "corners_min": min(corners), "corners_median": sorted(corners)[len(corners) // 2],
            "rotation_error_deg": out["errors"]["rotation_error_deg"],
            "translation_error_mm": out["errors"]["translation_error_mm"], "passed": out["verdict"]["passed"]}


def ratio_summary(rows: list, run: str, base: str = "checkerboard", draws: int = 4000) -> dict:
    """RMS and median over the seeds both runs have of ``run``'s error against ``base``'s, with 95 % bootstrap
    intervals (seeds resampled in pairs), for rotation and translation."""
    import numpy as np  # noqa: PLC0415

    by = {(r["run"], r["seed"]): r for r in rows}
    seeds = sorted(s for (name, s) in by if name == run and (base, s) in by)
    out: dict = {"run": run, "base": base, "seeds": len(seeds)}
    rng = np.random.default_rng(37)
    for key in ("rotation_error_deg", "translation_error_mm"):
        a = np.array([by[(run, s)][key] for s in seeds])
        b = np.array([by[(base, s)][key] for s in seeds])
        pick = rng.integers(0, len(seeds), (draws, len(seeds)))
        for stat, f in (("rms", lambda x: np.sqrt(np.mean(x**2, axis=-1))), ("median", lambda x: np.median(x, axis=-1))):
            boot = f(a[pick]) / f(b[pick])
            out[f"{key}_{stat}"] = [float(f(a)), float(f(b))]
            out[f"{key}_{stat}_ratio"] = float(f(a) / f(b))
            out[f"{key}_{stat}_ratio_95"] = [float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))]
    return out


def print_summary(rows: list) -> None:
    """The ratio of every run's error to the unoccluded checkerboard's, over the seeds."""
    for run in [name for name, _, _ in RUNS[1:] if any(r["run"] == name for r in rows)]:
        s = ratio_summary(rows, run)
        if not s["seeds"]:
            continue
        print(f"{run} / checkerboard over {s['seeds']} seeds:")
        for key, unit in (("rotation_error_deg", "deg"), ("translation_error_mm", "mm")):
            for stat in ("rms", "median"):
                a, b = s[f"{key}_{stat}"]
                lo, hi = s[f"{key}_{stat}_ratio_95"]
                print(f"  {key.split('_')[0]:11s} {stat:6s} {a:.4f} / {b:.4f} {unit} = {s[f'{key}_{stat}_ratio']:.2f}x "
                      f"(95 % bootstrap {lo:.2f}-{hi:.2f}x; target <= 1.1)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[7])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--only", help="run only the runs whose name starts with this (e.g. charuco)")
    parser.add_argument("--runs", nargs="+", type=int, help="run only these runs (0-4: checkerboard, occluded "
                        "checkerboard, charuco, occluded charuco, circles; default 0-3)")
    parser.add_argument("--rows", nargs="+", help="summarise the rows of these JSON files (no runs)")
    args = parser.parse_args(argv)
    if args.rows:
        print_summary([r for f in args.rows for r in json.loads(Path(f).read_text())])
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in args.seeds:
            for k, (name, board, occlude) in enumerate(RUNS):
                if (args.only and not name.startswith(args.only)) or k not in (args.runs or (range(len(RUNS)) if args.only else DEFAULT_RUNS)):
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
    if len(args.seeds) > 1:
        print_summary(rows)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
