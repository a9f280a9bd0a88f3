"""The paper's section-4 study, reproduced: every method over sweeps of robot and camera noise and
of the number of postures, many trials per cell, results as CSV, plots and a markdown table.

Each trial draws its own scene (a posture set of the IRB 1400 around the 8x13 board, seed = trial)
and its own noise. Errors are measured against the truth (rotation in degrees, translation in mm)
and by the point measures of the paper, d_org (eq. 22) and d_back (eq. 23), on all board corners
and on the three board points of the plane fit (section 3.1). On the corners every method looks the
same once camera noise is large, because each corner carries its own noise; the three fitted points
average it out and show the differences. ``truth`` is the true X scored by the same point measures.
"""

from __future__ import annotations

import csv
import time
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..calibration.errors import CalibrationError, HandEyeError
from ..calibration.files import make_folder, write_text_atomic
from ..calibration.metrics import d_back, d_org, errors_against_truth, fixed_points
from ..calibration.solve import ALL_METHODS, calibrate, problem_from_session
from ..calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from .opencv_reference import OPENCV_METHODS, opencv_available, solve_opencv

SWEEPS = ("sigma_cam", "sigma_rob", "postures")
METRICS = (
    ("rotation_error_deg", "rotation error to truth (deg)"),
    ("translation_error_mm", "translation error to truth (mm)"),
    ("d_org3_mm", "d_org, eq. 22, three board points (mm)"),
    ("d_back3_mm", "d_back, eq. 23, three board points (mm)"),
    ("d_org_mm", "d_org, eq. 22, all corners (mm)"),
    ("d_back_mm", "d_back, eq. 23, all corners (mm)"),
)


@dataclass(frozen=True)
class BenchmarkOptions:
    """What to sweep and how much.

    Attributes
    ----------
    output : str
        Folder for ``results.csv``, ``summary.md`` and the PNG plots.
    sweeps : tuple of str
        Any of ``sigma_cam`` (robot noise 0), ``sigma_rob`` (camera noise 0), ``postures``
        (camera noise ``postures_sigma_cam``).
    trials : int
        Trials per cell (each its own scene and noise).
    methods : tuple of str or None
        Method names (``None``: all of ours and, when available, OpenCV's as ``opencv_<name>``).
    """

    output: str = "benchmarks/paper"
    sweeps: tuple = SWEEPS
    trials: int = 20
    sigma_cam_values: tuple = (0.0, 2.5, 5.0, 10.0, 15.0, 20.0)
    sigma_rob_values: tuple = (0.0, 0.1, 0.2, 0.3, 0.4)
    postures_values: tuple = (10, 20, 30, 50)
    postures: int = 30
    postures_sigma_cam: float = 5.0
    camera_model: str = "paper"
    methods: tuple | None = None
    opencv: bool = True
    seed: int = 0
    plots: bool = True
    extra: dict = field(default_factory=dict)


def _cells(options: BenchmarkOptions):
    for sweep in options.sweeps:
        if sweep == "sigma_cam":
            for v in options.sigma_cam_values:
                yield sweep, v, NoiseConfig(0.0, v, options.camera_model), options.postures
        elif sweep == "sigma_rob":
            for v in options.sigma_rob_values:
                yield sweep, v, NoiseConfig(v, 0.0, options.camera_model), options.postures
        elif sweep == "postures":
            for v in options.postures_values:
                yield sweep, v, NoiseConfig(0.0, options.postures_sigma_cam, options.camera_model), int(v)
        else:
            raise HandEyeError(f"unknown sweep {sweep!r}; use {', '.join(SWEEPS)}")


def _row(sweep, value, trial, method, x, truth, problem, runtime, outliers=0):
    fixed = fixed_points(problem.hand, x, problem.points_cam)
    fixed3 = fixed_points(problem.hand, x, problem.compact.points)
    e = errors_against_truth(x, truth["x"])
    return {"sweep": sweep, "value": value, "trial": trial, "method": method,
            "rotation_error_deg": e["rotation_error_deg"], "translation_error_mm": e["translation_error_mm"],
            "d_org3_mm": d_org(fixed3), "d_back3_mm": d_back(fixed3),
            "d_org_mm": d_org(fixed), "d_back_mm": d_back(fixed), "runtime_s": runtime, "outliers": outliers}


