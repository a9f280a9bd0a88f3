"""The calibration report: one self-contained HTML file a station engineer reads offline.

Everything is inside the file: CSS inline, plots as base64 PNG ``data:`` URIs, no scripts, no links
to other files or the network, so it opens on a station PC without internet and can be mailed as is.

Contents: a banner when the data come from the embedded mock station or a simulation
(``station.origin``); the verdict (PASS/FAIL) with the camera pose as a RAPID literal (copyable on a
PASS; greyed out, struck through and not selectable under "FAIL - do not write this into the robot"
on a FAIL), its uncertainty and the outliers; the quality checks with advice; five figures and
tables (per-posture residuals, rotation-axis coverage, method comparison, repeatability of the board
corners in the fixed frame, quality metrics and truth errors); the data checks made before solving;
the capture plan's preview of the cell when the session holds one (``SESSION/preview.png``).
d_org is everywhere the one of ``calibration.quality_words.result_d_org``, and the header says which
postures and points it is computed over.

A presenter of ``station.assessment.Assessment``: every figure and table shows what the assessment
holds (the verdict, the quality words, the method comparison, the repeatability); nothing here solves.

Plots use matplotlib's object API (``Figure`` + Agg canvas): no pyplot, no global backend change.
No two texts of a figure may overlap (tests/test_report_figures.py checks every figure).
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..calibration.errors import HandEyeError
from ..calibration.invariants import bounded_pairs, pairs_used
from ..calibration.problem import EYE_IN_HAND, HandEyeProblem
from ..calibration.quality_words import D_ORG_ALL_NAME, METRIC_MEANINGS, AxisCoverage, hand_frame
from ..calibration.session import write_text_atomic
from ..rapid.literals import pose_literal, rounded_pose
from .assessment import Assessment
from .origin import origin_banner
from .quality import CHECK_LABELS, Verdict, direction_name, format_check_value

__all__ = ["write_report"]

_BLUE, _RED, _ORANGE, _GREY = "#1f5fa8", "#c62828", "#ef8a17", "#8a8a8a"


# ----------------------------------------------------------------------------------------- plots
def _figure(width: float, height: float, layout: str | None = None):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout=layout)
    fig.patch.set_facecolor("white")
    return fig


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, bbox_inches="tight", facecolor="white")
    return buffer.getvalue()


def _style(ax):
    ax.grid(True, alpha=0.25)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def plot_residuals(result, problem: HandEyeProblem, limit_mm: float | None) -> bytes:
    """Bar chart of each posture's residual (mm); outliers red, inliers over the limit orange."""
    ids = [int(i) for i in problem.posture_ids]
    values = np.array([result.residuals_mm.get(i, np.nan) for i in ids])
    outliers = {int(i) for i in result.outliers}
    colours = [_RED if i in outliers else (_ORANGE if limit_mm is not None and v > limit_mm else _BLUE)
               for i, v in zip(ids, values)]
    fig = _figure(10.5, 3.4)
    ax = fig.add_subplot()
    x = np.arange(len(ids))
    median = float(np.nanmedian(values))
    used = np.array([i not in outliers for i in ids])
    scale = max(float(np.nanmax(values[used])) if used.any() else 0.0, limit_mm or 0.0, median)
    top = float(np.nanmax(values))
    if top > 4.0 * scale > 0:  # a gross outlier would flatten the others: clip it and print its value
        top = 2.5 * scale
    ax.bar(x, np.minimum(values, top), color=colours, width=0.75)
    ax.axhline(median, color=_GREY, linestyle=":", linewidth=1.2, label=f"median {median:.2f} mm")
    if limit_mm is not None:
        ax.axhline(limit_mm, color=_RED, linestyle="--", linewidth=1.2, label=f"limit {limit_mm:g} mm")
    labelled = [(k, v) for k, (i, v) in enumerate(zip(ids, values)) if i in outliers or v > top]
    off_scale = [(k, v) for k, v in labelled if v > top]
    if off_scale:  # a clipped bar ends in an arrow head
        ax.plot([k for k, _ in off_scale], [top] * len(off_scale), linestyle="none", marker="^", markersize=6,
                color=_RED, clip_on=False)
    for k, v in labelled:  # upright value labels: neighbouring outliers' labels cannot run into each other
        ax.annotate(f"{v:.1f}" if v >= 100 else f"{v:.2f}", (k, min(v, top)), ha="center", va="bottom",
                    rotation=90, fontsize=8, color=_RED, xytext=(0, 7 if v > top else 2), textcoords="offset points")
    step = max(1, int(np.ceil(len(ids) / 40)))
    ax.set_xticks(x[::step])
    ax.set_xticklabels([str(i) for i in ids][::step], fontsize=8)
    ax.set_xlim(-0.7, len(ids) - 0.3)
    ax.set_ylim(0, (top * (1.4 if labelled else 1.18)) if top > 0 else 1.0)
    ax.set_xlabel("posture")
    ax.set_ylabel("residual (mm)")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(color=_BLUE, label="used"), Patch(color=_RED, label="outlier (left out)")]
    if _ORANGE in colours:
        handles.append(Patch(color=_ORANGE, label="used, over the limit"))
    if off_scale:
        handles.append(Line2D([], [], linestyle="none", marker="^", color=_RED, label="off scale (value printed)"))
    line_handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + line_handles, fontsize=8, loc="lower right", bbox_to_anchor=(1.0, 1.0),
              ncol=len(handles) + len(line_handles), frameon=False)
    _style(ax)
    ax.grid(False, axis="x")
    return _png(fig)


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
        ax.plot(r * np.cos(theta), r * np.sin(theta), color=_GREY, linewidth=0.6, linestyle=":")
    ax.plot([-1, 1], [0, 0], color=_GREY, linewidth=0.5)
    ax.plot([0, 0], [-1, 1], color=_GREY, linewidth=0.5)
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
    ax.scatter([w[u_axis]], [w[v_axis]], s=260, facecolors="none", edgecolors=_RED, linewidths=2.0, zorder=4)
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
    fig = _figure(12.5, 4.9)
    grid = fig.add_gridspec(2, 3, width_ratios=[1, 1, 0.8], height_ratios=[1, 0.045], wspace=0.3, hspace=0.12)
    ax1, ax2 = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    sc = _hemisphere(ax1, coverage.axes, coverage.angles_deg, 2, coverage.frame, vmax, coverage.weakest_direction)
    _hemisphere(ax2, coverage.axes, coverage.angles_deg, 0, coverage.frame, vmax, coverage.weakest_direction)
    cax = fig.add_subplot(grid[1, 0:2])
    bar = fig.colorbar(sc, cax=cax, orientation="horizontal")
    bar.set_label("rotation angle between the two postures (deg)     red ring: least exercised direction", fontsize=9)
    ax3 = fig.add_subplot(grid[0, 2])
    ax3.bar(["x", "y", "z"], coverage.rms_about_axes_deg, color=_BLUE, width=0.6)
    for k, v in enumerate(coverage.rms_about_axes_deg):
        ax3.annotate(f"{v:.1f}", (k, v), ha="center", va="bottom", fontsize=9, xytext=(0, 2), textcoords="offset points")
    ax3.set_title(f"rotation about each {coverage.frame} axis\n(RMS over posture pairs)", fontsize=10)
    ax3.set_xlabel(f"{coverage.frame} axis")
    ax3.set_ylabel("deg")
    ax3.set_ylim(0, max(coverage.rms_about_axes_deg.max() * 1.2, 1.0))
    _style(ax3)
    ax3.grid(False, axis="x")
    return _png(fig)


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
    return _png(method_comparison_figure(rows))


