"""Do the robot file's capsules hold the arm? Mesh vertices moved with their links, tested against the capsules.

A vertex of link ``i`` is given in base with every axis at 0; at a posture it is moved by the standard-DH
frame ``i`` of the robot's table (``T_i(q) T_i(0)^-1``, the serial angles of the controller's through the
coupling: the frame the link's mesh is drawn in), and the capsules by :meth:`CellGuard.capsule_segments`
(what every cell and self-collision check uses: the quaternion chain's :meth:`RobotModel.link_frames`). The
vertex must lie inside one of *its link's* capsules (:func:`link_capsules`): those fixed to link ``i``, and
those fixed to an earlier link whose axis lies on every axis between (the upper arm's tube, fixed to link 3
on axis 4, holds link 4's tube: axis 4 turns it into itself). Lengths in mm.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .capsules import point_segment_distance
from .clearance import CellGuard, arm_capsules
from .kinematics import RobotModel, dh_transforms

__all__ = ["link_capsules", "outside_counts"]

_ON_AXIS_MM = 1e-6


def _on_line(point, origin, direction) -> bool:
    offset = np.asarray(point, float) - origin
    return float(np.linalg.norm(offset - (offset @ direction) * direction)) <= _ON_AXIS_MM


def link_capsules(robot: RobotModel) -> list:
    """For each part ``0 .. k``, the indices of :func:`arm_capsules` that move with it at every posture."""
    capsules, pivots = arm_capsules(robot), robot.home_pivots()
    out = []
    for link in range(robot.dof + 1):
        rows = []
        for c, (_, part, start, end, _) in enumerate(capsules):
            between = range(part + 1, link + 1)  # the axes (1-based) that turn link but not the capsule
            if part <= link and all(_on_line(pivots[part] + p, pivots[a], robot.axes[a - 1])
                                    for a in between for p in (start, end)):
                rows.append(c)
        out.append(rows)
    return out


def _dh_frames(robot: RobotModel, joints_deg) -> np.ndarray:
    """Standard-DH frames ``(n, k + 1, 4, 4)`` of the robot's table at controller angles ``(n, k)``."""
    theta = robot.serial_angles_rad(joints_deg) + np.radians(robot.dh[:, 3])
    links = dh_transforms(robot.dh, theta)
    frames = [np.broadcast_to(np.eye(4), links.shape[:1] + (4, 4))]
    for i in range(robot.dof):
        frames.append(frames[-1] @ links[:, i])
    return np.stack(frames, axis=1)


def outside_counts(robot: RobotModel, points_by_link: Sequence[ArrayLike], joints_deg: ArrayLike, chunk: int = 200) -> list:
    """``[(count outside, worst excess mm)]`` per link over the postures ``(n, k)``.

    Parameters
    ----------
    robot : RobotModel
    points_by_link : sequence of array-like, shape (n_i, 3)
        Vertices of link ``i`` in base with every axis at 0, mm (link 0 the base).
    joints_deg : array-like, shape (n, k)
        Controller axis angles.

    Returns
    -------
    list of (int, float)
        Per link: how many (posture, vertex) pairs lie outside all of the link's capsules, and the
        largest distance beyond the nearest capsule's surface (negative: the tightest vertex's depth).
    """
    joints = np.atleast_2d(np.asarray(joints_deg, float))
    guard = CellGuard(robot, [], self_collision=False)
    radii = np.array([c[4] for c in arm_capsules(robot)], float)
    home = _dh_frames(robot, np.zeros((1, robot.dof)))[0]
    members = link_capsules(robot)
    out = []
    for link, points in enumerate(points_by_link):
        local = np.asarray(points, float) @ home[link, :3, :3] + -home[link, :3, 3] @ home[link, :3, :3]  # in frame i
        rows = members[link]
        count, worst = 0, -np.inf
        for start in range(0, len(joints), chunk):
            q = joints[start:start + chunk]
            frames = _dh_frames(robot, q)[:, link]
            moved = np.matmul(local[None], np.swapaxes(frames[:, :3, :3], 1, 2)) + frames[:, None, :3, 3]  # (n, p, 3)
            if not rows:
                count, worst = count + moved.shape[0] * moved.shape[1], np.inf
                continue
            seg = guard.capsule_segments(q)[:, rows]  # (n, c, 2, 3)
            excess = np.min([point_segment_distance(moved, seg[:, None, c, 0], seg[:, None, c, 1]) - radii[row]
                             for c, row in enumerate(rows)], axis=0)  # (n, p)
            count += int(np.sum(excess > 1e-6))
            worst = max(worst, float(excess.max()))
        out.append((count, worst))
    return out
