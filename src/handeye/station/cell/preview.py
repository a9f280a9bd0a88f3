"""The preview of a plan: the cell seen from above and from the side, before anything moves.

One PNG (``SESSION/preview.png``, and in the report): the keep-out volumes (boxes, cylinders, the
floor, the board's stand), the board, the whole arm at the start posture (every capsule the cell and
self-collision checks watch: the robot file's bodies, the base and links 1-6), the path the flange will run (tool0's origin along the
joint-interpolated moves, from the start posture through every posture in order) and the numbered
postures (the flange there), each by its number: its file's, ``postures/NNN.yaml`` -> NNN
(:func:`posture_labels`), as capture, calibrate and the report name it. Two views of the base frame: from above (x, y) and from the side
(x, z; the robot's foot at the origin). mm.

matplotlib's object API (``Figure`` + Agg canvas), no pyplot, as the report's figures; the posture
numbers are placed so no two overlap (where a view is too crowded for one, that view leaves it out:
the other view, or the plan's joints in the session, still have it).
"""

from __future__ import annotations

import io

import numpy as np

from ...robot import Box, Cylinder, Floor
from ...robot import CellGuard
from ...robot import RobotModel
from ..board_square import known_square_mm
from ..capture.planning import PosturePlan

__all__ = ["plan_preview_figure", "plan_preview_png", "posture_labels", "write_preview"]

_VOLUME, _STAND, _BOARD, _PATH, _CAMERA = "#c62828", "#ef8a17", "#1f5fa8", "#555555", "#1f5fa8"
_ARM = "#7a7a7a"
#: The two views: (title, index of the horizontal axis, of the vertical axis, their names).
_VIEWS = (("from above", 0, 1, ("x (mm)", "y (mm)")), ("from the side (looking along +y)", 0, 2, ("x (mm)", "z (mm)")))


def _hull(points_2d: np.ndarray) -> np.ndarray:
    """Convex hull (counter-clockwise) of 2-D points (monotone chain)."""
    pts = sorted(map(tuple, np.round(points_2d, 6)))
    if len(pts) <= 2:
        return np.array(pts)

    def turn(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and turn(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])


def _volume_patch(ax, volume, h: int, v: int, extent):
    from matplotlib.patches import Polygon, Rectangle

    stand = volume.name.startswith("board stand")
    colour = _STAND if stand else _VOLUME
    style = {"facecolor": colour, "alpha": 0.18, "edgecolor": colour, "linewidth": 1.2}
    if isinstance(volume, Floor):
        if v == 2:
            ax.add_patch(Rectangle((extent[0], extent[2] - 1e4), extent[1] - extent[0], volume.z_mm - extent[2] + 1e4,
                                   hatch="//", **style))
        return
    if isinstance(volume, Cylinder):
        low, high = volume.z_mm
        if v == 1:
            from matplotlib.patches import Circle

            ax.add_patch(Circle(volume.centre_mm, volume.radius_mm, **style))
        else:
            ax.add_patch(Rectangle((volume.centre_mm[0] - volume.radius_mm, low), 2 * volume.radius_mm, high - low, **style))
        return
    if isinstance(volume, Box):
        ax.add_patch(Polygon(_hull(volume.corners()[:, [h, v]]), closed=True, **style))


def _draw_arm(ax, segments: np.ndarray, radii, h: int, v: int) -> None:
    """The arm's capsules ``(B, 2, 3)`` (base frame) seen along the third axis: each the outline of its two
    end circles (the capsule's silhouette in that view)."""
    from matplotlib.patches import Polygon

    turn = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    circle = np.stack([np.cos(turn), np.sin(turn)], axis=1)
    for (a, b), r in zip(segments, radii):
        outline = np.vstack([a[[h, v]] + r * circle, b[[h, v]] + r * circle])
        ax.add_patch(Polygon(_hull(outline), closed=True, facecolor=_ARM, edgecolor=_ARM, alpha=0.25, linewidth=0.8))


def _arm_at(robot: RobotModel, guard, joints) -> tuple[np.ndarray, list]:
    """The capsules' axes ``(B, 2, 3)`` at ``joints`` and their radii (the guard's, or the robot's alone)."""
    from ...robot import arm_capsules

    guard = guard if guard is not None else CellGuard(robot, [], self_collision=False)
    return guard.capsule_segments(joints)[0], [c[4] for c in arm_capsules(robot)]


