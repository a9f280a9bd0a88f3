"""The simulated world of the mock camera: the printed board and where things are.

Frames as in conventions.md: ``target2cam`` maps board coordinates (mm, target frame: origin at
the first inner corner, z into the board) to the camera frame (camera 1 = left; x right, y down,
z forward). Helpers here place a camera so that it looks at the board the way the station does
(0.7-1.2 m away, tilted and rolled) and check that the whole printed sheet is in view.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from ..geometry import STATION_BOARD, BoardGeometry
from ..robot import look_at

if TYPE_CHECKING:
    from ..drivers import StereoModel
    from .camera import MockCamera

__all__ = ["PrintedBoard", "Lighting", "BoardOperator", "look_at", "board_view", "sample_board_views", "sheet_in_view",
           "hard_lighting"]


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

    geometry: BoardGeometry = STATION_BOARD
    margin_mm: float = 30.0

    @property
    def square_mm(self) -> float:
        if self.geometry.square_mm is None:
            raise ValueError("a printed board needs its square size (geometry.square_mm)")
        return float(self.geometry.square_mm)

    @property
    def corners(self) -> tuple[int, int]:
        return self.geometry.corners

    def checker_bounds(self) -> tuple[float, float, float, float]:
        """``(u_min, u_max, v_min, v_max)`` of the squares (target frame, mm)."""
        nx, ny = self.corners
        s = self.square_mm
        if getattr(self.geometry, "kind", "") == "circles":  # the circles' extent and a spacing around it
            hi = self.geometry.grid().max(axis=0)
            return -s / 2, hi[0] + s / 2, -s / 2, hi[1] + s / 2
        return -s, nx * s, -s, ny * s

    def sheet_bounds(self) -> tuple[float, float, float, float]:
        """``(u_min, u_max, v_min, v_max)`` of the paper (squares plus margin)."""
        u0, u1, v0, v1 = self.checker_bounds()
        m = self.margin_mm
        return u0 - m, u1 + m, v0 - m, v1 + m

    def centre(self) -> np.ndarray:
        """Centre of the corner grid in the target frame."""
        if getattr(self.geometry, "kind", "") == "circles":
            grid = self.geometry.grid()
            return 0.5 * (grid.min(axis=0) + grid.max(axis=0))
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


@dataclass(frozen=True)
class Lighting:
    """How the sheet is lit, the way a real cell is (uneven, with glare and shadows).

    Effects on the sheet are given in board coordinates (target frame, mm), so both cameras see them
    at the same place on the board; vignetting is an effect of the lens, in image coordinates.

    Attributes
    ----------
    gradient : float
        Fractional fall of the light across the sheet along ``gradient_deg`` (0.5: the far side gets half).
    gradient_deg : float
        Direction of the fall in the board plane (0 = along the board's x).
    glare_uv_mm : tuple of float or None
        Centre ``(u, v)`` of a specular glare spot on the sheet (mm, target frame).
    glare_radius_mm : float
        Gaussian radius (sigma) of the glare spot.
    glare_dn : float
        Grey levels added at the spot's centre (saturates the sensor when large).
    shadow_line : tuple of float or None
        ``(u, v, angle_deg)``: a point on the shadow's edge and the edge's direction; the sheet to the
        left of the edge (seen along the direction, x right and y down in the board) is in shadow.
    shadow_depth : float
        Fraction of the light left in the shadow.
    shadow_soft_mm : float
        Width of the shadow's soft edge (penumbra).
    vignetting : float
        Fraction of the light lost at the image corners (cos^4-like fall, image coordinates).
    """

    gradient: float = 0.0
    gradient_deg: float = 0.0
    glare_uv_mm: tuple | None = None
    glare_radius_mm: float = 40.0
    glare_dn: float = 0.0
    shadow_line: tuple | None = None
    shadow_depth: float = 0.5
    shadow_soft_mm: float = 10.0
    vignetting: float = 0.0

    @property
    def is_even(self) -> bool:
        """No effect at all (the renderer then skips the light computation)."""
        return (self.gradient == 0 and (self.glare_uv_mm is None or self.glare_dn == 0)
                and self.shadow_line is None and self.vignetting == 0)

    def on_board(self, u: np.ndarray, v: np.ndarray, board: PrintedBoard) -> tuple[np.ndarray, np.ndarray]:
        """``(gain, added)`` of the light at board coordinates ``(u, v)`` (arrays of mm, same shape)."""
        gain = np.ones(np.shape(u), np.float32)
        added = np.zeros(np.shape(u), np.float32)
        if self.gradient:
            su0, su1, sv0, sv1 = board.sheet_bounds()
            a = np.radians(self.gradient_deg)
            direction = np.array([np.cos(a), np.sin(a)])
            corners = np.array([[su0, sv0], [su1, sv0], [su0, sv1], [su1, sv1]]) @ direction
            lo, hi = corners.min(), corners.max()
            along = ((u * direction[0] + v * direction[1]) - lo) / max(hi - lo, 1e-9)
            gain *= (1.0 - self.gradient * np.clip(along, 0, 1)).astype(np.float32)
        if self.shadow_line is not None:
            u0, v0, angle = self.shadow_line
            a = np.radians(angle)
            # signed distance to the edge, positive on its left (normal (sin, -cos) of the direction)
            side = (u - u0) * np.sin(a) - (v - v0) * np.cos(a)
            t = np.clip(0.5 + side / max(self.shadow_soft_mm, 1e-6), 0.0, 1.0)
            gain *= (1.0 - (1.0 - self.shadow_depth) * t).astype(np.float32)
        if self.glare_uv_mm is not None and self.glare_dn:
            gu, gv = self.glare_uv_mm
            r2 = ((u - gu) ** 2 + (v - gv) ** 2) / (2.0 * self.glare_radius_mm**2)
            added += (self.glare_dn * np.exp(-r2)).astype(np.float32)
        return gain, added

    def in_image(self, width: int, height: int) -> np.ndarray:
        """Vignetting gain ``(h, w)`` float32 (1 at the centre)."""
        if not self.vignetting:
            return np.ones((height, width), np.float32)
        y, x = np.mgrid[0:height, 0:width].astype(np.float32)
        r2 = ((x - (width - 1) / 2) ** 2 + (y - (height - 1) / 2) ** 2) / (((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2)
        return (1.0 - self.vignetting * r2 ** 2).astype(np.float32)


def hard_lighting(rng: np.random.Generator, board: PrintedBoard | None = None) -> Lighting:
    """Random uneven lighting of a real cell: a gradient across the sheet and vignetting always, a glare
    spot on the squares a third of the time and a shadow across part of them a third of the time."""
    board = board or PrintedBoard()
    cu0, cu1, cv0, cv1 = board.checker_bounds()
    glare = shadow = None
    if rng.random() < 1 / 3:
        glare = (float(rng.uniform(cu0, cu1)), float(rng.uniform(cv0, cv1)))
    if rng.random() < 1 / 3:
        shadow = (float(rng.uniform(cu0, cu1)), float(rng.uniform(cv0, cv1)), float(rng.uniform(0, 360)))
    return Lighting(gradient=float(rng.uniform(0.2, 0.5)), gradient_deg=float(rng.uniform(0, 360)),
                    glare_uv_mm=glare, glare_radius_mm=float(rng.uniform(15, 40)), glare_dn=float(rng.uniform(60, 160)),
                    shadow_line=shadow, shadow_depth=float(rng.uniform(0.45, 0.7)),
                    shadow_soft_mm=float(rng.uniform(3, 30)), vignetting=float(rng.uniform(0.2, 0.45)))


def board_view(distance_mm: float, tilt_deg: float = 0.0, tilt_azimuth_deg: float = 0.0, roll_deg: float = 0.0,
               board: PrintedBoard = PrintedBoard(), offset_px: npt.ArrayLike = (0.0, 0.0),
               f_px: float = 983.0) -> np.ndarray:
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
    cam2target = look_at(eye, centre, 0.0, up=(0.0, -1.0, 0.0))  # image y as close to +y (board frame) as can be
    roll = Rotation.from_rotvec([0, 0, np.radians(roll_deg)]).as_matrix()
    cam2target[:3, :3] = cam2target[:3, :3] @ roll
    # Shift the aim so the board centre lands offset_px from the image centre.
    offset = np.asarray(offset_px, float)
    shift = np.array([offset[0], offset[1], 0.0]) * distance_mm / f_px
    cam2target[:3, 3] -= cam2target[:3, :3] @ shift
    return np.linalg.inv(cam2target)


def sheet_in_view(target2cam: np.ndarray, model: StereoModel, board: PrintedBoard = PrintedBoard(),
                  views: Sequence[str] = ("left", "right"), border_px: float = 4.0) -> bool:
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


def sample_board_views(n: int, model: StereoModel, board: PrintedBoard = PrintedBoard(), *,
                       distance_mm: tuple[float, float] = (700.0, 1200.0), tilt_deg: tuple[float, float] = (0.0, 40.0),
                       roll_deg: float = 45.0, offset_px: float = 80.0, seed: int | None = None,
                       views: Sequence[str] = ("left", "right", "centre"), border_px: float = 4.0,
                       max_tries: int = 10000) -> list[np.ndarray]:
    """``n`` random board poses ``target2cam`` with the whole sheet in view of every camera.

    Distances uniform in ``distance_mm``, tilt uniform in ``tilt_deg`` at a uniform azimuth, roll
    uniform in ``[-roll_deg, roll_deg]`` plus a half turn half of the time (so the board appears
    upside down as often as not), board centre moved up to ``offset_px`` from the image centre of
    the left camera shifted half a baseline (the head's middle). ``border_px`` is the smallest gap
    between the sheet and the image edge (small gaps with a large ``offset_px`` put boards near the edge).
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
        if sheet_in_view(pose, model, board, views, border_px):
            out.append(pose)
    if len(out) < n:
        raise RuntimeError(f"only {len(out)} of {n} board views fit in the images; relax the ranges")
    return out


class BoardOperator:
    """A simulated operator who holds the board where a guided capture asks (the mock camera's scene).

    :meth:`follow` takes a hint of the stereo calibration's guided loop (an object with ``side``,
    ``cell`` = ``(row, col)`` of a 3 x 3 grid, and ``tilt``, a tilt class of
    :func:`handeye.drivers.camera.coverage.tilt_class`) and returns a board pose ``target2cam`` that
    puts the board's centre in that cell of that image with that tilt, the whole sheet in view of
    both cameras when it can (of that camera alone otherwise); ``None`` hints ask for any new view.

    Parameters
    ----------
    model : StereoModel
    board : PrintedBoard
    distance_mm : (float, float)
        Range of distances to hold the board at.
    seed : int, optional
    """

    def __init__(self, model: StereoModel, board: PrintedBoard = PrintedBoard(),
                 distance_mm: tuple[float, float] = (550.0, 1100.0), seed: int | None = None):
        self.model = model
        self.board = board
        self.distance_mm = distance_mm
        self.rng = np.random.default_rng(seed)

    def _candidate(self, tilt_range) -> np.ndarray:
        w, h = self.model.image_size
        f = float(self.model.K1[0, 0])
        dist = self.rng.uniform(*self.distance_mm)
        roll = self.rng.uniform(-30, 30) + (180.0 if self.rng.random() < 0.5 else 0.0)
        off = (self.rng.uniform(-0.45 * w, 0.45 * w), self.rng.uniform(-0.45 * h, 0.45 * h))
        return board_view(dist, self.rng.uniform(*tilt_range), self.rng.uniform(0, 360), roll, self.board, off, f)

    def pose_for(self, hint: object, tries: int = 4000) -> np.ndarray:
        """A board pose satisfying ``hint`` as well as can be found in ``tries`` random poses."""
        from ..drivers import tilt_class  # the class names of the guided loop

        side = getattr(hint, "side", None)
        cell = getattr(hint, "cell", None)
        tilt = getattr(hint, "tilt", None)
        tilt_range = (0.0, 8.0) if tilt == "facing" else (25.0, 40.0) if tilt else (0.0, 40.0)
        w, h = self.model.image_size
        centre = self.board.centre()
        fallback = None
        for k in range(tries):
            pose = self._candidate(tilt_range)
            if tilt and tilt_class(pose)[0] != tilt:
                continue
            views = ("left", "right") if k < tries // 2 else ((side,) if side else ("left", "right"))
            if not sheet_in_view(pose, self.model, self.board, views, border_px=6.0):
                continue
            if cell is not None and side is not None:
                x, y = self.model.project(pose[:3, :3] @ centre + pose[:3, 3], side)[0]
                if (min(int(3 * y / h), 2), min(int(3 * x / w), 2)) != tuple(cell):
                    fallback = fallback if fallback is not None else pose
                    continue
            return pose
        if fallback is not None:
            return fallback
        return sample_board_views(1, self.model, self.board, seed=int(self.rng.integers(1 << 30)),
                                  views=("left", "right"))[0]

    def follow(self, camera: MockCamera, hint: object) -> np.ndarray:
        """Move the board of a :class:`~handeye.mocks.camera.MockCamera` (camera frame = base frame) as
        ``hint`` asks; returns the pose."""
        pose = self.pose_for(hint)
        camera.set_scene(target2base=pose, cam2base=np.eye(4))
        return pose
