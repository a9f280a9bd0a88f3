"""Compact sensed points (paper section 3.1, Algorithm 1 step 1).

The corners measured at one posture are reduced to three points on the fitted board plane: the
centre (mean of all corners), one point along the board's x axis (the long side) and one along its
y axis (the short side). The plane is the least-squares plane of the corners; the in-plane
directions come from regressing the corners on their grid coordinates, so every corner contributes.
The same fit gives the board pose ``target2cam`` in the target frame of the conventions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import STATION_BOARD, BoardGeometry, board_corners
from ..geometry import transform_from_rotation_translation

__all__ = ["STATION_BOARD", "BoardGeometry", "CompactPoints", "board_corners", "compact_points_from_corners", "compact_points_from_poses"]


@dataclass(frozen=True)
class CompactPoints:
    """Compact points and board poses for a batch of postures.

    Attributes
    ----------
    points : ndarray, shape (n, 3, 3)
        Per posture: centre, point along x, point along y, in the camera frame (mm).
    target_points : ndarray, shape (3, 3)
        The same three points in the target frame (mm).
    target2cam : ndarray, shape (n, 4, 4)
        Board pose per posture, target frame of the conventions.
    plane_rms_mm : ndarray, shape (n,)
        RMS distance of the corners from their fitted plane (zero when built from poses).
    square_mm : float or None
        The square size used (given, or measured from the corners); ``None`` for poses.
    """

    points: np.ndarray
    target_points: np.ndarray
    target2cam: np.ndarray
    plane_rms_mm: np.ndarray
    square_mm: float | None = None


def compact_points_from_corners(corners_cam: ArrayLike, board: BoardGeometry) -> CompactPoints:
    """Fit the board plane and pose to measured corners and return the compact points.

    Parameters
    ----------
    corners_cam : array-like, shape (n, m, 3)
        Corners in the camera frame (mm), ``m = board.count``, index ``row * nx + col``.
    board : BoardGeometry

    Returns
    -------
    CompactPoints
    """
    pts = np.asarray(corners_cam, dtype=float)
    nx, ny = board.corners
    unit_grid = board_corners(board.corners, 1.0)[:, :2]
    g = unit_grid - unit_grid.mean(axis=0)
    centre = pts.mean(axis=1)  # P_0: the mean of all corners lies on the least-squares plane
    centred = pts - centre[:, None, :]
    # Plane normal: the right singular vector of the smallest singular value.
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    normal = vt[:, 2, :]
    plane_rms = s[:, 2] / np.sqrt(pts.shape[1])
    # In-plane directions: least squares  corner - centre = gx * ex + gy * ey  (ex, ey per square).
    coeffs = np.linalg.lstsq(g, centred.transpose(1, 0, 2).reshape(len(g), -1), rcond=None)[0]
    ex, ey = coeffs.reshape(2, -1, 3)
    normal = np.where((np.einsum("ni,ni->n", np.cross(ex, ey), normal) < 0)[:, None], -normal, normal)
    x_hat = ex - np.einsum("ni,ni->n", ex, normal)[:, None] * normal
    x_hat /= np.linalg.norm(x_hat, axis=1, keepdims=True)
    y_hat = np.cross(normal, x_hat)
    if board.square_mm is not None:
        square = float(board.square_mm)
    else:
        square = float(np.median(0.5 * (np.linalg.norm(ex, axis=1) + np.linalg.norm(ey, axis=1))))
    half_x = 0.5 * (nx - 1) * square
    half_y = 0.5 * (ny - 1) * square
    points = np.stack([centre, centre + half_x * x_hat, centre + half_y * y_hat], axis=1)
    rotation = np.stack([x_hat, y_hat, normal], axis=2)  # columns: target axes in the camera frame
    grid_centre = np.array([half_x, half_y, 0.0])
    origin = centre - np.einsum("nij,j->ni", rotation, grid_centre)
    target_points = np.array([grid_centre, grid_centre + [half_x, 0, 0], grid_centre + [0, half_y, 0]])
    return CompactPoints(points, target_points, transform_from_rotation_translation(rotation, origin), plane_rms, square)


def compact_points_from_poses(target2cam: ArrayLike, length_mm: float = 100.0) -> CompactPoints:
    """Compact points of sessions that hold board poses only: origin, (L, 0, 0) and (0, L, 0).

    Parameters
    ----------
    target2cam : array-like, shape (n, 4, 4)
    length_mm : float
        ``L``: the target's size, or 100 mm when unknown (conventions).
    """
    poses = np.asarray(target2cam, dtype=float)
    target_points = np.array([[0.0, 0.0, 0.0], [length_mm, 0.0, 0.0], [0.0, length_mm, 0.0]])
    points = np.einsum("nij,pj->npi", poses[:, :3, :3], target_points) + poses[:, None, :3, 3]
    return CompactPoints(points, target_points, poses, np.zeros(len(poses)))
