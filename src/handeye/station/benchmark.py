"""The paper's section-4 study, reproduced: every method over sweeps of robot and camera noise and
of the number of postures, many trials per cell, results as CSV, plots and a markdown table; and
the pose-noise model of OpenCV's own hand-eye test (``src/handeye/calibration/synthetic_poses.py``).

Each trial draws its own scene (a posture set of the IRB 1400 around the 8x13 board, seed = trial)
and its own noise. Errors are measured against the truth (rotation in degrees, translation in mm)
and by the point measures of the paper, d_org (eq. 22) and d_back (eq. 23), on all board corners
and on the three board points of the plane fit (section 3.1). On the corners every method looks the
same once camera noise is large, because each corner carries its own noise; the three fitted points
average it out and show the differences. ``truth`` is the true X scored by the same point measures.
Methods that report an uncertainty (``ml``, ``robust``) also get ``z_rms``: the RMS over the six
axes of error / one-sigma, whose RMS over the trials should be near 1.
"""

from __future__ import annotations

import csv
import time
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..base import CalibrationError, HandEyeError
from ..base import make_folder, write_text_atomic
from ..calibration import d_back, d_org, errors_against_truth, fixed_points
from ..calibration import DEFAULT_METHOD, METHODS, get_method, method_names
from ..calibration import calibrate, problem_from_session
from ..calibration import NoiseConfig, SceneConfig, make_scene, sample_session
from ..calibration import opencv_test_problem
from .opencv_reference import OPENCV_METHODS, opencv_available, solve_opencv