def method_comparison_figure(rows: list[dict]):
    """The figure of :func:`plot_method_comparison` (a matplotlib ``Figure``)."""
    names = [r["method"] + (" (chosen)" if r["chosen"] else "") for r in rows]
    colours = [_BLUE if r["chosen"] else _GREY for r in rows]
    panels = [("held_out_mm", "held-out error\n(mm RMS, ranks)", "{:.3f}"),
              ("d_position_mm", "position difference\nfrom the chosen (mm)", "{:.3f}"),
              ("d_rotation_deg", "rotation difference\nfrom the chosen (deg)", "{:.4f}"),
              ("d_org_mm", "d_org, in-sample\n(mm)", "{:.3f}")]
    if any(r["d_org_incl_outliers_mm"] is not None for r in rows):
        panels.append(("d_org_incl_outliers_mm", f"{D_ORG_ALL_NAME}\n(mm)", "{:.3f}"))
    fig = _figure(3.4 * len(panels) + 1.4, 0.42 * len(rows) + 1.9, layout="constrained")
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
        _style(ax)
        ax.grid(False, axis="y")
    return fig


def _grid_shape(points_2d: np.ndarray):
    """``(ny, nx)`` when the points form a full row-major grid (index = row * nx + col), else None."""
    xs, ys = np.unique(np.round(points_2d[:, 0], 6)), np.unique(np.round(points_2d[:, 1], 6))
    if len(xs) * len(ys) != len(points_2d) or len(xs) < 2 or len(ys) < 2:
        return None
    expected = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    return (len(ys), len(xs)) if np.allclose(expected, np.round(points_2d, 6)) else None