def run_benchmark(options: BenchmarkOptions, progress=None) -> list[dict]:
    """Run the sweeps; returns one row per (cell, trial, method). ``progress(done, total, label)``."""
    ours = tuple(options.methods) if options.methods else ALL_METHODS
    use_opencv = options.opencv and opencv_available()
    ocv = [m[len("opencv_"):] for m in ours if m.startswith("opencv_")] if options.methods else list(OPENCV_METHODS)
    ocv = ocv if use_opencv else []
    ours = tuple(m for m in ours if not m.startswith("opencv_"))
    cells = list(_cells(options))
    largest = max(c[3] for c in cells)
    total = len(cells) * options.trials
    scenes = {}
    rows: list[dict] = []
    done = 0
    for sweep, value, noise, postures in cells:
        for trial in range(options.trials):
            if trial not in scenes:
                scenes[trial] = make_scene(SceneConfig(postures=largest, seed=options.seed + trial))
            full = scenes[trial]
            scene = replace(full, joints_deg=full.joints_deg[:postures], config=replace(full.config, postures=postures))
            trial_noise = replace(noise, seed=zlib.crc32(f"{sweep}:{float(value)}:{trial}:{options.seed}".encode()))
            problem = problem_from_session(sample_session(scene, trial_noise))
            truth = {"x": scene.x_true, "target2fixed": scene.target2fixed}
            rows.append(_row(sweep, value, trial, "truth", scene.x_true, truth, problem, 0.0))
            for method in ours:
                try:
                    r = calibrate(problem, method, truth)
                except CalibrationError:
                    continue
                rows.append(_row(sweep, value, trial, method, r.x, truth, problem, r.runtime_s, len(r.outliers)))
            for name in ocv:
                start = time.perf_counter()
                x = solve_opencv(problem.hand, problem.target2cam, name)
                runtime = time.perf_counter() - start
                if np.all(np.isfinite(x)):
                    rows.append(_row(sweep, value, trial, f"opencv_{name}", x, truth, problem, runtime))
            done += 1
            if progress:
                progress(done, total, f"{sweep} = {value:g}, trial {trial + 1}/{options.trials}")
    return rows


def medians(rows: list[dict]) -> dict:
    """``{sweep: {method: {value: {metric: median}}}}``."""
    table: dict = {}
    for row in rows:
        cell = table.setdefault(row["sweep"], {}).setdefault(row["method"], {}).setdefault(row["value"], {})
        for key, _ in METRICS + (("runtime_s", ""),):
            cell.setdefault(key, []).append(row[key])
    for sweep in table.values():
        for method in sweep.values():
            for value, cell in method.items():
                method[value] = {k: float(np.median(v)) for k, v in cell.items()}
    return table


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def markdown(table: dict, options: BenchmarkOptions) -> str:
    titles = {"sigma_cam": "camera noise sigma_cam (mm), robot noise 0",
              "sigma_rob": "robot joint noise sigma_rob (deg), camera noise 0",
              "postures": f"number of postures, camera noise {options.postures_sigma_cam:g} mm"}
    out = [f"# Method comparison (medians of {options.trials} trials per cell, {options.camera_model} camera noise)", ""]
    for sweep, methods in table.items():
        values = sorted(next(iter(methods.values())))
        for key, label in METRICS:
            out += [f"## {label} vs {titles[sweep]}", "",
                    "| method | " + " | ".join(f"{v:g}" for v in values) + " |",
                    "|---|" + "---|" * len(values)]
            best = {v: min(m[v][key] for name, m in methods.items() if name != "truth" and v in m) for v in values}
            for name, cells in methods.items():
                if name == "truth" and key.endswith("error_deg") or name == "truth" and key.endswith("error_mm"):
                    continue
                entries = []
                for v in values:
                    if v not in cells:
                        entries.append("-")
                        continue
                    text = f"{cells[v][key]:.4g}"
                    entries.append(f"**{text}**" if name != "truth" and cells[v][key] == best[v] else text)
                out.append(f"| {name} | " + " | ".join(entries) + " |")
            out.append("")
    return "\n".join(out)


def plot(table: dict, folder: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    colours = plt.get_cmap("tab20").colors
    for sweep, methods in table.items():
        fig, axes = plt.subplots(2, 3, figsize=(18, 9))
        for ax, (key, label) in zip(axes.ravel(), METRICS):
            for index, (name, cells) in enumerate(methods.items()):
                if name == "truth" and "error" in key:
                    continue
                # the noise-free cell is exact for everyone (1e-12): leave it out of the noise plots
                values = [v for v in sorted(cells) if sweep == "postures" or v > 0]
                style = "-" if name.startswith("mc") or name == "robust" else ("--" if not name.startswith("opencv") else ":")
                if name == "truth":
                    style = "-."
                width = 2.5 if name in ("mcb", "robust") else 1.2
                ax.plot(values, [cells[v][key] for v in values], style, marker="o", markersize=3, linewidth=width,
                        label=name, color="black" if name == "truth" else colours[index % len(colours)])
            ax.set_xlabel(sweep)
            ax.set_title(label)
            ax.grid(True, which="both", alpha=0.3)
        axes[0, 0].legend(fontsize=7, ncol=2)
        fig.suptitle(f"handeye benchmark: {sweep} sweep (median over trials)")
        fig.tight_layout()
        path = folder / f"{sweep}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def benchmark(options: BenchmarkOptions, progress=None) -> dict:
    """Run, then write ``results.csv``, ``summary.md`` and plots into ``options.output``."""
    folder = make_folder(options.output)  # fails before the long run, not after
    started = time.time()
    rows = run_benchmark(options, progress)
    if not rows:
        raise HandEyeError("the benchmark produced no results")
    table = medians(rows)
    write_csv(rows, folder / "results.csv")
    write_text_atomic(folder / "summary.md", markdown(table, options))
    plots = plot(table, folder) if options.plots else []
    return {"rows": len(rows), "folder": str(folder), "plots": [str(p) for p in plots], "wall_s": time.time() - started}