SWEEPS = ("sigma_cam", "sigma_rob", "postures", "pose_noise")
#: Sweeps summarised by the mean over trials (OpenCV's test reports means); the others by the median.
MEAN_SWEEPS = ("pose_noise",)
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
        (camera noise ``postures_sigma_cam``), ``pose_noise`` (OpenCV's test model: random poses,
        board poses only, noise on both poses).
    trials : int
        Trials per cell (each its own scene and noise).
    pose_noise_trials, pose_noise_poses : int
        Trials and poses per trial of the ``pose_noise`` sweep (OpenCV's test: 100 x 10).
    methods : tuple of str or None
        Method names (``None``: every method of the table, plug-ins' too, and, when available,
        OpenCV's as ``opencv_<name>``).
    """

    output: str = "benchmarks/paper"
    sweeps: tuple = SWEEPS
    trials: int = 20
    sigma_cam_values: tuple = (0.0, 2.5, 5.0, 10.0, 15.0, 20.0)
    sigma_rob_values: tuple = (0.0, 0.02, 0.05, 0.1, 0.2, 0.4)
    postures_values: tuple = (8, 10, 12, 20, 30, 50)
    pose_noise_trials: int = 100
    pose_noise_poses: int = 10
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
        elif sweep == "pose_noise":
            yield sweep, options.pose_noise_poses, None, 0
        else:
            raise HandEyeError(f"unknown sweep {sweep!r}; use {', '.join(SWEEPS)}")


def _row(sweep, value, trial, method, x, truth, problem, runtime, outliers=0, uncertainty=None):
    fixed = fixed_points(problem.hand, x, problem.points_cam)
    fixed3 = fixed_points(problem.hand, x, problem.compact.points)
    e = errors_against_truth(x, truth["x"])
    return {"sweep": sweep, "value": value, "trial": trial, "method": method,
            "rotation_error_deg": e["rotation_error_deg"], "translation_error_mm": e["translation_error_mm"],
            "d_org3_mm": d_org(fixed3), "d_back3_mm": d_back(fixed3),
            "d_org_mm": d_org(fixed), "d_back_mm": d_back(fixed), "runtime_s": runtime, "outliers": outliers,
            "z_rms": _z_rms(x, truth["x"], uncertainty)}


def _z_rms(x, x_true, uncertainty) -> float:
    """RMS over the six axes of error / reported one-sigma (NaN without an uncertainty)."""
    if not uncertainty:
        return float("nan")
    from scipy.spatial.transform import Rotation

    et = x[:3, 3] - x_true[:3, 3]
    er = np.degrees(Rotation.from_matrix(x[:3, :3] @ x_true[:3, :3].T).as_rotvec())
    z = np.concatenate([et / np.asarray(uncertainty["translation_mm"]), er / np.asarray(uncertainty["rotation_deg"])])
    return float(np.sqrt(np.mean(z**2)))


def run_benchmark(options: BenchmarkOptions, progress=None, failures: dict | None = None) -> list[dict]:
    """Run the sweeps; returns one row per (cell, trial, method). ``progress(done, total, label)``.

    A method that cannot solve a trial (``CalibrationError``: degenerate draws, or a plug-in's fault,
    named) has no row for it; ``failures``, when given, is filled with ``{method: [trials failed, the
    first reason]}``.
    """
    ours = _methods(options)
    use_opencv = options.opencv and opencv_available()
    ocv = [m[len("opencv_"):] for m in ours if m.startswith("opencv_")] if options.methods else list(OPENCV_METHODS)
    ocv = ocv if use_opencv else []
    ours = tuple(m for m in ours if not m.startswith("opencv_"))
    cells = list(_cells(options))
    largest = max(c[3] for c in cells)
    total = sum(options.pose_noise_trials if c[0] == "pose_noise" else options.trials for c in cells)
    scenes = {}
    rows: list[dict] = []
    done = 0
    for sweep, value, noise, postures in cells:
        for trial in range(options.pose_noise_trials if sweep == "pose_noise" else options.trials):
            problem, truth = _trial_problem(options, scenes, largest, sweep, value, noise, postures, trial)
            rows.append(_row(sweep, value, trial, "truth", truth["x"], truth, problem, 0.0))
            for method in ours:
                try:
                    r = calibrate(problem, method, truth)
                except CalibrationError as exc:
                    if failures is not None:
                        failures.setdefault(method, [0, str(exc)])[0] += 1
                    continue
                rows.append(_row(sweep, value, trial, method, r.x, truth, problem, r.runtime_s, len(r.outliers),
                                 r.uncertainty))
            for name in ocv:
                start = time.perf_counter()
                x = solve_opencv(problem.hand, problem.target2cam, name)
                runtime = time.perf_counter() - start
                if np.all(np.isfinite(x)):
                    rows.append(_row(sweep, value, trial, f"opencv_{name}", x, truth, problem, runtime))
            done += 1
            if progress:
                progress(done, total, f"{sweep} = {value:g}, trial {trial + 1}")
    return rows


def _methods(options: BenchmarkOptions) -> tuple[str, ...]:
    """The methods to run: ``options.methods``, or every row of the methods table (plug-ins' too).

    Raises
    ------
    HandEyeError
        A name that is neither a method nor ``opencv_<name>``, in one line.
    """
    ours = tuple(options.methods) if options.methods else method_names()
    unknown = [m for m in ours if not m.startswith("opencv_") and get_method(m) is None]
    if unknown:
        raise HandEyeError(f"--methods: {METHODS.unknown(unknown[0])} (or opencv_<name>)")
    return ours


def _trial_problem(options, scenes, largest, sweep, value, noise, postures, trial):
    """The problem and truth of one trial: an IRB 1400 scene with noise, or OpenCV's random poses."""
    seed = zlib.crc32(f"{sweep}:{float(value)}:{trial}:{options.seed}".encode())
    if sweep == "pose_noise":
        return opencv_test_problem(np.random.default_rng(seed), int(value))
    if trial not in scenes:
        scenes[trial] = make_scene(SceneConfig(postures=largest, seed=options.seed + trial))
    full = scenes[trial]
    scene = replace(full, joints_deg=full.joints_deg[:postures], config=replace(full.config, postures=postures))
    # the plausibility checks are for real sessions: 20 mm of corner noise stretches the measured squares
    problem = problem_from_session(sample_session(scene, replace(noise, seed=seed)), check_units=False)
    return problem, {"x": scene.x_true, "target2fixed": scene.target2fixed}


def medians(rows: list[dict]) -> dict:
    """``{sweep: {method: {value: {metric: statistic}}}}``: the median over trials (the mean for
    :data:`MEAN_SWEEPS`); ``z_rms`` is aggregated as the RMS over trials."""
    table: dict = {}
    for row in rows:
        cell = table.setdefault(row["sweep"], {}).setdefault(row["method"], {}).setdefault(row["value"], {})
        for key, _ in METRICS + (("runtime_s", ""), ("z_rms", "")):
            cell.setdefault(key, []).append(row.get(key, float("nan")))
    for name, sweep in table.items():
        stat = np.mean if name in MEAN_SWEEPS else np.median
        for method in sweep.values():
            for value, cell in method.items():
                z = np.array(cell.pop("z_rms"), float)
                method[value] = {k: float(stat(v)) for k, v in cell.items()}
                method[value]["z_rms"] = float(np.sqrt(np.mean(z**2))) if np.all(np.isfinite(z)) and len(z) else float("nan")
    return table


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def markdown(table: dict, options: BenchmarkOptions) -> str:
    titles = {"sigma_cam": "camera noise sigma_cam (mm), robot noise 0",
              "sigma_rob": "robot joint noise sigma_rob (deg), camera noise 0",
              "postures": f"number of postures, camera noise {options.postures_sigma_cam:g} mm",
              "pose_noise": (f"poses per trial, OpenCV's test model (means of {options.pose_noise_trials} trials; "
                             "0.002 rad / 5 mm on target2cam, 0.001 rad / 1 mm on gripper2base)")}
    out = [f"# Method comparison (medians of {options.trials} trials per cell, {options.camera_model} camera noise; "
           f"the pose-noise sweep: means)", ""]
    for sweep, methods in table.items():
        values = sorted(next(iter(methods.values())))
        for key, label in METRICS + (("z_rms", "RMS of error / reported one-sigma over the six axes (near 1 = honest)"),):
            if key == "z_rms":
                methods = {name: cells for name, cells in methods.items()
                           if any(np.isfinite(c.get("z_rms", np.nan)) for c in cells.values())}
                if not methods:
                    continue
            out += [f"## {label} vs {titles[sweep]}", "",
                    "| method | " + " | ".join(f"{v:g}" for v in values) + " |",
                    "|---|" + "---|" * len(values)]
            best = {v: min((m[v][key] for name, m in methods.items() if name != "truth" and v in m), default=np.nan)
                    for v in values}
            for name, cells in methods.items():
                if name == "truth" and key.endswith("error_deg") or name == "truth" and key.endswith("error_mm"):
                    continue
                entries = []
                for v in values:
                    if v not in cells:
                        entries.append("-")
                        continue
                    text = f"{cells[v][key]:.4g}"
                    bold = name != "truth" and cells[v][key] == best[v] and key != "z_rms"
                    entries.append(f"**{text}**" if bold else text)
                out.append(f"| {name} | " + " | ".join(entries) + " |")
            out.append("")
    return "\n".join(out)


def plot(table: dict, folder: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    tab20 = plt.get_cmap("tab20")
    colours = [tab20(k) for k in range(tab20.N)]  # its 20 colours (RGBA)
    for sweep, methods in table.items():
        fig, axes = plt.subplots(2, 3, figsize=(18, 9))
        statistic = "mean" if sweep in MEAN_SWEEPS else "median"
        if len(next(iter(methods.values()))) == 1:  # one cell (the pose-noise model): bars per method
            _bars(axes, methods, colours)
            fig.suptitle(f"handeye benchmark: {sweep} ({statistic} over trials)")
            fig.tight_layout()
            path = folder / f"{sweep}.png"
            fig.savefig(path, dpi=90)
            plt.close(fig)
            paths.append(path)
            continue
        for ax, (key, label) in zip(axes.ravel(), METRICS):
            for index, (name, cells) in enumerate(methods.items()):
                if name == "truth" and "error" in key:
                    continue
                # the noise-free cell is exact for everyone (1e-12): leave it out of the noise plots
                values = [v for v in sorted(cells) if sweep == "postures" or v > 0]
                style, width, colour = _line_style(name, colours[index % len(colours)])
                ax.plot(values, [cells[v][key] for v in values], style, marker="o", markersize=3, linewidth=width,
                        label=name, color=colour)
            ax.set_xlabel(sweep)
            ax.set_title(label)
            ax.grid(True, which="both", alpha=0.3)
        axes[0, 0].legend(fontsize=7, ncol=2)
        fig.suptitle(f"handeye benchmark: {sweep} sweep ({statistic} over trials)")
        fig.tight_layout()
        path = folder / f"{sweep}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def _line_style(name: str, colour) -> tuple[str, float, object]:
    """Line style, width and colour of a method's curve: the truth dash-dotted black, the default
    thick red, the paper's variants and the estimators solid (mcb and robust wider), the classic
    solvers dashed, OpenCV's dotted."""
    if name == "truth":
        return "-.", 1.2, "black"
    row = get_method(name)
    style = "-" if row is not None and row.kind in ("paper", "estimator") else (":" if name.startswith("opencv") else "--")
    width = 3.0 if name == DEFAULT_METHOD else (2.0 if name in ("mcb", "robust") else 1.2)
    return style, width, "red" if name == DEFAULT_METHOD else colour


def _bars(axes, methods: dict, colours) -> None:
    """One horizontal bar per method and metric (sweeps with a single cell)."""
    for ax, (key, label) in zip(axes.ravel(), METRICS):
        names = [n for n in methods if not (n == "truth" and "error" in key)]
        values = [next(iter(methods[n].values()))[key] for n in names]
        colour = [_line_style(n, colours[i % len(colours)])[2] for i, n in enumerate(names)]
        ax.barh(names, values, color=colour)
        ax.set_xscale("log")
        ax.set_title(label)
        ax.grid(True, axis="x", which="both", alpha=0.3)
        ax.tick_params(axis="y", labelsize=7)


def benchmark(options: BenchmarkOptions, progress=None) -> dict:
    """Run, then write ``results.csv``, ``summary.md`` and plots into ``options.output``."""
    _methods(options)  # an unknown method fails before anything is written
    folder = make_folder(options.output)  # fails before the long run, not after
    started = time.time()
    failures: dict = {}
    rows = run_benchmark(options, progress, failures)
    if not rows:
        raise HandEyeError("the benchmark produced no results")
    table = medians(rows)
    write_csv(rows, folder / "results.csv")
    write_text_atomic(folder / "summary.md", markdown(table, options) + failures_markdown(failures))
    plots = plot(table, folder) if options.plots else []
    return {"rows": len(rows), "folder": str(folder), "plots": [str(p) for p in plots], "wall_s": time.time() - started,
            "failures": failures}


def failures_markdown(failures: dict) -> str:
    """The section of ``summary.md`` naming the methods that could not solve some trials (their medians
    are over the trials they solved); empty when every method solved every trial."""
    if not failures:
        return ""
    rows = [f"| {method} | {count} | {reason.replace('|', chr(92) + '|')} |" for method, (count, reason) in failures.items()]
    return "\n".join(["", "## Trials a method could not solve (its medians above leave them out)", "",
                      "| method | trials | first reason |", "|---|---|---|", *rows, ""])