def plot_repeatability(problem: HandEyeProblem, result, rep: dict) -> tuple[bytes, list]:
    """Deviations of the board points from their mean in the fixed frame, top and side views.

    Returns the PNG and the outlier postures whose board centre lies beyond the plotted frame.
    """
    dev, centre, inliers = rep["deviations"], rep["centre_deviation"], rep["inliers"]
    ids = np.array([int(i) for i in problem.posture_ids])
    frame = rep["frame"]
    fig = _figure(11.0, 5.0)
    limit = 1.15 * float(np.max(np.abs(dev[inliers]))) if inliers.any() else 1.0
    limit = max(limit, 0.05)  # noise-free data: keep readable ticks
    clipped = set()
    for k, (a, b, view) in enumerate(((0, 1, "top view"), (0, 2, "side view"))):
        ax = fig.add_subplot(1, 2, k + 1)
        inl = dev[inliers].reshape(-1, 3)
        ax.scatter(inl[:, a], inl[:, b], s=3, color=_GREY, alpha=0.35, edgecolors="none", label="corners, used postures")
        ax.scatter(centre[inliers, a], centre[inliers, b], s=24, color=_BLUE, edgecolors="white", linewidths=0.5,
                   label="board centre, one per posture", zorder=3)
        if (~inliers).any():
            out = dev[~inliers].reshape(-1, 3)
            ax.scatter(out[:, a], out[:, b], s=3, color=_RED, alpha=0.35, edgecolors="none", label="corners, outliers")
            ax.scatter(centre[~inliers, a], centre[~inliers, b], s=44, color=_RED, marker="X",
                       label="board centre, outliers", zorder=4)
            for i, c in zip(ids[~inliers], centre[~inliers]):
                if max(abs(c[a]), abs(c[b])) > limit:
                    clipped.add(int(i))
                else:
                    ax.annotate(str(i), (c[a], c[b]), xytext=(4, 2), textcoords="offset points", fontsize=8, color=_RED)
        ax.axhline(0, color="black", linewidth=0.5)
        ax.axvline(0, color="black", linewidth=0.5)
        ax.set_xlim(-limit, limit)
        ax.set_ylim(-limit, limit)
        ax.set_aspect("equal")
        ax.set_xlabel(f"{frame} {'xyz'[a]} deviation (mm)")
        ax.set_ylabel(f"{frame} {'xyz'[b]} deviation (mm)")
        ax.set_title(f"{view}: {frame} {'xyz'[a]} and {'xyz'[b]}", fontsize=10)
        ax.locator_params(nbins=7)
        _style(ax)
        if k == 0:
            handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8.5, frameon=False, markerscale=2,
               bbox_to_anchor=(0.5, -0.02))
    fig.subplots_adjust(bottom=0.2, wspace=0.3)
    return _png(fig), sorted(clipped)


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
        fig = _figure(min(11.0, 1.2 + 0.62 * nx), 0.9 + 0.55 * ny)
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
        fig = _figure(6.0, 3.2)
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
    return _png(fig)


