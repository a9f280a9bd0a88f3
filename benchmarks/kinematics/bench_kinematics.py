"""The arm's kinematic identification (``calibrate --kinematics``) against a known truth, per seed.

Per seed (issue 36's Must hold): a plan of 30 postures of the IRB 1400 looking at the station board
(``synthetic.make_scene``: views at 0.7-1.2 m), a true arm that differs from its DH table by joint
zero errors uniform in +-0.05 deg on J2-J5 and link errors uniform in +-0.3 mm on every non-zero DH
length (d1, a1, a2, a3, d4, d6), joint repeatability 0.002 deg, the XB3's corners triangulated with
0.1 px of pixel noise (``arm_synthetic.deviated_session``: the controller reports the nominal flange,
the camera sees from the true one). The default estimator (camera only) and the identification run
on it; then 100 held-out postures (another plan's) give the error of a point 750 mm along the camera
axis in the board's frame, with the camera-only calibration and the nominal arm, and with the
identified arm, against the truth, next to what the identification predicts for those postures.

NOT the rendered mock station: the corners are drawn from the stereo noise model, not detected in
rendered images (50 rendered captures of 30 postures would take hours on this machine).

Output: one JSON line per seed (``--out``), the summary on stdout, ``--figure`` a PNG.

Usage:
    python benchmarks/kinematics/bench_kinematics.py [--seeds 50] [--out results.jsonl] [--figure kinematics.png]
    python benchmarks/kinematics/bench_kinematics.py --summary results.jsonl [--figure kinematics.png]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from handeye.calibration.arm_identification import identify_arm
from handeye.calibration.arm_parameters import corrected_robot, parameter_names
from handeye.calibration.arm_synthetic import deviated_session, random_deviation
from handeye.calibration.solve import problem_from_session
from handeye.calibration.standoff import measured_standoff, predicted_standoff
from handeye.calibration.synthetic import SceneConfig, make_scene

NAMES = parameter_names()
LINKS = ("d1", "a1", "a2", "a3", "d4", "d6")


def one_seed(seed: int, postures: int = 30, held_out: int = 100) -> dict:
    rng = np.random.default_rng(seed)
    deviation = random_deviation(rng, 0.05, 0.3, links=LINKS)
    scene = make_scene(SceneConfig(postures=postures, seed=seed))
    started = time.perf_counter()
    ident = identify_arm(problem_from_session(deviated_session(scene, deviation, seed=seed)))
    seconds = time.perf_counter() - started
    held = make_scene(SceneConfig(postures=held_out, seed=10_000 + seed)).joints_deg
    predicted = predicted_standoff(ident, held)
    true_arm = corrected_robot(scene.robot, deviation)
    with_, without = measured_standoff(true_arm, scene.x_true, scene.target2fixed, scene.robot, ident, held)
    zeros = {}
    for axis in (2, 3, 4, 5):
        j = NAMES.index(f"zero{axis}")
        zeros[f"J{axis}"] = {"true": float(deviation[j]), "value": float(ident.values[j]),
                             "sigma": float(ident.sigma[j]), "status": ident.status[j],
                             "z": float((ident.values[j] - deviation[j]) / ident.sigma[j])}
    row = {"seed": seed, "zeros": zeros, "seconds": seconds}
    row.update(standoff_figures(predicted, with_, without))
    row["not_identifiable"] = [n for n, s in zip(NAMES, ident.status) if s != "identified"]
    return row


def standoff_figures(predicted, with_, without) -> dict:
    """A seed's stand-off figures: measured and predicted RMS, their ratio, and where the measured RMS
    lies in the predicted distribution of one calibration's RMS (``StandoffError.quantile``)."""
    mw, mo = float(np.sqrt(np.mean(with_ ** 2))), float(np.sqrt(np.mean(without ** 2)))
    return {"measured_with_mm": mw, "measured_without_mm": mo,
            "predicted_with_mm": predicted.corrected_rms_mm, "predicted_without_mm": predicted.uncorrected_rms_mm,
            "predicted_with_90_mm": list(predicted.interval(0.9, True)),
            "predicted_without_90_mm": list(predicted.interval(0.9, False)),
            "quantile_with": predicted.quantile(mw, True), "quantile_without": predicted.quantile(mo, False),
            "reduction": mw / mo,
            "predicted_over_measured_with": predicted.corrected_rms_mm / mw,
            "predicted_over_measured_without": predicted.uncorrected_rms_mm / mo}


def inside(rows: list[dict], key: str) -> float | None:
    """Fraction of seeds whose measured RMS lies in the central 90 % of its predicted distribution."""
    q = np.array([r[key] for r in rows if key in r])
    return float(np.mean((q >= 0.05) & (q <= 0.95))) if len(q) else None