def _flange_path(robot: RobotModel, plan: PosturePlan, guard) -> np.ndarray:
    """tool0 origins ``(m, 3)`` along the moves from the start through every posture in order."""
    nodes = np.vstack([plan.start_joints_deg[None], plan.joints_deg])
    samples = [guard.path_samples(a, b) for a, b in zip(nodes[:-1], nodes[1:])] if guard is not None else \
        [a + np.linspace(0, 1, 20)[:, None] * (b - a) for a, b in zip(nodes[:-1], nodes[1:])]
    return robot.forward_transform(np.concatenate(samples))[:, :3, 3]


def _place_labels(ax, points_2d, labels, renderer, taken: list) -> int:
    """Numbers beside their points, each where it overlaps no other text (8 directions, 3 distances);
    returns how many found no place (left out)."""
    offsets = [(dx * r, dy * r) for r in (5, 10, 16) for dx, dy in
               ((1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1))]
    frame = ax.get_window_extent(renderer)
    missing = 0
    for (x, y), text in zip(points_2d, labels):
        for dx, dy in offsets:
            label = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", fontsize=7,
                                ha="left" if dx >= 0 else "right", va="bottom" if dy >= 0 else "top", color=_CAMERA)
            box = label.get_window_extent(renderer).padded(2.0)
            inside = frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
            if inside and not any(box.overlaps(other) for other in taken):
                taken.append(box)
                break
            label.remove()
        else:
            missing += 1
    return missing


def posture_labels(count: int) -> list[str]:
    """The numbers written beside the ``count`` planned postures, in visiting order: the numbers of the
    files they will be captured into (``postures/000.yaml`` -> ``0``)."""
    return [str(index) for index in range(count)]


#: How far beyond the robot, the board and the postures a volume still widens the view, mm.
_VOLUME_REACH_MM = 300.0
#: Border around everything shown, mm.
_BORDER_MM = 150.0


