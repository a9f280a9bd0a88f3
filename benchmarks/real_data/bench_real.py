"""Every method on the data sets measured on real robots (../shared/datasets), scored alike.

Run from the repository root:

    python benchmarks/real_data/bench_real.py

For each set: d_org (eq. 22) of the same three target-frame points over ALL postures (the measure
of issue 3), d_org over the postures the robust default keeps, the distance to the set's published
reference where there is one (another tool's estimate, not truth), and the solve time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.errors import CalibrationError
from handeye.calibration.metrics import d_org, fixed_points
from handeye.calibration.solve import ALL_METHODS, calibrate, problem_from_session
from handeye.station.opencv_reference import OPENCV_METHODS, opencv_available, solve_opencv
from handeye.station.importers import read_any

DATASETS = Path(__file__).resolve().parents[2].parent / "shared" / "datasets"
SETS = {
    "moveit-calibration": ("pose_samples.json", {}),
    "visp-eye-in-hand": ("", {}),
    "camodocal-ar-tag": ("TransformPairsInput.yml", {}),
    "ethz-robot-arm": ("", {}),
    "visp-apps-eye-in-hand": ("", {}),
}
REFERENCES = {  # published estimates (datasets/README.md): position in mm, rotation
    "moveit-calibration": (np.array([0.659, -0.249, 0.830]) * 1000, Rotation.from_euler("XYZ", [0.230, -2.540, 1.950])),
    "visp-eye-in-hand": (np.array([0.05346, -0.00952, -0.04510]) * 1000, Rotation.from_rotvec([-0.02347, -0.07939, 1.57459])),
}


def opencv_methods():
    """OpenCV's methods as ``opencv_<name> -> solve(problem)`` ({} without calibrateHandEye)."""
    if not opencv_available():
        return {}
    return {f"opencv_{n}": (lambda problem, n=n: solve_opencv(problem.hand, problem.target2cam, n)) for n in OPENCV_METHODS}


def main():
    if not DATASETS.is_dir():
        sys.exit(f"no data sets at {DATASETS}")
    ocv = opencv_methods()
    for name, (file, options) in SETS.items():
        session = read_any(DATASETS / name / file if file else DATASETS / name, **options)
        problem = problem_from_session(session)
        robust = calibrate(problem)
        keep = ~np.isin(problem.posture_ids, robust.outliers)
        rows = []
        for method in list(ALL_METHODS) + list(ocv):
            if method == "mcy":
                continue
            try:
                if method in ocv:
                    x, runtime = ocv[method](problem), float("nan")
                else:
                    r = calibrate(problem, method)
                    x, runtime = r.x, r.runtime_s
            except CalibrationError as exc:
                rows.append((method, None, None, None, str(exc)))
                continue
            if not np.all(np.isfinite(x)):
                rows.append((method, None, None, None, "not finite"))
                continue
            score_all = d_org(fixed_points(problem.hand, x, problem.compact.points))
            score_in = d_org(fixed_points(problem.hand[keep], x, problem.compact.points[keep]))
            ref = ""
            if name in REFERENCES:
                t, rot = REFERENCES[name]
                angle = np.degrees((Rotation.from_matrix(x[:3, :3]) * rot.inv()).magnitude())
                ref = f"{np.linalg.norm(x[:3, 3] - t):.2f} mm, {angle:.3f} deg"
            rows.append((method, score_all, score_in, runtime, ref))
        best_ocv = min((r[1] for r in rows if r[0].startswith("opencv") and r[1] is not None), default=np.nan)
        print(f"\n### {name}: {problem.n} postures, {problem.setup}; robust outliers: {robust.outliers or 'none'}\n")
        print("| method | d_org all postures (mm) | vs best OpenCV | d_org robust inliers (mm) | to published reference | solve (ms) |")
        print("|---|---|---|---|---|---|")
        for method, s_all, s_in, runtime, ref in rows:
            if s_all is None:
                print(f"| {method} | - | - | - | {ref} | - |")
                continue
            ms = "-" if np.isnan(runtime) else f"{1000 * runtime:.1f}"
            bold = "**" if method == "robust" else ""
            print(f"| {bold}{method}{bold} | {s_all:.3f} | {s_all / best_ocv:.2f} | {s_in:.3f} | {ref} | {ms} |")


if __name__ == "__main__":
    main()
