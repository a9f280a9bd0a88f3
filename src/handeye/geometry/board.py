"""The checkerboard as the package describes it: its inner-corner grid, its square size, its corners.

Corners in the target frame of the conventions: the first inner corner at the origin, x along the
long side (``corners[0]`` corners), y along the short side, the board in ``z = 0``; corner index
``row * nx + col``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .station_board import STATION_CORNERS, STATION_SQUARE_MM

__all__ = ["STATION_BOARD", "BoardGeometry", "board_corners"]


@dataclass(frozen=True)
class BoardGeometry:
    """A checkerboard's inner-corner grid.

    Attributes
    ----------
    corners : tuple of int
        Inner corners along x (the long side, ``corners[0]``) and along y.
    square_mm : float or None
        Square size; ``None`` when unknown (the size is then measured from the points).
    """

    corners: tuple[int, int]
    square_mm: float | None = None

    @property
    def count(self) -> int:
        return int(self.corners[0] * self.corners[1])

    def grid(self, square_mm: float | None = None) -> np.ndarray:
        """Corner coordinates in the target frame, shape ``(count, 3)``, index ``row * nx + col``."""
        return board_corners(self.corners, square_mm if square_mm is not None else (self.square_mm or 1.0))


#: The station's checkerboard, the one default of every board setting: 13 x 8 inner corners (14 x 9
#: squares) of 30 mm.
STATION_BOARD = BoardGeometry(STATION_CORNERS, STATION_SQUARE_MM)


def board_corners(corners: Sequence[int], square_mm: float) -> np.ndarray:
    """Inner corners of a ``corners[0] x corners[1]`` board in the target frame, ``(nx*ny, 3)``."""
    nx, ny = int(corners[0]), int(corners[1])
    col, row = np.meshgrid(np.arange(nx), np.arange(ny))
    return np.stack([col.ravel() * square_mm, row.ravel() * square_mm, np.zeros(nx * ny)], axis=1)