# ------------------------------------------------------------------------------------------ HTML
_CSS = """
body{font-family:"Segoe UI",Arial,Helvetica,sans-serif;margin:0;background:#f3f4f6;color:#1b1b1b;font-size:15px}
main{max-width:1280px;margin:0 auto;padding:18px 24px 40px}
h1{font-size:24px;margin:6px 0 2px} h2{font-size:19px;margin:28px 0 8px;border-bottom:2px solid #d5d8dc;padding-bottom:4px}
.sub{color:#555;font-size:13px;margin-bottom:14px}
section{background:#fff;border-radius:6px;padding:12px 18px 16px;margin-bottom:16px;box-shadow:0 1px 2px rgba(0,0,0,.08)}
.verdict{font-size:44px;font-weight:800;letter-spacing:2px;padding:10px 20px;border-radius:6px;color:#fff;display:inline-block}
.pass{background:#2e7d32} .fail{background:#c62828} .none{background:#757575}
.verdict-line{font-size:15px;margin:8px 0 4px}
.grid{display:grid;grid-template-columns:repeat(auto-fit,minmax(330px,1fr));gap:6px 28px;margin-top:12px}
.kv{display:grid;grid-template-columns:170px 1fr;gap:3px 10px;align-items:baseline;align-content:start}
.kv div:nth-child(odd){color:#555}
code,.literal{font-family:Consolas,"DejaVu Sans Mono",monospace}
.literal{background:#f0f3f7;border:1px solid #ccd3dc;border-radius:4px;padding:8px 10px;font-size:16px;
 display:block;margin:4px 0 10px;word-break:break-all;user-select:all}
table{border-collapse:collapse;width:100%;font-size:14px;margin:6px 0}
th,td{border-bottom:1px solid #e1e4e8;padding:5px 8px;text-align:left;vertical-align:top}
th{background:#f6f7f9;font-weight:600} td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.bad td{background:#fdecea} tr.chosen td{background:#e8f0fb;font-weight:600}
.ok{color:#2e7d32;font-weight:700} .ko{color:#c62828;font-weight:700}
img{max-width:100%;height:auto;display:block;margin:8px auto}
.how{color:#444;font-size:13.5px;margin:4px 0}
.note{color:#555;font-size:13px}
ul{margin:4px 0 4px 20px;padding:0}
footer{color:#666;font-size:12.5px;margin-top:18px}
.origin{background:#6a1b9a;color:#fff;font-size:18px;padding:10px 16px;border-radius:6px;margin:0 0 12px}
.origin b{font-size:22px;letter-spacing:1px}
.donotwrite{border:3px solid #c62828;border-radius:6px;padding:6px 12px 8px;margin:10px 0;background:#f5f5f5}
.donotwrite-banner{color:#c62828;font-weight:800;font-size:18px;margin:2px 0 6px}
.void{display:block;color:#9e9e9e;font-family:Consolas,"DejaVu Sans Mono",monospace;font-size:16px;
 text-decoration:line-through;background:#ececec;border:1px dashed #bdbdbd;border-radius:4px;padding:8px 10px;
 margin:4px 0 10px;word-break:break-all;user-select:none;-webkit-user-select:none}
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def _num(value, fmt="{:.3f}") -> str:
    return "n/a" if value is None else fmt.format(value)


def _kv(pairs) -> str:
    return '<div class="kv">' + "".join(f"<div>{_e(k)}</div><div>{v}</div>" for k, v in pairs) + "</div>"


#: What the report says about where the data come from (``station.origin``).
_ORIGIN_FACTS = {
    "real": "the real station (capture record in session.yaml)",
    "mock": "a mock station, embedded or a rehearsal (simulated robot and camera)",
    "simulated": "a simulation (truth.yaml beside the session)",
    "unknown": "not recorded (imported or hand-written session)",
}


def _origin_banner(origin: str) -> str:
    banner = origin_banner(origin)
    if banner is None:
        return ""
    word, text = banner
    return f'<div class="origin" data-origin="{_e(origin)}"><b>{_e(word)}</b> &ndash; {_e(text)}</div>'


def _literals(x, tooldata_literal, label: str, verdict) -> list[str]:
    """The RAPID literals: copyable unless the verdict failed; then greyed out, struck through, not
    selectable, under a banner that says not to write them."""
    literals = [(f"{label}, RAPID literal:", pose_literal(x))]
    if tooldata_literal:
        literals.append(("tooldata:", tooldata_literal))
    if verdict is None or verdict.passed:
        return [item for caption, text in literals for item in
                (f'<div style="margin-top:10px">{_e(caption)}</div>', f'<code class="literal">{_e(text)}</code>')]
    body = "".join(f'<div>{_e(caption)} (failed result, for reference only)</div><del class="void">{_e(text)}</del>'
                   for caption, text in literals)
    return ['<div class="donotwrite"><div class="donotwrite-banner">FAIL &ndash; do not write this into the robot'
            "</div>" + body + '<div class="note">Act on the failed checks below, then calibrate again; '
            "<code>handeye writeback</code> refuses a failed result.</div></div>"]


def _verdict_banner(verdict: Verdict | None) -> str:
    if verdict is None:
        return '<div class="verdict none">NO VERDICT</div><div class="verdict-line">no thresholds were applied</div>'
    cls, word = ("pass", "PASS") if verdict.passed else ("fail", "FAIL")
    failed = verdict.failed
    line = ("every quality check passed" if verdict.passed else
            (f"{verdict.cause}. " if verdict.cause else "")
            + f"{len(failed)} of {len(verdict.checks)} checks failed: " + ", ".join(c.name for c in failed)
            + " (see the advice below)")
    return f'<div class="verdict {cls}">{word}</div><div class="verdict-line">{_e(line)}</div>'


def _pose_facts(result) -> list:
    """The camera pose and its uncertainty, as (label, HTML) pairs."""
    position, quaternion = rounded_pose(result.x)
    euler = Rotation.from_matrix(result.x[:3, :3]).as_euler("ZYX", degrees=True)
    pose = [
        ("position", f"x {position[0]:.3f} &nbsp; y {position[1]:.3f} &nbsp; z {position[2]:.3f} mm"),
        ("quaternion q1..q4", " &nbsp; ".join(f"{v:.6f}" for v in quaternion)),
        ("Euler ZYX", f"z {euler[0]:.4f} &nbsp; y {euler[1]:.4f} &nbsp; x {euler[2]:.4f} deg"),
    ]
    u = result.uncertainty
    if u is not None:
        pose += [("uncertainty, position", "&plusmn; " + " / ".join(f"{v:.3f}" for v in u["translation_mm"])
                  + " mm (x / y / z, one sigma)"),
                 ("uncertainty, rotation", "&plusmn; " + " / ".join(f"{v:.4f}" for v in u["rotation_deg"])
                  + " deg (about x / y / z, one sigma)")]
    else:
        pose.append(("uncertainty", f"not estimated by method {_e(result.method)} (the default does)"))
    cv = result.cross_validation
    if cv:  # the default estimator's held-out accuracy (calibration/crossval.py)
        pose.append(("cross-validated accuracy", f"{cv['rms_mm']:.3f} mm RMS of held-out board points ({cv['folds']}-fold)"
                     + (f"; the noise model predicts {cv['predicted_rms_mm']:.3f} mm" if "predicted_rms_mm" in cv else "")))
        if cv.get("systematic"):
            pose.append(("systematic error", _e(cv.get("advice", ""))))
    return pose


def _session_facts(a: Assessment) -> list:
    """Session, origin, method, postures, outliers, d_org (and d_org incl. outliers), times, truth errors."""
    result, n, scatter = a.result, a.problem.n, a.d_org
    outliers = [int(i) for i in result.outliers]
    residual_text = ", ".join(f"{i} ({result.residuals_mm.get(i, float('nan')):.2f} mm)" for i in outliers)
    facts = [
        ("session", f"<code>{_e(a.session_path)}</code>"),
        ("data from", _e(_ORIGIN_FACTS.get(a.origin, a.origin))),
        ("set-up", _e(result.setup.replace("_", "-"))),
        ("method", _e(result.method)),
        ("postures", f"{n} captured, {n - len(outliers)} used, {len(outliers)} outlier{'s' if len(outliers) != 1 else ''}"),
        ("outliers (residual)", _e(residual_text) if outliers else "none"),
        ("d_org", f'<span class="num" data-d-org="header">{scatter.mm:.3f} mm</span><br>'
                  f'<span class="note">{_e(scatter.basis())} (eq. 22)</span>'),
    ]
    if result.excluded:
        facts.append(("left out before solving", _excluded_html(result.excluded)))
    if scatter.incl_outliers_mm is not None:
        facts.append((D_ORG_ALL_NAME, f"{scatter.incl_outliers_mm:.3f} mm (the same over all {n} postures)"))
    facts.append(("solve time", f"{1000 * result.runtime_s:.1f} ms"))
    if result.truth_errors is not None:
        errors = result.truth_errors
        text = f"{errors['translation_error_mm']:.3f} mm, {errors['rotation_error_deg']:.4f} deg (synthetic session)"
        facts.append(("error vs truth", text))
    return facts


def _summary(a: Assessment) -> str:
    """The head of the report: origin banner, verdict, RAPID literals, pose and session facts."""
    verdict, eye_in_hand = a.verdict, a.result.setup == EYE_IN_HAND
    literal_label = "tframe (camera in tool0)" if eye_in_hand else "camera pose in base"
    parts = [_origin_banner(a.origin), _verdict_banner(verdict)] + _literals(a.result.x, a.tooldata_literal,
                                                                             literal_label, verdict)
    if eye_in_hand and not a.tooldata_literal and (verdict is None or verdict.passed):
        parts.append('<div class="note">tooldata: the load (mass, centre of gravity) comes from the station '
                     'configuration; <code>handeye writeback</code> writes the full tooldata with this tframe.</div>')
    return ("<section>" + "".join(parts) + '<div class="grid">' + _kv(_pose_facts(a.result))
            + _kv(_session_facts(a)) + "</div></section>")


def _checks_table(verdict: Verdict) -> str:
    rows = []
    for c in verdict.checks:
        label = CHECK_LABELS.get(c.name, (c.name,))[0]
        comparator = "&le;" if c.name.startswith("max_") else "&ge;"
        status = '<span class="ok">pass</span>' if c.passed else '<span class="ko">FAIL</span>'
        rows.append(
            f'<tr class="{"" if c.passed else "bad"}"><td>{status}</td><td>{_e(label)}<br><code class="note">{_e(c.name)}'
            f'</code></td><td class="num">{_e(format_check_value(c.name, c.value))}</td>'
            f'<td class="num">{comparator} {_e(format_check_value(c.name, c.limit))}</td><td>{_e(c.advice)}</td></tr>')
    return ("<table><tr><th></th><th>check (threshold key)</th><th>value</th><th>limit</th><th>what to do</th></tr>"
            + "".join(rows) + "</table>")


def _comparison_table(rows: list[dict]) -> str:
    with_all = any(r["d_org_incl_outliers_mm"] is not None for r in rows)
    with_truth = any(r["truth_errors"] for r in rows)
    head = ["method", "held-out (mm)", "x (mm)", "y (mm)", "z (mm)", "&Delta; position (mm)", "&Delta; rotation (deg)",
            "d_org (mm)"]
    if with_all:
        head.append(f"{_e(D_ORG_ALL_NAME)} (mm)")
    if with_truth:
        head += ["truth error (mm)", "truth error (deg)"]
    head += ["outliers", "solve (ms)"]
    out = ["<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>"]
    for r in rows:
        cells = [_e(r["method"] + (" (chosen)" if r["chosen"] else ""))]
        cells.append(f'<td class="num">{_num(r.get("held_out_mm"))}</td>')
        cells += [f'<td class="num">{v:.3f}</td>' for v in r["position_mm"]]
        cells += [f'<td class="num">{r["d_position_mm"]:.3f}</td>', f'<td class="num">{r["d_rotation_deg"]:.4f}</td>',
                  f'<td class="num">{r["d_org_mm"]:.3f}</td>']
        if with_all:
            cells.append(f'<td class="num">{_num(r["d_org_incl_outliers_mm"])}</td>')
        if with_truth:
            t = r["truth_errors"] or {}
            cells += [f'<td class="num">{_num(t.get("translation_error_mm"))}</td>',
                      f'<td class="num">{_num(t.get("rotation_error_deg"), "{:.4f}")}</td>']
        cells += [f"<td>{_e(', '.join(map(str, r['outliers'])) or '-')}</td>",
                  f'<td class="num">{1000 * r["runtime_s"]:.1f}</td>']
        first = f"<td>{cells[0]}</td>"
        out.append(f'<tr class="{"chosen" if r["chosen"] else ""}">' + first + "".join(cells[1:]) + "</tr>")
    return "".join(out) + "</table>"


def _metrics_table(a: Assessment) -> str:
    result, scatter = a.result, a.d_org
    m = result.metrics
    rows = [
        ("d_org", f"{scatter.mm:.3f} mm", METRIC_MEANINGS["d_org"]),
        ("d_back", f"{m['d_back_mm']:.3f} mm", METRIC_MEANINGS["d_back"]),
        ("dR", f"{m['delta_r']:.5f}", METRIC_MEANINGS["dR"]),
        ("dt", f"{m['delta_t_mm']:.3f} mm", METRIC_MEANINGS["dt"]),
    ]
    if scatter.incl_outliers_mm is not None:
        rows.insert(1, (D_ORG_ALL_NAME, f"{scatter.incl_outliers_mm:.3f} mm",
                        f"{METRIC_MEANINGS[D_ORG_ALL_NAME]} ({a.problem.n} postures)"))
    if result.truth_errors is not None:
        rows += [("rotation error", f"{result.truth_errors['rotation_error_deg']:.4f} deg", "against the synthetic truth"),
                 ("translation error", f"{result.truth_errors['translation_error_mm']:.3f} mm", "against the synthetic truth")]
    body = "".join(f'<tr><td>{_e(x)}</td><td class="num">{_e(y)}</td><td>{_e(z)}</td></tr>' for x, y, z in rows)
    return (f'<table><tr><th>metric</th><th>value</th><th>meaning</th></tr>{body}</table>'
            f'<p class="note">d_org and d_back are computed {_e(scatter.basis())}; dR and dt over the pairs of the '
            f'same postures. Lower is better.</p>')


# -------------------------------------------------------------------------------------- sections
def _checks_section(verdict: Verdict) -> str:
    return ("<h2>Quality checks</h2><section>" + _checks_table(verdict)
            + '<p class="note">Thresholds: defaults of <code>handeye.station.quality.QualityThresholds</code>'
              " unless a thresholds file was given (handeye calibrate --thresholds FILE.yaml).</p></section>")


def _residuals_section(a: Assessment, fixed_frame: str) -> str:
    result = a.result
    limit = a.verdict.thresholds.max_posture_residual_mm if a.verdict is not None else None
    outliers = [int(i) for i in result.outliers]
    residual_note = ("Outliers (left out of the solution): "
                     + ", ".join(f"posture {i}: {result.residuals_mm.get(i, float('nan')):.2f} mm" for i in outliers)
                     if outliers else "No posture was left out as an outlier.")
    return (
        "<h2>1. Per-posture residuals</h2><section>"
        f'<p class="how">Each bar: the {_e(result.residuals_meaning)}; the fixed frame is {fixed_frame}. '
        f"Bars should be about equal; a bar well above "
        f"the others is a posture to check (board partly hidden or misdetected, robot not at rest)."
        + (f" Dashed line: the limit max_posture_residual_mm = {limit:g} mm." if limit is not None else "") + "</p>"
        + _img(plot_residuals(result, a.problem, limit), "per-posture residuals")
        + f'<p class="note">{_e(residual_note)}</p>'
        + (f'<p class="note">Outliers left out before solving (the robot and board poses of the session fit no '
           f"rigid camera mount with them): {_excluded_html(result.excluded)}</p>" if result.excluded else "")
        + "</section>")


def _excluded_html(excluded: dict) -> str:
    """Gross postures left out before solving, each with its reason (``CalibrationResult.excluded``)."""
    return "<br>".join(f"posture {int(i)}: {_e(reason)}" for i, reason in excluded.items())


def _coverage_section(a: Assessment) -> str:
    coverage, frame = a.coverage, hand_frame(a.problem.setup)
    return (
        "<h2>2. Rotation-axis coverage</h2><section>"
        f'<p class="how">Every dot is the rotation axis of the flange motion between two used postures, in {frame} '
        f"coordinates, drawn on a unit sphere seen from two sides (an axis and its opposite are the same, so each "
        f"view shows every axis once); colour and size grow with the rotation angle. Regions without dots are "
        f"directions the flange never turned about; the red ring marks the least exercised direction "
        f"({_e(direction_name(coverage.weakest_direction, coverage.frame))}). Right: how much the flange turned "
        f"about each {frame} axis.</p>"
        + _img(plot_axis_coverage(coverage), "rotation-axis coverage")
        + f'<p class="note">{len(coverage.axes)} posture pairs with a usable axis; median relative rotation angle '
          f"between two postures {coverage.median_angle_deg:.1f} deg; rotation-axis spread {coverage.spread_deg:.1f} deg "
          f"(0 = all axes in one plane, 35.3 = even over the sphere).</p></section>")


def _comparison_section(a: Assessment) -> str:
    if not a.comparison:
        return ('<h2>3. Method comparison</h2><section><p class="note">Not computed '
                "(no comparison results were given).</p></section>")
    rows = a.comparison
    return (
        "<h2>3. Method comparison</h2><section>"
        '<p class="how">The same data solved by other methods, ranked by the held-out error: the RMS distance of a '
        "posture's board points from where a fit without that posture puts them (the same folds for every method, "
        "over the postures the chosen result kept). &Delta; = difference from the chosen result "
        "(position distance, rotation angle). d_org (eq. 22) is computed for every method on the same data, "
        f"{_e(a.d_org.basis())}, as in the header and the verdict, so the column compares "
        "like with like"
        + (f"; {_e(D_ORG_ALL_NAME)}: the same over all {a.problem.n} postures. " if a.result.outliers else ". ")
        + "Methods that agree within a few tenths of a millimetre confirm the result; one far off is usually a "
        "method thrown by outliers or weak geometry.</p>"
        + (f'<p class="note" data-note="d-org">{_e(a.comparison_note)}</p>' if a.comparison_note else "")
        + _comparison_table(rows) + _img(plot_method_comparison(rows), "method comparison") + "</section>")


def _repeatability_section(a: Assessment, fixed_frame: str) -> str:
    rep = a.repeatability
    rms = rep["rms_per_point"]
    radial = np.linalg.norm(rep["centre_deviation"][rep["inliers"]], axis=1)
    scatter_png, clipped = plot_repeatability(a.problem, a.result, rep)
    clipped_note = (f" Outlier postures whose board lies beyond the plotted frame: {', '.join(map(str, clipped))}."
                    if clipped else "")
    return (
        f"<h2>4. Repeatability of the board corners in {fixed_frame}</h2><section>"
        f'<p class="how">The board does not move, so with the right camera pose every posture should put each board '
        f"corner at the same place in {fixed_frame}. The plots show each corner's deviation from its mean position "
        f"over the used postures (grey; outlier postures red) and each posture's board centre (blue), seen from "
        f"above and from the side. A tight round cloud is noise; a posture's centre far from the rest is a posture "
        f"to check; an elongated cloud points at a direction the calibration could not pin down.</p>"
        + _img(scatter_png, "repeatability of the board corners, top and side views")
        + f'<p class="note">Board centre over the used postures: RMS '
          f"{float(np.sqrt(np.mean(radial ** 2))) if radial.size else 0.0:.3f} mm, largest "
          f"{float(radial.max()) if radial.size else 0.0:.3f} mm.{_e(clipped_note)}</p>"
        + '<p class="how">Per-corner RMS deviation, laid out as on the board (point 0 = the first corner, the '
          "target origin): a uniform level is camera noise; a "
          "gradient across the board points at a rotation error of the camera pose or a scale error of the stereo "
          "model; single hot corners are detection problems.</p>"
        + _img(plot_point_rms(a.problem, rep), "per-corner RMS deviation")
        + f'<p class="note">Per-corner RMS: median {np.median(rms):.3f} mm, largest {rms.max():.3f} mm '
          f"(point {int(np.argmax(rms))}).</p></section>")


def _preview_section(png: bytes | None, missing: str | None = None) -> str:
    if png is None:
        return f'<h2>Capture plan: the cell</h2><section><p class="note">Preview not shown: {_e(missing)}</p></section>'
    return ("<h2>Capture plan: the cell</h2><section>"
            '<p class="how">The preview written before the robot moved: the keep-out volumes and the board\'s stand, the '
            "board, the path the flange ran and the postures, numbered as their files (postures/NNN.yaml) and as "
            "this report names them, from above and from the side (base frame, mm).</p>"
            + _img(png, "capture plan preview: the cell from above and from the side") + "</section>")


def _findings_section(findings, postures: int) -> str:
    items = "".join(f"<li>{_e(f)}</li>" for f in findings)
    body = f"<ul>{items}</ul>" if findings else '<p class="note">Nothing odd found in the poses.</p>'
    pairs = pairs_used(len(bounded_pairs(postures)), postures)
    return ("<h2>Data checks before solving</h2><section>" + body
            + f'<p class="how">The pairwise checks ran on {_e(pairs)}.</p></section>')


_FOOTER = (
    "<footer>Units: mm and degrees; quaternions q1..q4 = (w, x, y, z), scalar first. The camera frame is the left "
    "camera of the stereo head (x right, y down, z forward). Uncertainties are one sigma from the "
    "estimator's covariance (random errors); the cross-validated accuracy also shows systematic ones. Report "
    "written by handeye.</footer>")


def write_report(path_html, assessment: Assessment, title: str = "Hand-eye calibration report") -> Path:
    """Write the calibration report of an assessment as one self-contained HTML file.

    Parameters
    ----------
    path_html : str or Path
        The file to write (written atomically; its folder must exist).
    assessment : Assessment
        From ``station.assessment.assess``: the result, its verdict (the PASS/FAIL banner and the
        checks, when judged), the method comparison (when compared), the data checks, the origin (mock
        and simulated sessions get a banner saying they are not a calibration of a real robot).
    title : str

    Returns
    -------
    Path

    Raises
    ------
    HandEyeError
        When the folder does not exist or the file cannot be written.
    """
    path = Path(path_html)
    if not path.parent.is_dir():
        raise HandEyeError(f"cannot write the report {path}: folder {path.parent} does not exist")
    a = assessment
    fixed_frame = "base" if a.problem.setup == EYE_IN_HAND else "tool0"
    now = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    sections = [f"<h1>{_e(title)}</h1>",
                f'<div class="sub">{_e(a.session_path)} &middot; {_e(a.result.setup.replace("_", "-"))} &middot; '
                f"method {_e(a.result.method)} &middot; generated {_e(now)}</div>", _summary(a)]
    if a.verdict is not None:
        sections.append(_checks_section(a.verdict))
    sections += [_residuals_section(a, fixed_frame), _coverage_section(a), _comparison_section(a),
                 _repeatability_section(a, fixed_frame),
                 "<h2>5. Quality metrics</h2><section>" + _metrics_table(a) + "</section>"]
    if a.findings is not None:
        sections.append(_findings_section(a.findings, a.problem.n))
    if a.plan_preview is not None or a.plan_preview_missing is not None:
        sections.append(_preview_section(a.plan_preview, a.plan_preview_missing))
    sections.append(_FOOTER)
    document = ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{_e(title)}</title>"
                f"<style>{_CSS}</style></head><body><main>" + "\n".join(sections) + "</main></body></html>\n")
    try:
        write_text_atomic(path, document)
    except OSError as exc:
        raise HandEyeError(f"cannot write the report {path}: {exc.strerror or exc}") from None
    return path
