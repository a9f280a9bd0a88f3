"""The calibration report's figures, as PNG bytes (matplotlib's object API: ``Figure`` + Agg canvas,
no pyplot, no global backend change).

Per-posture residuals, rotation-axis coverage, the method comparison, repeatability of the board
corners in the fixed frame and the per-corner RMS. No two texts of a figure may overlap
(tests/station/test_report_figures.py checks every figure). :func:`new_figure`, :func:`style_axes`,
:func:`to_png` and the colours serve every figure of the station (the verify history's trend too).
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING, Literal

import numpy as np

from ...calibration import HandEyeProblem
from ...calibration import D_ORG_ALL_NAME, AxisCoverage

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ...calibration import CalibrationResult

__all__ = ["BLUE", "RED", "ORANGE", "GREY", "new_figure", "to_png", "style_axes", "plot_residuals", "plot_axis_coverage",
           "plot_method_comparison", "method_comparison_figure", "plot_repeatability", "plot_point_rms"]

BLUE, RED, ORANGE, GREY = "#1f5fa8", "#c62828", "#ef8a17", "#8a8a8a"


def new_figure(width: float, height: float, layout: Literal["constrained", "compressed", "tight"] | None = None) -> Figure:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout=layout)
    fig.patch.set_facecolor("white")
    return fig


def to_png(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight", facecolor="white")
    return buffer.getvalue()


def style_axes(ax: Axes) -> None:
    ax.grid(True, alpha=0.25)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def plot_residuals(result: CalibrationResult, problem: HandEyeProblem, limit_mm: float | None) -> bytes:
    """Bar chart of each posture's residual (mm); outliers red, inliers over the limit orange."""
    ids = [int(i) for i in problem.posture_ids]
    values = np.array([result.residuals_mm.get(i, np.nan) for i in ids])
    outliers = {int(i) for i in result.outliers}
    colours = [RED if i in outliers else (ORANGE if limit_mm is not None and v > limit_mm else BLUE)
               for i, v in zip(ids, values)]
    fig = new_figure(10.5, 3.4)
    ax = fig.add_subplot()
    x = np.arange(len(ids))
    median = float(np.nanmedian(values))
    used = np.array([i not in outliers for i in ids])
    scale = max(float(np.nanmax(values[used])) if used.any() else 0.0, limit_mm or 0.0, median)
    top = float(np.nanmax(values))
    if top > 4.0 * scale > 0:  # a gross outlier would flatten the others: clip it and print its value
        top = 2.5 * scale
    ax.bar(x, np.minimum(values, top), color=colours, width=0.75)
    ax.axhline(median, color=GREY, linestyle=":", linewidth=1.2, label=f"median {median:.2f} mm")
    if limit_mm is not None:
        ax.axhline(limit_mm, color=RED, linestyle="--", linewidth=1.2, label=f"limit {limit_mm:g} mm")
    labelled = [(k, v) for k, (i, v) in enumerate(zip(ids, values)) if i in outliers or v > top]
    off_scale = [(k, v) for k, v in labelled if v > top]
    if off_scale:  # a clipped bar ends in an arrow head
        ax.plot([k for k, _ in off_scale], [top] * len(off_scale), linestyle="none", marker="^", markersize=6,
                color=RED, clip_on=False)
    for k, v in labelled:  # upright value labels: neighbouring outliers' labels cannot run into each other
        ax.annotate(f"{v:.1f}" if v >= 100 else f"{v:.2f}", (k, min(v, top)), ha="center", va="bottom",
                    rotation=90, fontsize=8, color=RED, xytext=(0, 7 if v > top else 2), textcoords="offset points")
    step = max(1, int(np.ceil(len(ids) / 40)))
    ax.set_xticks(x[::step])
    ax.set_xticklabels([str(i) for i in ids][::step], fontsize=8)
    ax.set_xlim(-0.7, len(ids) - 0.3)
    ax.set_ylim(0, (top * (1.4 if labelled else 1.18)) if top > 0 else 1.0)
    ax.set_xlabel("posture")
    ax.set_ylabel("residual (mm)")
    from matplotlib.artist import Artist
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Artist] = [Patch(color=BLUE, label="used"), Patch(color=RED, label="outlier (left out)")]
    if ORANGE in colours:
        handles.append(Patch(color=ORANGE, label="used, over the limit"))
    if off_scale:
        handles.append(Line2D([], [], linestyle="none", marker="^", color=RED, label="off scale (value printed)"))
    line_handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + line_handles, fontsize=8, loc="lower right", bbox_to_anchor=(1.0, 1.0),
              ncol=len(handles) + len(line_handles), frameon=False)
    style_axes(ax)
    ax.grid(False, axis="x")
    return to_png(fig)


