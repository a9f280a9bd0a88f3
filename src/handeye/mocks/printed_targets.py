"""What the mock camera renders besides the checkerboard (issue 37): ChArUco sheets and occluded views.

ChArUco: OpenCV draws the board (``cv2.aruco.CharucoBoard.generateImage``, markers from its own
dictionaries) at :data:`PX_PER_MM` pixels per mm; the renderer reads that print where a pixel's ray meets
the board plane (its sub-samples on edges too), so the markers and squares are OpenCV's own. OpenCV's
board has its origin at the outer corner of the first square and corner ``(col, row)`` at
``((col + 1) s, (row + 1) s)``; the target frame's origin is corner 0, hence the shift by one square.

Occlusion (``mock: {occlude: {postures: 0.3, band: [0.2, 0.4]}}``): a share of the postures sees a grey
band (a clamp, the probe) across the board covering a drawn 20-40 % of its length, at a drawn place.
Which views are occluded is fixed by the order in which the camera first sees each camera pose: the
first (the start posture) never, then evenly spread (``floor(k p) > floor((k - 1) p)``), so 30 % of 30
postures are exactly 9, and the same posture revisited is occluded the same way.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import cv2
import numpy as np

from ..geometry import BoardGeometry, CharucoBoard, CircleGrid

if TYPE_CHECKING:
    from .world import PrintedBoard

__all__ = ["PX_PER_MM", "Occlusion", "charuco_print", "printed_labels", "circle_labels", "circle_diameter_mm", "occluded",
           "OcclusionPicker"]

#: Resolution of the ChArUco print the renderer samples (pixels per mm).
PX_PER_MM = 8.0
#: Label of the occluding band (0 background, 1 white, 2 black).
OCCLUDER = 3


@dataclass(frozen=True)
class Occlusion:
    """``mock.occlude``: the share of postures partly covered and the band's width range (fractions of the board)."""

    postures: float = 0.3
    band: tuple = (0.2, 0.4)


@functools.lru_cache(maxsize=4)
def _print(geometry, px_per_mm: float) -> np.ndarray:
    from ..drivers import opencv_board

    board = opencv_board(geometry)
    squares, square_mm = geometry.squares, float(geometry.square_mm)
    size = (int(round(squares[0] * square_mm * px_per_mm)), int(round(squares[1] * square_mm * px_per_mm)))
    return board.generateImage(size, marginSize=0, borderBits=1)


def charuco_print(geometry: CharucoBoard, px_per_mm: float = PX_PER_MM) -> np.ndarray:
    """OpenCV's image ``(h, w)`` uint8 of a :class:`~handeye.geometry.targets.CharucoBoard` (squares only)."""
    return _print(geometry, float(px_per_mm))  # the geometry is a frozen dataclass: the cache key


def printed_labels(u: np.ndarray, v: np.ndarray, front: np.ndarray, board: PrintedBoard) -> np.ndarray:
    """Labels (0 background, 1 white, 2 black) of a ChArUco sheet at board coordinates ``(u, v)`` mm."""
    image = charuco_print(cast(CharucoBoard, board.geometry))  # called for a sheet of kind charuco only (camera._labels)
    su0, su1, sv0, sv1 = board.sheet_bounds()
    sq = float(board.square_mm)
    on_sheet = front & (u >= su0) & (u <= su1) & (v >= sv0) & (v <= sv1)
    h, w = image.shape
    col = np.floor((u + sq) * PX_PER_MM).astype(np.int64)
    row = np.floor((v + sq) * PX_PER_MM).astype(np.int64)
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    black = inside & (image[np.clip(row, 0, h - 1), np.clip(col, 0, w - 1)] < 128)
    return on_sheet.astype(np.uint8) + (black & on_sheet).astype(np.uint8)


def circle_diameter_mm(geometry: BoardGeometry) -> float:
    """The printed circles' diameter: the grid's ``diameter_mm``, else half the spacing of a row (OpenCV's
    sample grid: circles a little over a third of their diagonal neighbours' distance)."""
    spacing = _spacing_mm(geometry)
    diameter = geometry.diameter_mm if isinstance(geometry, CircleGrid) else None
    return float(diameter) if diameter else 0.5 * spacing


def _spacing_mm(geometry: BoardGeometry) -> float:
    """The target's ``square_mm`` (a circle grid's spacing); a target without one cannot be printed."""
    if geometry.square_mm is None:
        raise ValueError("the target has no square_mm: give the printed spacing in mm in the board: section")
    return float(geometry.square_mm)


def circle_labels(u: np.ndarray, v: np.ndarray, front: np.ndarray, board: PrintedBoard) -> np.ndarray:
    """Labels (0 background, 1 white, 2 black) of an asymmetric circle grid sheet at board coordinates
    ``(u, v)`` mm: black discs centred on :meth:`~handeye.geometry.targets.CircleGrid.grid`."""
    geometry = board.geometry
    half = 0.5 * _spacing_mm(geometry)  # row pitch; circles of one row are 2 * half apart
    per_row, rows = int(geometry.corners[0]), int(geometry.corners[1])
    radius = 0.5 * circle_diameter_mm(geometry)
    su0, su1, sv0, sv1 = board.sheet_bounds()
    on_sheet = front & (u >= su0) & (u <= su1) & (v >= sv0) & (v <= sv1)
    black = np.zeros(np.broadcast(u, v).shape, bool)
    for offset in (0.0, 1.0):  # the nearest circle lies in the row below or above (v / half floored)
        row = np.clip(np.floor(v / half) + offset, 0, rows - 1)
        col = np.clip(np.round((u / half - row % 2) / 2), 0, per_row - 1)
        du, dv = u - (2 * col + row % 2) * half, v - row * half
        black |= du * du + dv * dv <= radius * radius
    return on_sheet.astype(np.uint8) + (black & on_sheet).astype(np.uint8)


def occluded(labels: np.ndarray, u: np.ndarray, band: tuple[float, float] | None) -> np.ndarray:
    """``labels`` with the band ``(u0, u1)`` (mm along the board's x) covered by the occluder."""
    if band is None:
        return labels
    cover = (u >= band[0]) & (u < band[1]) & (labels > 0)
    return np.where(cover, np.uint8(OCCLUDER), labels).astype(np.uint8)


class OcclusionPicker:
    """Which camera poses see the band, and where (see the module docstring)."""

    def __init__(self, occlusion: Occlusion, board: BoardGeometry, seed: int | Sequence[int] | None):
        self.occlusion = occlusion
        self.board = board
        self.seed = 0 if seed is None else seed
        self._seen: dict = {}

    def band(self, cam2base: np.ndarray) -> tuple[float, float] | None:
        """``(u0, u1)`` mm of the band this camera pose sees, or None."""
        key = tuple(np.round(np.asarray(cam2base, float)[:3, 3], 0).tolist())
        if key not in self._seen:
            k = len(self._seen)
            p = float(self.occlusion.postures)
            hit = k > 0 and np.floor(k * p) > np.floor((k - 1) * p)
            self._seen[key] = self._draw(k) if hit else None
        return self._seen[key]

    def _draw(self, k: int):
        rng = np.random.default_rng([*np.atleast_1d(self.seed).tolist(), 37, k])
        nx, square = int(self.board.corners[0]), self.board.square_mm
        if square is None:
            raise ValueError("an occluded board needs its square size (square_mm)")
        length = (nx + 1) * float(square)  # the squares' extent along x
        width = rng.uniform(*self.occlusion.band) * length
        start = -float(square) + rng.uniform(0.0, length - width)
        return float(start), float(start + width)