def _bounds(volume, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds ``(low, high)``, each shape (3,), of a volume in base (a floor: its top, under
    the middle of ``points``)."""
    if isinstance(volume, Box):
        corners = volume.corners()
        return corners.min(axis=0), corners.max(axis=0)
    if isinstance(volume, Cylinder):
        c, r = volume.centre_mm, volume.radius_mm
        return np.array([c[0] - r, c[1] - r, volume.z_mm[0]]), np.array([c[0] + r, c[1] + r, volume.z_mm[1]])
    top = np.array([points[:, 0].mean(), points[:, 1].mean(), volume.z_mm])
    return top, top


def _extent(points: np.ndarray, volumes) -> np.ndarray:
    """``[xmin, xmax, ymin, ymax, zmin, zmax]`` framing the points (the robot's base, the board, the flange
    path and postures) and the parts of the volumes within :data:`_VOLUME_REACH_MM` of them, with a border:
    a huge keep-out volume is clipped to the view instead of shrinking the postures to a dot cluster."""
    low, high = points.min(axis=0), points.max(axis=0)
    near_low, near_high = low - _VOLUME_REACH_MM, high + _VOLUME_REACH_MM
    for volume in volumes:
        v_low, v_high = _bounds(volume, points)
        part_low, part_high = np.maximum(v_low, near_low), np.minimum(v_high, near_high)
        if np.all(part_low <= part_high):  # the volume reaches near the scene: frame that part of it
            low, high = np.minimum(low, part_low), np.maximum(high, part_high)
    low, high = low - _BORDER_MM, high + _BORDER_MM
    return np.array([low[0], high[0], low[1], high[1], low[2], high[2]])


def plan_preview_png(robot: RobotModel, plan: PosturePlan) -> bytes:
    """The preview of ``plan`` (:func:`plan_preview_figure`) as PNG bytes."""
    buffer = io.BytesIO()
    plan_preview_figure(robot, plan).savefig(buffer, format="png", dpi=100, facecolor="white")
    return buffer.getvalue()


def plan_preview_figure(robot: RobotModel, plan: PosturePlan):
    """The preview of ``plan`` (its cell: ``plan.cell``; none: the board and the path only), a matplotlib
    ``Figure`` on an Agg canvas."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    guard = plan.cell.guard(robot, plan.board2base, plan.board) if plan.cell is not None else None
    volumes = guard.volumes if guard is not None else []
    path = _flange_path(robot, plan, guard)
    flanges = robot.forward_transform(plan.joints_deg)[:, :3, 3]
    start = robot.forward_transform(plan.start_joints_deg)[:3, 3]
    cols, rows = plan.board.corners
    s = known_square_mm(plan.board)
    outline = np.array([[-s, -s, 0], [cols * s, -s, 0], [cols * s, rows * s, 0], [-s, rows * s, 0], [-s, -s, 0]])
    board = outline @ plan.board2base[:3, :3].T + plan.board2base[:3, 3]
    arm, arm_radii = _arm_at(robot, guard, plan.start_joints_deg)
    extent = _extent(np.vstack([path, board, [[0.0, 0.0, 0.0]], arm.reshape(-1, 3)]), volumes)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(figsize=(13.0, 6.4), dpi=100)
    fig.patch.set_facecolor("white")
    canvas = FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2, gridspec_kw={"left": 0.06, "right": 0.99, "bottom": 0.16, "top": 0.9, "wspace": 0.15})
    for ax, (title, h, v, names) in zip(axes, _VIEWS):
        for volume in volumes:
            _volume_patch(ax, volume, h, v, extent)
        _draw_arm(ax, arm, arm_radii, h, v)
        ax.fill(board[:, h], board[:, v], color=_BOARD, alpha=0.35, linewidth=1.5)
        ax.plot(path[:, h], path[:, v], color=_PATH, linewidth=0.8, alpha=0.8)
        ax.plot(flanges[:, h], flanges[:, v], "o", color=_CAMERA, markersize=3.5)
        ax.plot([start[h]], [start[v]], "s", color="black", markersize=5)
        ax.plot([0.0], [0.0], "^", color="black", markersize=7)
        ax.set_xlim(extent[2 * h], extent[2 * h + 1])
        ax.set_ylim(extent[2 * v], extent[2 * v + 1])
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.25)
    canvas.draw()  # the axes are where they will be: the numbers can be placed
    renderer = canvas.get_renderer()
    left_out = []
    for ax, (title, h, v, _) in zip(axes, _VIEWS):
        taken = [t.get_window_extent(renderer) for t in (ax.title, ax.xaxis.label, ax.yaxis.label)]
        missing = _place_labels(ax, flanges[:, [h, v]], posture_labels(len(flanges)), renderer, taken)
        if missing:
            left_out.append(f"{missing} number{'s' if missing != 1 else ''} left out {title.split(' (')[0]} (crowded)")
    handles = [Patch(facecolor=_VOLUME, alpha=0.3, edgecolor=_VOLUME, label="keep-out volume"),
               Patch(facecolor=_STAND, alpha=0.3, edgecolor=_STAND, label="board stand"),
               Patch(facecolor=_BOARD, alpha=0.35, label="board"),
               Patch(facecolor=_ARM, alpha=0.25, edgecolor=_ARM, label="arm at the start"),
               Line2D([], [], color=_PATH, label="flange path (tool0)"),
               Line2D([], [], marker="o", linestyle="", color=_CAMERA, label="flange at posture n"),
               Line2D([], [], marker="s", linestyle="", color="black", label="start (flange)"),
               Line2D([], [], marker="^", linestyle="", color="black", label="robot base")]
    fig.legend(handles=handles, loc="lower center", ncol=8, fontsize=8, frameon=False)
    margin = f"margin {plan.cell.margin_mm:g} mm" if plan.cell is not None else "no cell given"
    notes = "; ".join([margin] + left_out)
    fig.suptitle(f"Plan preview: {len(plan.joints_deg)} postures in visiting order, numbered as their files "
                 f"(postures/NNN.yaml); {notes}", fontsize=11)
    return fig


def write_preview(path, robot: RobotModel, plan: PosturePlan):
    """Write :func:`plan_preview_png` to ``path`` atomically; returns the path."""
    from ...base import write_bytes_atomic

    return write_bytes_atomic(path, plan_preview_png(robot, plan))