def _hemisphere(ax, axes, angles, centre: int, frame: str, vmax: float, weakest):
    """Orthographic view of the unit sphere looking along +``centre`` axis; axes and their opposites
    are both drawn, so the visible hemisphere shows every axis once."""
    import matplotlib.colors as mcolors

    pts = np.concatenate([axes, -axes]) if len(axes) else np.zeros((0, 3))
    ang = np.concatenate([angles, angles]) if len(angles) else np.zeros(0)
    u_axis, v_axis = [(1, 2), (2, 0), (0, 1)][centre]  # right-handed screen axes for each view
    visible = pts[:, centre] >= 0
    theta = np.linspace(0, 2 * np.pi, 200)
    ax.plot(np.cos(theta), np.sin(theta), color="black", linewidth=1.0)
    for elevation in (30, 60):  # circles at 30 and 60 deg from the centre axis
        r = np.sin(np.radians(elevation))
        ax.plot(r * np.cos(theta), r * np.sin(theta), color=GREY, linewidth=0.6, linestyle=":")
    ax.plot([-1, 1], [0, 0], color=GREY, linewidth=0.5)
    ax.plot([0, 0], [-1, 1], color=GREY, linewidth=0.5)
    order = np.argsort(ang[visible])
    sc = ax.scatter(pts[visible, u_axis][order], pts[visible, v_axis][order], c=ang[visible][order],
                    s=10 + 40 * ang[visible][order] / max(vmax, 1e-9), cmap="viridis",
                    norm=mcolors.Normalize(0, vmax), edgecolors="none", alpha=0.85, zorder=3)
    names = "xyz"
    ax.annotate(f"{frame} {names[u_axis]}", (1.0, 0), xytext=(4, 0), textcoords="offset points", va="center", fontsize=9)
    ax.annotate(f"{frame} {names[v_axis]}", (0, 1.0), xytext=(0, 4), textcoords="offset points", ha="center",
                va="bottom", fontsize=9)
    ax.plot([0], [0], marker="+", color="black", markersize=9)
    w = np.asarray(weakest, float) * (1 if weakest[centre] >= 0 else -1)
    ax.scatter([w[u_axis]], [w[v_axis]], s=260, facecolors="none", edgecolors=RED, linewidths=2.0, zorder=4)
    ax.set_title(f"seen from {frame} +{names[centre]}\n(centre: turning about {names[centre]})", fontsize=10)
    ax.set_xlim(-1.25, 1.35)
    ax.set_ylim(-1.2, 1.25)
    ax.set_aspect("equal")
    ax.axis("off")
    return sc


def plot_axis_coverage(coverage: AxisCoverage) -> bytes:
    """Rotation axes of the relative flange motions (inlier postures) on two hemispheres, plus the RMS
    rotation about each axis of the hand frame (``calibration.quality_words.AxisCoverage``)."""
    vmax = max(90.0, float(coverage.angles_deg.max()) if coverage.angles_deg.size else 90.0)
    fig = new_figure(12.5, 4.9)
    grid = fig.add_gridspec(2, 3, width_ratios=[1, 1, 0.8], height_ratios=[1, 0.045], wspace=0.3, hspace=0.12)
    ax1, ax2 = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    sc = _hemisphere(ax1, coverage.axes, coverage.angles_deg, 2, coverage.frame, vmax, coverage.weakest_direction)
    _hemisphere(ax2, coverage.axes, coverage.angles_deg, 0, coverage.frame, vmax, coverage.weakest_direction)
    cax = fig.add_subplot(grid[1, 0:2])
    bar = fig.colorbar(sc, cax=cax, orientation="horizontal")
    bar.set_label("rotation angle between the two postures (deg)     red ring: least exercised direction", fontsize=9)
    ax3 = fig.add_subplot(grid[0, 2])
    ax3.bar(["x", "y", "z"], coverage.rms_about_axes_deg, color=BLUE, width=0.6)
    for k, v in enumerate(coverage.rms_about_axes_deg):
        ax3.annotate(f"{v:.1f}", (k, v), ha="center", va="bottom", fontsize=9, xytext=(0, 2), textcoords="offset points")
    ax3.set_title(f"rotation about each {coverage.frame} axis\n(RMS over posture pairs)", fontsize=10)
    ax3.set_xlabel(f"{coverage.frame} axis")
    ax3.set_ylabel("deg")
    ax3.set_ylim(0, max(coverage.rms_about_axes_deg.max() * 1.2, 1.0))
    style_axes(ax3)
    ax3.grid(False, axis="x")
    return to_png(fig)


