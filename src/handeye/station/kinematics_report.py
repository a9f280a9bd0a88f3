"""The report's section on the arm's kinematics: the identified offsets and a map of the predicted
error of the stand-off point over the working volume, with and without the correction."""

from __future__ import annotations

import numpy as np

from .report.figures import new_figure, style_axes, to_png
from .report.html import escape, img

__all__ = ["plot_standoff_map", "kinematics_section"]


def plot_standoff_map(standoff) -> bytes:
    """Two panels (without / with correction): the stand-off point of every posture seen from above
    (base x, y; mm), coloured by its predicted error (mm, one colour scale for both)."""
    fig = new_figure(9.0, 3.8, layout="constrained")
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    vmax = float(max(np.max(standoff.uncorrected_mm), 1e-9))
    points = standoff.points_mm
    for ax, values, name in ((axes[0], standoff.uncorrected_mm, "without correction"),
                             (axes[1], standoff.corrected_mm, "with the identified arm")):
        shown = ax.scatter(points[:, 0], points[:, 1], c=values, cmap="viridis", vmin=0.0, vmax=vmax, s=42,
                           edgecolors="k", linewidths=0.3)
        ax.set_title(f"{name}: RMS {np.sqrt(np.mean(values ** 2)):.3f} mm", fontsize=10)
        ax.set_xlabel("base x (mm)")
        ax.set_aspect("equal", adjustable="box")
        style_axes(ax)
    axes[0].set_ylabel("base y (mm)")
    bar = fig.colorbar(shown, ax=list(axes), shrink=0.9)
    bar.set_label(f"predicted error at {standoff.standoff_mm:g} mm (mm)")
    return to_png(fig)


def kinematics_section(ident, standoff, lines: list[str]) -> str:
    """The HTML section: the summary lines and (eye-in-hand) the stand-off map."""
    body = "<pre>" + escape("\n".join(lines)) + "</pre>"
    if standoff is not None:
        body += img(plot_standoff_map(standoff), "predicted stand-off error over the working volume")
        body += ("<p>Each dot is the stand-off point of one posture of the plan seen from above; its colour the "
                 "predicted error of that point in the board's frame from the full covariance (camera, board, "
                 "kinematics, noise).</p>")
    return "<h2>Arm kinematics and the error at the stand-off</h2><section>" + body + "</section>"
