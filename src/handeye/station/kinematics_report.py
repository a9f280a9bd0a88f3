"""The report's section on the arm's kinematics: the identified offsets and a map of the predicted
error of the stand-off point over the arm's working volume, with and without the correction."""

from __future__ import annotations

import numpy as np

from .report.figures import new_figure, style_axes, to_png
from .report.html import escape, img

__all__ = ["plot_standoff_map", "volume_standoff", "kinematics_section"]

#: Postures drawn over the working volume for the map.
VOLUME_POSTURES = 600


def volume_standoff(ident, standoff_mm: float, count: int = VOLUME_POSTURES):
    """The predicted stand-off error (``calibration.standoff.StandoffError``, no draws) at ``count``
    postures spread over the arm's working volume (``calibration.standoff.working_volume_joints``)."""
    from ..calibration import predicted_standoff
    from ..calibration import working_volume_joints
    from ..robot import load_robot

    joints = working_volume_joints(load_robot(ident.robot), ident.camera_only.fit.x, count)
    return predicted_standoff(ident, joints, standoff_mm, draws=0)


def plot_standoff_map(volume, plan=None) -> bytes:
    """Four panels: without / with the correction (columns), the stand-off point of every posture of
    ``volume`` seen from above (base x, y) and from the side (distance from axis 1, base z; mm),
    coloured by its predicted error (mm, one logarithmic colour scale); the plan's postures (``plan``,
    a StandoffError) as crosses."""
    from matplotlib.colors import LogNorm

    fig = new_figure(10.0, 8.0, layout="constrained")
    axes = fig.subplots(2, 2, sharex="row", sharey="row")
    low = float(max(np.min(volume.corrected_mm), 1e-6))
    norm = LogNorm(vmin=low, vmax=float(max(np.max(volume.uncorrected_mm), 2 * low)))
    p = volume.points_mm
    views = ((p[:, 0], p[:, 1], "base x (mm)", "base y (mm)"),
             (np.hypot(p[:, 0], p[:, 1]), p[:, 2], "distance from axis 1 (mm)", "base z (mm)"))
    for col, (values, name) in enumerate(((volume.uncorrected_mm, "without correction"),
                                          (volume.corrected_mm, "with the identified arm"))):
        order = np.argsort(values)  # the largest errors drawn last, on top
        for row, (h, v, hl, vl) in enumerate(views):
            ax = axes[row, col]
            shown = ax.scatter(h[order], v[order], c=values[order], cmap="viridis", norm=norm, s=10, linewidths=0)
            if plan is not None:
                q = plan.points_mm
                ph, pv = (q[:, 0], q[:, 1]) if row == 0 else (np.hypot(q[:, 0], q[:, 1]), q[:, 2])
                ax.scatter(ph, pv, marker="x", color="#c62828", s=14, linewidths=0.8, alpha=0.7,
                           label="the plan's postures" if row == 0 and col == 0 else None)
            ax.set_xlabel(hl)
            ax.set_aspect("equal", adjustable="box")
            style_axes(ax)
        axes[0, col].set_title(f"{name}: RMS {np.sqrt(np.mean(values ** 2)):.3f} mm, "
                               f"median {np.median(values):.3f} mm", fontsize=10)
        axes[0, 0].set_ylabel(views[0][3])
        axes[1, 0].set_ylabel(views[1][3])
    if plan is not None:
        axes[0, 0].legend(fontsize=8, loc="upper right")
    bar = fig.colorbar(shown, ax=axes.ravel().tolist(), shrink=0.8)
    bar.set_label(f"predicted error of the point at {volume.standoff_mm:g} mm (mm, board frame)")
    return to_png(fig)


def kinematics_section(ident, standoff, lines: list[str]) -> str:
    """The HTML section: the summary lines and (eye-in-hand) the stand-off map over the working volume."""
    body = "<pre>" + escape("\n".join(lines)) + "</pre>"
    if standoff is not None:
        volume = volume_standoff(ident, standoff.standoff_mm)
        body += img(plot_standoff_map(volume, standoff), "predicted stand-off error over the working volume")
        body += ("<p>Each dot is the stand-off point of one of "
                 f"{len(volume.corrected_mm)} postures drawn over the arm's working volume (uniform inside the joint "
                 "limits, the arm and the camera above the base's plane; the cell's bodies are not checked), seen "
                 "from above and from the side; its colour the predicted error of that point in the board's frame "
                 "from the full covariance (camera, board, kinematics, noise). Crosses: the plan's postures, where "
                 "the calibration was measured; away from them the correction is an extrapolation and its error "
                 "grows.</p>")
    return "<h2>Arm kinematics and the error at the stand-off</h2><section>" + body + "</section>"
