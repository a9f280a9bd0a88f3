"""An exact arm (no deviations from its DH table): does ``calibrate --kinematics`` leave the camera where
the camera-only calibration put it, and call the offsets consistent with zero? (issue 36, Must hold 2)

Per seed: a plan of 30 postures (``synthetic.make_scene``), the arm exactly its table, 0.1 px corners and
0.002 deg joint repeatability (``arm_synthetic.deviated_session`` with zero deviations). Printed per seed:
the chi-square of the identified offsets against zero and its 1 % limit, the camera pose's change
against the camera-only fit as the RMS of its six components over their one-sigmas, and its
Mahalanobis distance (chi-square, 6 degrees of freedom, 1 % limit 16.8). One JSON line per seed
(``--out``), the summary on stdout.

Usage:
    python benchmarks/kinematics/bench_exact_arm.py [--seeds 20] [--out benchmarks/kinematics/results_exact.jsonl]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from handeye.calibration.arm_identification import identify_arm
from handeye.calibration.arm_parameters import parameter_names
from handeye.calibration.arm_synthetic import deviated_session
from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import SceneConfig, make_scene
from handeye.station.kinematics_step import kinematics_json

from bench_kinematics import run_seeds


def one_seed(seed: int) -> dict:
    scene = make_scene(SceneConfig(postures=30, seed=seed))
    ident = identify_arm(problem_from_session(deviated_session(scene, np.zeros(len(parameter_names())),
                                                               seed=seed + 100)))
    entry = kinematics_json(ident)
    zero, change = entry["consistent_with_zero"], entry["camera_pose_change"]
    return {"seed": seed, "consistent_with_zero": zero["consistent"], "chi_square": zero["statistic"],
            "limit": zero["limit"], "parameters": zero["parameters"], "change_rms_in_sigmas": change["rms_in_sigmas"],
            "change_mahalanobis_squared": change["mahalanobis_squared"],
            "change_within_uncertainty": change["within_uncertainty"]}


def summary(rows: list[dict]) -> dict:
    rms = np.array([r["change_rms_in_sigmas"] for r in rows])
    return {"seeds": len(rows), "consistent_with_zero": float(np.mean([r["consistent_with_zero"] for r in rows])),
            "chi_square_range": [min(r["chi_square"] for r in rows), max(r["chi_square"] for r in rows)],
            "limit": rows[0]["limit"], "change_below_one_sigma": float(np.mean(rms < 1.0)),
            "change_rms_in_sigmas_median": float(np.median(rms)), "change_rms_in_sigmas_max": float(rms.max()),
            "change_rms_in_sigmas_overall": float(np.sqrt(np.mean(rms ** 2))),
            "change_within_uncertainty": float(np.mean([r["change_within_uncertainty"] for r in rows]))}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--first", type=int, default=1)
    p.add_argument("--out", default="benchmarks/kinematics/results_exact.jsonl")
    args = p.parse_args(argv)
    rows = run_seeds(range(args.first, args.first + args.seeds), one_seed, args.out, lambda row: (
        f"chi-square {row['chi_square']:.1f} (limit {row['limit']:.1f}), camera change "
        f"{row['change_rms_in_sigmas']:.2f} sigma RMS, Mahalanobis {row['change_mahalanobis_squared']:.2f}"))
    print(json.dumps(summary(rows), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