def summary(rows: list[dict]) -> dict:
    z = np.array([v["z"] for r in rows for v in r["zeros"].values()])
    red = np.array([r["reduction"] for r in rows])
    pw = np.array([r["predicted_over_measured_with"] for r in rows])
    po = np.array([r["predicted_over_measured_without"] for r in rows])
    within = lambda a: float(np.mean((a >= 0.7) & (a <= 1.5)))  # noqa: E731
    return {"seeds": len(rows), "zeros_within_3_sigma": float(np.mean(np.abs(z) <= 3.0)),
            "z_rms": float(np.sqrt(np.mean(z ** 2))),
            "reduction_median": float(np.median(red)), "reduction_max": float(np.max(red)),
            "reduction_at_most_0.6": float(np.mean(red <= 0.6)),
            "measured_with_median_mm": float(np.median([r["measured_with_mm"] for r in rows])),
            "measured_without_median_mm": float(np.median([r["measured_without_mm"] for r in rows])),
            "predicted_over_measured_with_median": float(np.median(pw)),
            "predicted_over_measured_with_in_0.7_1.5": within(pw),
            "predicted_over_measured_without_median": float(np.median(po)),
            "predicted_over_measured_without_in_0.7_1.5": within(po),
            "predicted_over_measured_with_range": [float(pw.min()), float(pw.max())],
            "predicted_over_measured_without_range": [float(po.min()), float(po.max())],
            "measured_in_predicted_90_with": inside(rows, "quantile_with"),
            "measured_in_predicted_90_without": inside(rows, "quantile_without"),
            "seconds_median": float(np.median([r["seconds"] for r in rows]))}


def figure(rows: list[dict], path: Path) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 3.6), dpi=100, layout="constrained")
    a, b, c = fig.subplots(1, 3)
    z = np.array([v["z"] for r in rows for v in r["zeros"].values()])
    a.hist(z, bins=np.linspace(-4, 4, 33), color="#1f5fa8")
    a.axvline(-3, color="#c62828", ls="--")
    a.axvline(3, color="#c62828", ls="--")
    a.set_title(f"J2-J5 zeros: (estimate - truth) / sigma\n{np.mean(np.abs(z) <= 3) * 100:.1f} % within 3 sigma",
                fontsize=10)
    w = np.array([r["measured_with_mm"] for r in rows])
    wo = np.array([r["measured_without_mm"] for r in rows])
    b.scatter(wo, w, s=14, color="#1f5fa8")
    top = float(wo.max()) * 1.05
    b.plot([0, top], [0, 0.6 * top], color="#c62828", ls="--", label="0.6x")
    b.set_xlabel("camera only, nominal arm (mm)")
    b.set_ylabel("with the identified arm (mm)")
    b.set_title("RMS error at 750 mm, 100 held-out postures", fontsize=10)
    b.legend(fontsize=8)
    pw = [r["predicted_over_measured_with"] for r in rows]
    po = [r["predicted_over_measured_without"] for r in rows]
    c.scatter(range(len(rows)), po, s=14, color="#ef8a17", label="without correction")
    c.scatter(range(len(rows)), pw, s=14, color="#1f5fa8", label="with correction")
    for level in (0.7, 1.5):
        c.axhline(level, color="#c62828", ls="--")
    c.set_xlabel("seed")
    c.set_ylabel("predicted / measured")
    c.set_title("predicted vs measured stand-off error", fontsize=10)
    c.legend(fontsize=8)
    for ax in (a, b, c):
        ax.grid(True, alpha=0.25)
    fig.savefig(path, format="png", dpi=100, facecolor="white")


def run_seeds(seeds, one_seed, out_path, describe) -> list:
    """``one_seed(seed)`` for every seed: each row written to ``out_path`` (JSON lines) as it comes, and
    ``seed N: describe(row)`` on stderr; the rows."""
    rows = []
    with open(out_path, "w", encoding="utf-8") as out:
        for seed in seeds:
            row = one_seed(seed)
            rows.append(row)
            out.write(json.dumps(row) + "\n")
            out.flush()
            print(f"seed {seed}: {describe(row)}", file=sys.stderr, flush=True)
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=50)
    p.add_argument("--first", type=int, default=1)
    p.add_argument("--out", default="benchmarks/kinematics/results.jsonl")
    p.add_argument("--figure", default=None)
    p.add_argument("--summary", default=None, help="print the figures of an existing results file")
    args = p.parse_args(argv)
    if args.summary:
        rows = [json.loads(line) for line in Path(args.summary).read_text().splitlines() if line.strip()]
    else:
        rows = run_seeds(range(args.first, args.first + args.seeds), one_seed, args.out, lambda row: (
            f"reduction {row['reduction']:.3f}, predicted/measured with {row['predicted_over_measured_with']:.2f} "
            f"without {row['predicted_over_measured_without']:.2f}, z {[round(v['z'], 2) for v in row['zeros'].values()]}"))
    print(json.dumps(summary(rows), indent=1))
    if args.figure:
        figure(rows, Path(args.figure))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