def _readable_value_axis(axis, nbins: int = 4) -> None:
    """Few ticks, plain numbers (no offset or 1e-5 factor, which lands on a neighbouring panel), each
    with as many decimals as the step between ticks needs."""
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    axis.set_major_locator(MaxNLocator(nbins=nbins, steps=[1, 2, 2.5, 5, 10], min_n_ticks=2))

    def label(value, _position):
        ticks = np.asarray(axis.get_majorticklocs(), float)
        step = float(np.min(np.diff(ticks))) if len(ticks) > 1 else (abs(value) or 1.0)
        decimals = next((d for d in range(9) if np.allclose(np.round(ticks, d), ticks, rtol=0, atol=1e-6 * step)), 8)
        return f"{value:.{decimals}f}"

    axis.set_major_formatter(FuncFormatter(label))


def plot_method_comparison(rows: list[dict]) -> bytes:
    """Horizontal bars per method: held-out error, position and rotation difference from the chosen result, d_org."""
    return to_png(method_comparison_figure(rows))


def method_comparison_figure(rows: list[dict]) -> Figure:
    """The figure of :func:`plot_method_comparison` (a matplotlib ``Figure``)."""
    names = [r["method"] + (" (chosen)" if r["chosen"] else "") for r in rows]
    colours = [BLUE if r["chosen"] else GREY for r in rows]
    panels = [("held_out_mm", "held-out error\n(mm RMS, ranks)", "{:.3f}"),
              ("d_position_mm", "position difference\nfrom the chosen (mm)", "{:.3f}"),
              ("d_rotation_deg", "rotation difference\nfrom the chosen (deg)", "{:.4f}"),
              ("d_org_mm", "d_org, in-sample\n(mm)", "{:.3f}")]
    if any(r["d_org_incl_outliers_mm"] is not None for r in rows):
        panels.append(("d_org_incl_outliers_mm", f"{D_ORG_ALL_NAME}\n(mm)", "{:.3f}"))
    fig = new_figure(3.4 * len(panels) + 1.4, 0.42 * len(rows) + 1.9, layout="constrained")
    y = np.arange(len(rows))[::-1]
    for k, (key, title, fmt) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        values = np.array([np.nan if r.get(key) is None else r[key] for r in rows], dtype=float)
        ax.barh(y, np.nan_to_num(values), color=colours, height=0.6)
        finite = values[np.isfinite(values)]
        resolution = 10.0 ** -len(fmt.format(0.0).split(".")[1])  # smaller values print as zero anyway
        top = max(float(finite.max()) if finite.size else 0.0, 10 * resolution)
        for yy, v in zip(y, values):
            ax.annotate("n/a" if not np.isfinite(v) else fmt.format(v), (0 if not np.isfinite(v) else v, yy),
                        xytext=(3, 0), textcoords="offset points", va="center", fontsize=8)
        ax.set_xlim(0, top * 1.45)
        _readable_value_axis(ax.xaxis)
        ax.tick_params(axis="x", labelsize=8.5)
        ax.set_yticks(y)
        ax.set_yticklabels(names if k == 0 else [""] * len(rows), fontsize=9)
        ax.set_title(title, fontsize=10)
        style_axes(ax)
        ax.grid(False, axis="y")
    return fig


def _grid_shape(points_2d: np.ndarray):
    """``(ny, nx)`` when the points form a full row-major grid (index = row * nx + col), else None."""
    xs, ys = np.unique(np.round(points_2d[:, 0], 6)), np.unique(np.round(points_2d[:, 1], 6))
    if len(xs) * len(ys) != len(points_2d) or len(xs) < 2 or len(ys) < 2:
        return None
    expected = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    return (len(ys), len(xs)) if np.allclose(expected, np.round(points_2d, 6)) else None


