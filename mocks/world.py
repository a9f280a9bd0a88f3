"""The simulated world of the mock camera: the printed board and where things are.

Frames as in conventions.md: ``target2cam`` maps board coordinates (mm, target frame: origin at
the first inner corner, z into the board) to the camera frame (camera 1 = left; x right, y down,
z forward). Helpers here place a camera so that it looks at the board the way the station does
(0.7-1.2 m away, tilted and rolled) and check that the whole printed sheet is in view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..calibration.compact_points import BoardGeometry

__all__ = ["PrintedBoard", "look_at", "board_view", "sample_board_views", "sheet_in_view"]


@dataclass(frozen=True)
class PrintedBoard:
    """A printed checkerboard sheet.

    Attributes
    ----------
    geometry : BoardGeometry
        Inner corners ``(nx, ny)`` and square size (mm).
    margin_mm : float
        White paper around the outer squares.
    """

    geometry: BoardGeometry = BoardGeometry((13, 8), 30.0)
    margin_mm: float = 30.0

    @property
    def square_mm(self) -> float:
        return float(self.geometry.square_mm)

    @property
    def corners(self) -> tuple[int, int]:
        return self.geometry.corners

    def checker_bounds(self) -> tuple[float, float, float, float]:
        """``(u_min, u_max, v_min, v_max)`` of the squares (target frame, mm)."""
        nx, ny = self.corners
        s = self.square_mm
        return -s, nx * s, -s, ny * s

    def sheet_bounds(self) -> tuple[float, float, float, float]:
        """``(u_min, u_max, v_min, v_max)`` of the paper (squares plus margin)."""
        u0, u1, v0, v1 = self.checker_bounds()
        m = self.margin_mm
        return u0 - m, u1 + m, v0 - m, v1 + m

    def centre(self) -> np.ndarray:
        """Centre of the corner grid in the target frame."""
        nx, ny = self.corners
        return np.array([(nx - 1) * self.square_mm / 2, (ny - 1) * self.square_mm / 2, 0.0])

    def outline(self, per_edge: int = 16) -> np.ndarray:
        """Points along the sheet's edge, ``(4 * per_edge, 3)`` in the target frame."""
        u0, u1, v0, v1 = self.sheet_bounds()
        t = np.linspace(0, 1, per_edge, endpoint=False)
        edges = [np.c_[u0 + (u1 - u0) * t, np.full_like(t, v0)], np.c_[np.full_like(t, u1), v0 + (v1 - v0) * t],
                 np.c_[u1 - (u1 - u0) * t, np.full_like(t, v1)], np.c_[np.full_like(t, u0), v1 - (v1 - v0) * t]]
        pts = np.concatenate(edges)
        return np.c_[pts, np.zeros(len(pts))]


def look_at(eye, target, up=(0.0, -1.0, 0.0)) -> np.ndarray:
    """``cam2world`` of a camera at ``eye`` whose optical axis (z) points at ``target``; image y as close
    to ``-up`` as possible (image y points down)."""
    eye = np.asarray(eye, float)
    z = np.asarray(target, float) - eye
    z /= np.linalg.norm(z)
    y = -np.asarray(up, float)
    y = y - (y @ z) * z
    if np.linalg.norm(y) < 1e-9:
        y = np.array([0.0, 1.0, 0.0]) - z[1] * z
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, y, z])
    out[:3, 3] = eye
    return out


def board_view(distance_mm: float, tilt_deg: float = 0.0, tilt_azimuth_deg: float = 0.0, roll_deg: float = 0.0,
               board: PrintedBoard = PrintedBoard(), offset_px=(0.0, 0.0), f_px: float = 983.0) -> np.ndarray:
    """``target2cam`` of a camera looking at the board centre from ``distance_mm``.

    The viewing direction is tilted by ``tilt_deg`` from the board normal (towards azimuth
    ``tilt_azimuth_deg`` in the board plane), the camera is rolled by ``roll_deg`` about its axis and
    the board centre is moved by ``offset_px`` in the image.
    """
    centre = board.centre()
    az, tilt = np.radians(tilt_azimuth_deg), np.radians(tilt_deg)
    # Camera on the printed side: the board's z points into the board, so the camera sits at -z.
    direction = np.array([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), -np.cos(tilt)])
    eye = centre + distance_mm * direction
    cam2target = look_at(eye, centre, up=(0.0, -1.0, 0.0))
    roll = Rotation.from_rotvec([0, 0, np.radians(roll_deg)]).as_matrix()
    cam2target[:3, :3] = cam2target[:3, :3] @ roll
    # Shift the aim so the board centre lands offset_px from the image centre.
    shift = np.array([offset_px[0], offset_px[1], 0.0]) * distance_mm / f_px
    cam2target[:3, 3] -= cam2target[:3, :3] @ shift
    return np.linalg.inv(cam2target)


def sheet_in_view(target2cam: np.ndarray, model, board: PrintedBoard = PrintedBoard(), views=("left", "right"),
                  border_px: float = 4.0) -> bool:
    """Whether the whole sheet (with margin) lies inside every image of ``views``, in front of the camera."""
    outline = board.outline()
    pts = outline @ target2cam[:3, :3].T + target2cam[:3, 3]
    w, h = model.image_size
    for view in views:
        _, _, r, t = model.view(view)
        if np.any((pts @ r.T + t)[:, 2] <= 1.0):
            return False
        px = model.project(pts, view)
        if (px[:, 0].min() < border_px or px[:, 1].min() < border_px
                or px[:, 0].max() > w - 1 - border_px or px[:, 1].max() > h - 1 - border_px):
            return False
    return True


def sample_board_views(n: int, model, board: PrintedBoard = PrintedBoard(), *, distance_mm=(700.0, 1200.0),
                       tilt_deg=(0.0, 40.0), roll_deg=45.0, offset_px=80.0, seed=None,
                       views=("left", "right", "centre"), max_tries: int = 10000) -> list[np.ndarray]:
    """``n`` random board poses ``target2cam`` with the whole sheet in view of every camera.

    Distances uniform in ``distance_mm``, tilt uniform in ``tilt_deg`` at a uniform azimuth, roll
    uniform in ``[-roll_deg, roll_deg]`` plus a half turn half of the time (so the board appears
    upside down as often as not), board centre moved up to ``offset_px`` from the image centre of
    the left camera shifted half a baseline (the head's middle).
    """
    rng = np.random.default_rng(seed)
    out = []
    f = float(model.K1[0, 0])
    for _ in range(max_tries):
        if len(out) == n:
            break
        roll = rng.uniform(-roll_deg, roll_deg) + (180.0 if rng.random() < 0.5 else 0.0)
        dist = rng.uniform(*distance_mm)
        # Aim at the head's middle (x = +B/2 in the left camera): half the disparity to the right.
        half_disp = 0.5 * model.baseline_mm * f / dist
        off = rng.uniform(-offset_px, offset_px, 2) + np.array([half_disp, 0.0])
        pose = board_view(dist, rng.uniform(*tilt_deg), rng.uniform(0, 360), roll, board, off, f)
        if sheet_in_view(pose, model, board, views):
            out.append(pose)
    if len(out) < n:
        raise RuntimeError(f"only {len(out)} of {n} board views fit in the images; relax the ranges")
    return out
