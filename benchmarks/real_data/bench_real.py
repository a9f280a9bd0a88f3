"""Every method on the data sets measured on real robots (../shared/datasets), scored alike.

Run from the repository root:

    python benchmarks/real_data/bench_real.py [repeats]

For each set: d_org (eq. 22) of the same three target-frame points over ALL postures (the measure
of issue 3), the AX = XB rotation residual in degrees (RMS over all posture pairs of the angle
between R_A R_X and R_X R_B, eq. 16), the 5-fold posture cross-validation (src/handeye/calibration/crossval.py:
held-out board points against the training postures' mean points; the same definition for every
method; once with posture i in fold i mod 5, and as the mean over ``repeats`` random 5-fold splits,
default 20, the same splits for every method, because which method wins one split is partly the
split's doing), d_org over the postures the default keeps, the distance to the set's published reference
where there is one (another tool's estimate, not truth), and the solve time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.classic import CLASSIC_METHODS
from handeye.calibration.crossval import cross_validate
from handeye.base.errors import CalibrationError
from handeye.calibration.metrics import d_org, fixed_points
from handeye.calibration.solve import ALL_METHODS, DEFAULT_METHOD, calibrate, problem_from_session
from handeye.geometry.transforms import invert_transforms
from handeye.station.importers import read_any
from handeye.station.opencv_reference import OPENCV_METHODS, opencv_available, solve_opencv

#: Random 5-fold splits averaged in the repeated cross-validation (one split's ranking is partly the split's).
REPEATS = 20
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


def rotation_residual_deg(problem, x) -> float:
    """RMS over all posture pairs of the angle between ``R_A R_X`` and ``R_X R_B`` (eq. 16), degrees."""
    i, j = np.triu_indices(problem.n, 1)
    a = invert_transforms(problem.hand[i]) @ problem.hand[j]
    b = problem.target2cam[i] @ invert_transforms(problem.target2cam[j])
    m = np.swapaxes(a[:, :3, :3] @ x[:3, :3], 1, 2) @ (x[:3, :3] @ b[:, :3, :3])
    angle = np.degrees(np.arccos(np.clip((np.trace(m, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)))
    return float(np.sqrt(np.mean(angle**2)))


def ours(method: str):
    """``solve(problem) -> (X, runtime_s)`` of one of the package's methods."""
    def solve(problem):
        result = calibrate(problem, method)
        return result.x, result.runtime_s
    return solve


def solvers(ocv) -> dict:
    """Every method to compare, ``name -> solve(problem) -> (X, runtime_s or nan)`` (ours, then OpenCV's)."""
    out = {m: ours(m) for m in ALL_METHODS if m != "mcy"}
    out.update({m: (lambda p, f=f: (f(p), float("nan"))) for m, f in ocv.items()})
    return out


def split_orders(n: int, repeats: int, seed: int = 5) -> list[np.ndarray]:
    """Posture orders for repeated 5-fold CV: fold ``i mod 5`` of a random order is a random split (the same for every method)."""
    rng = np.random.default_rng(seed)
    return [rng.permutation(n) for _ in range(repeats)]


def score(problem, solve, keep=None, orders=()):
    """``(d_org all, rotation residual, 5-fold CV, d_org over keep, X, runtime, repeated CV)`` of one method,
    or the failure text. The repeated CV is the mean over the random splits ``orders`` (nan without)."""
    try:
        x, runtime = solve(problem)
    except CalibrationError as exc:
        return str(exc)
    if not np.all(np.isfinite(x)):
        return "not finite"
    keep = np.ones(problem.n, bool) if keep is None else keep
    score_all = d_org(fixed_points(problem.hand, x, problem.compact.points))
    score_in = d_org(fixed_points(problem.hand[keep], x, problem.compact.points[keep]))
    cv = cross_validate(problem, lambda p: solve(p)[0]).mean_mm
    repeated = [cross_validate(problem.subset(order), lambda p: solve(p)[0]).mean_mm for order in orders]
    return score_all, rotation_residual_deg(problem, x), cv, score_in, x, runtime, float(np.mean(repeated) if orders else np.nan)


def main():
    if not DATASETS.is_dir():
        sys.exit(f"no data sets at {DATASETS}")
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else REPEATS
    methods = solvers(opencv_methods())
    for name, (file, options) in SETS.items():
        session = read_any(DATASETS / name / file if file else DATASETS / name, **options)
        problem = problem_from_session(session)
        default = calibrate(problem)
        keep = ~np.isin(problem.posture_ids, default.outliers)
        orders = split_orders(problem.n, repeats)
        rows = []
        for method, solve in methods.items():
            result = score(problem, solve, keep, orders)
            if isinstance(result, str):
                rows.append((method, None, None, None, None, None, result, None))
                continue
            score_all, rot_res, cv, score_in, x, runtime, rep_cv = result
            ref = ""
            if name in REFERENCES:
                t, rot = REFERENCES[name]
                angle = np.degrees((Rotation.from_matrix(x[:3, :3]) * rot.inv()).magnitude())
                ref = f"{np.linalg.norm(x[:3, 3] - t):.2f} mm, {angle:.3f} deg"
            rows.append((method, score_all, rot_res, cv, score_in, runtime, ref, rep_cv))
        valid = [r for r in rows if r[1] is not None]
        best_ocv = min((r[1] for r in valid if r[0].startswith("opencv")), default=np.nan)
        best_classic = min((r[2] for r in valid if r[0] in CLASSIC_METHODS), default=np.nan)
        best_cv = {m: min((r[3] for r in valid if r[0] != m), default=np.nan) for m in (r[0] for r in valid)}
        best_rep = {m: min((r[7] for r in valid if r[0] != m), default=np.nan) for m in (r[0] for r in valid)}
        print(f"\n### {name}: {problem.n} postures, {problem.setup}; {DEFAULT_METHOD} outliers: {default.outliers or 'none'}\n")
        print("| method | d_org all postures (mm) | vs best OpenCV | AX=XB rotation residual (deg) | vs best classic "
              f"| 5-fold CV (mm) | vs best other | 5-fold CV, {repeats} random splits (mm) | vs best other "
              "| d_org default's inliers (mm) | to published reference | solve (ms) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for method, s_all, rot_res, cv, s_in, runtime, ref, rep_cv in rows:
            if s_all is None:
                print(f"| {method} | - | - | - | - | - | - | - | - | - | {ref} | - |")
                continue
            ms = "-" if np.isnan(runtime) else f"{1000 * runtime:.1f}"
            bold = "**" if method == DEFAULT_METHOD else ""
            print(f"| {bold}{method}{bold} | {s_all:.3f} | {s_all / best_ocv:.3f} | {rot_res:.4f} | {rot_res / best_classic:.2f} "
                  f"| {cv:.3f} | {cv / best_cv[method]:.3f} | {rep_cv:.3f} | {rep_cv / best_rep[method]:.3f} "
                  f"| {s_in:.3f} | {ref} | {ms} |")


if __name__ == "__main__":
    main()