def plot_repeatability(problem: HandEyeProblem, result: CalibrationResult, rep: dict) -> tuple[bytes, list]:
    """Deviations of the board points from their mean in the fixed frame, top and side views.

    Returns the PNG and the outlier postures whose board centre lies beyond the plotted frame.
    """
    dev, centre, inliers = rep["deviations"], rep["centre_deviation"], rep["inliers"]
    ids = np.array([int(i) for i in problem.posture_ids])
    frame = rep["frame"]
    fig = new_figure(11.0, 5.0)
    limit = 1.15 * float(np.max(np.abs(dev[inliers]))) if inliers.any() else 1.0
    limit = max(limit, 0.05)  # noise-free data: keep readable ticks
    clipped = set()
    for k, (a, b, view) in enumerate(((0, 1, "top view"), (0, 2, "side view"))):
        ax = fig.add_subplot(1, 2, k + 1)
        inl = dev[inliers].reshape(-1, 3)
        ax.scatter(inl[:, a], inl[:, b], s=3, color=GREY, alpha=0.35, edgecolors="none", label="corners, used postures")
        ax.scatter(centre[inliers, a], centre[inliers, b], s=24, color=BLUE, edgecolors="white", linewidths=0.5,
                   label="board centre, one per posture", zorder=3)
        if (~inliers).any():
            out = dev[~inliers].reshape(-1, 3)
            ax.scatter(out[:, a], out[:, b], s=3, color=RED, alpha=0.35, edgecolors="none", label="corners, outliers")
            ax.scatter(centre[~inliers, a], centre[~inliers, b], s=44, color=RED, marker="X",
                       label="board centre, outliers", zorder=4)
            for i, c in zip(ids[~inliers], centre[~inliers]):
                if max(abs(c[a]), abs(c[b])) > limit:
                    clipped.add(int(i))
                else:
                    ax.annotate(str(i), (c[a], c[b]), xytext=(4, 2), textcoords="offset points", fontsize=8, color=RED)
        ax.axhline(0, color="black", linewidth=0.5)
        ax.axvline(0, color="black", linewidth=0.5)
        ax.set_xlim(-limit, limit)
        ax.set_ylim(-limit, limit)
        ax.set_aspect("equal")
        ax.set_xlabel(f"{frame} {'xyz'[a]} deviation (mm)")
        ax.set_ylabel(f"{frame} {'xyz'[b]} deviation (mm)")
        ax.set_title(f"{view}: {frame} {'xyz'[a]} and {'xyz'[b]}", fontsize=10)
        ax.locator_params(nbins=7)
        style_axes(ax)
        if k == 0:
            handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8.5, frameon=False, markerscale=2,
               bbox_to_anchor=(0.5, -0.02))
    fig.subplots_adjust(bottom=0.2, wspace=0.3)
    return to_png(fig), sorted(clipped)


def plot_point_rms(problem: HandEyeProblem, rep: dict) -> bytes:
    """The RMS deviation of each board point over the used postures, laid out on the board (mm)."""
    import matplotlib.colors as mcolors

    target = problem.target_points if problem.target_points is not None else problem.compact.target_points
    rms = rep["rms_per_point"]
    norm = mcolors.Normalize(0, max(float(rms.max()), 0.01))
    cmap = "Blues"
    shape = _grid_shape(target[:, :2]) if target is not None and len(target) == len(rms) else None
    if shape is not None:
        ny, nx = shape
        fig = new_figure(min(11.0, 1.2 + 0.62 * nx), 0.9 + 0.55 * ny)
        ax = fig.add_subplot()
        image = ax.imshow(rms.reshape(ny, nx), cmap=cmap, norm=norm, origin="upper", aspect="equal")
        if nx * ny <= 300:
            for k, value in enumerate(rms):
                ax.text(k % nx, k // nx, f"{value:.2f}", ha="center", va="center", fontsize=8,
                        color="white" if norm(value) > 0.6 else "black")
        ax.set_xticks(range(nx))
        ax.set_yticks(range(ny))
        ax.set_xlabel("board column (along target x)")
        ax.set_ylabel("board row (along target y)")
        ax.tick_params(labelsize=8)
    else:
        fig = new_figure(6.0, 3.2)
        ax = fig.add_subplot()
        pts = target[:, :2] if target is not None and len(target) == len(rms) else np.c_[np.arange(len(rms)), 0 * rms]
        image = ax.scatter(pts[:, 0], pts[:, 1], c=rms, cmap=cmap, norm=norm, s=300, marker="s", edgecolors="black")
        for k, (px, py) in enumerate(pts):
            ax.annotate(f"point {k}: {rms[k]:.2f}", (px, py), xytext=(0, 14), textcoords="offset points",
                        ha="center", fontsize=8)
        ax.set_xlabel("target x (mm)")
        ax.set_ylabel("target y (mm)")
        ax.margins(0.3)
        ax.set_aspect("equal")
    ax.set_title("RMS deviation of each board point over the used postures (mm)", fontsize=10, pad=8)
    bar = fig.colorbar(image, ax=ax, fraction=0.04, pad=0.02)
    bar.set_label("mm")
    return to_png(fig)
