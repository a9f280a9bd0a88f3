"""Postures that saw part of the board (ChArUco views, issue 37): board points by id.

A partial view holds the corners it saw (``Posture.corner_ids``, target indices) and their positions.
:func:`board_arrays` turns a session's postures into the full-board arrays the solvers take: the
board pose of each posture is the rigid (Kabsch) fit of the board model's seen corners to the measured
ones; the corners a view did not see are filled with that fit and flagged in ``seen`` (the ML estimator
weighs them zero, the classic methods use the fitted poses and compact points, which come from the seen
corners only). A view with too few corners, or whose corners span too little of the board to fix its
pose, is refused with the reason (:func:`view_refusal`).
"""

from __future__ import annotations

import numpy as np

from .compact_points import CompactPoints
from ..geometry import transform_from_rotation_translation
from ..geometry import MIN_CORNERS, MIN_SPAN_FRACTION, view_refusal  # where a view is judged (drivers use it)

__all__ = ["MIN_CORNERS", "MIN_SPAN_FRACTION", "view_refusal", "rigid_fit", "board_arrays", "compact_points_from_fit"]

def rigid_fit(model, measured) -> np.ndarray:
    """``target2cam`` ``(4, 4)``: the least-squares rigid motion of ``model`` ``(k, 3)`` onto ``measured`` ``(k, 3)``."""
    a, b = np.asarray(model, float), np.asarray(measured, float)
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return transform_from_rotation_translation(rotation, cb - rotation @ ca)


def board_arrays(postures, board, square_mm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Full-board points, the seen mask and the fitted poses of postures, some of them partial.

    Parameters
    ----------
    postures : sequence of Posture
        Each with ``points_mm``; ``corner_ids`` for a partial view (None: every corner, index order).
    board : BoardGeometry
    square_mm : float

    Returns
    -------
    points : ndarray, shape (n, m, 3)
        Measured corners; the unseen ones from the seen subset's rigid fit.
    seen : ndarray of bool, shape (n, m)
    target2cam : ndarray, shape (n, 4, 4)

    Raises
    ------
    ValueError
        One line naming the posture: an id beyond the board, too few corners, too small a span.
    """
    model = board.grid(square_mm)
    m = len(model)
    points, seen, poses = [], [], []
    for p in postures:
        pts = np.asarray(p.points_mm, float)
        ids = np.arange(m) if p.corner_ids is None else np.asarray(p.corner_ids, int)
        if p.corner_ids is None and len(pts) != m:
            raise ValueError(f"posture {p.index} has {len(pts)} corners but no corner_ids; the board has {m}")
        if len(ids) and ids.max() >= m:
            raise ValueError(f"posture {p.index}: corner id {int(ids.max())} is beyond the board's {m} corners")
        why = view_refusal(ids, board)
        if why:
            raise ValueError(f"posture {p.index}: {why}")
        pose = rigid_fit(model[ids], pts)
        full = model @ pose[:3, :3].T + pose[:3, 3]
        full[ids] = pts
        mask = np.zeros(m, bool)
        mask[ids] = True
        points.append(full)
        seen.append(mask)
        poses.append(pose)
    return np.array(points), np.array(seen), np.array(poses)


def compact_points_from_fit(points, seen, target2cam, board, square_mm: float) -> CompactPoints:
    """Compact points (paper section 3.1) of fitted board poses: the centre of the corner grid's bounding
    box and points half its length along x and y, in the camera frame; ``plane_rms_mm`` of the seen corners."""
    model = board.grid(square_mm)
    lo, hi = model.min(axis=0), model.max(axis=0)
    centre = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    target_points = np.array([centre, centre + [half[0], 0, 0], centre + [0, half[1], 0]])
    poses = np.asarray(target2cam, float)
    compact = np.einsum("nij,pj->npi", poses[:, :3, :3], target_points) + poses[:, None, :3, 3]
    rms = []
    for pts, mask, pose in zip(points, seen, poses):
        offsets = (pts[mask] - pose[:3, 3]) @ pose[:3, 2]  # distance from the fitted board plane
        rms.append(float(np.sqrt(np.mean(offsets**2))))
    return CompactPoints(compact, target_points, poses, np.array(rms), float(square_mm))
