"""Where the board has been in the images, how it was tilted, what to do next, and a map of it.

A stereo calibration is only as good as the views are spread: lens distortion is pinned down by
corners near the image borders, the focal length and the principal point by tilted boards. The
coverage is kept per image on a 3 x 3 grid of cells (top/middle/bottom x left/centre/right) and per
tilt class of the board (facing the camera, or one of its edges nearer by :data:`MIN_TILT_DEG` or
more). :meth:`Coverage.next_hint` turns what is missing into one line for the operator, e.g.
"hold the board in the top-left of the left image, its right edge nearer (about 30 deg)";
:func:`coverage_map` draws both images' cells, board outlines and corners into one picture.

Tilt classes from the board pose ``target2cam`` (z of the target frame points into the board, away
from the camera): ``n = R[:, 2]``; the tilt is ``acos(n_z)``; ``n_x > 0`` means the board's right
edge is nearer (depth falls to the right: ``dZ/dX = -n_x / n_z``), ``n_y > 0`` its bottom edge.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dataclasses import dataclass, field

import cv2
import numpy as np

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["CELL_NAMES", "TILT_CLASSES", "Hint", "Coverage", "tilt_class", "coverage_map"]

ROWS, COLS = 3, 3
CELL_NAMES = (("top-left", "top-centre", "top-right"),
              ("middle-left", "centre", "middle-right"),
              ("bottom-left", "bottom-centre", "bottom-right"))
TILT_CLASSES = ("facing", "right edge nearer", "left edge nearer", "top edge nearer", "bottom edge nearer")
#: A board tilted less than this faces the camera; one tilted at least MIN_TILT_DEG counts for its class.
FACING_DEG = 15.0
MIN_TILT_DEG = 20.0
#: A view covers a cell when at least this many of its corners fall in it.
MIN_CORNERS_IN_CELL = 3


def tilt_class(target2cam: npt.ArrayLike) -> tuple[str | None, float]:
    """``(class, tilt_deg)`` of a board pose; the class is ``None`` between facing and tilted."""
    n = np.asarray(target2cam, float)[:3, 2]
    tilt = float(np.degrees(np.arccos(np.clip(n[2], -1.0, 1.0))))
    if tilt < FACING_DEG:
        return "facing", tilt
    if tilt < MIN_TILT_DEG:
        return None, tilt
    if abs(n[0]) >= abs(n[1]):
        return ("right edge nearer" if n[0] > 0 else "left edge nearer"), tilt
    return ("bottom edge nearer" if n[1] > 0 else "top edge nearer"), tilt


@dataclass(frozen=True)
class Hint:
    """What the operator should do next.

    Attributes
    ----------
    side : str or None
        ``"left"`` or ``"right"``: the image whose cell is empty (``None`` when only a tilt is missing).
    cell : tuple of int or None
        ``(row, col)`` of the empty cell.
    tilt : str or None
        A class of :data:`TILT_CLASSES` still missing.
    text : str
        The line to show.
    """

    side: str | None
    cell: tuple | None
    tilt: str | None
    text: str


@dataclass
class Coverage:
    """Counts of views per image cell and per tilt class.

    Attributes
    ----------
    image_size : (width, height)
    left, right : ndarray, shape (3, 3), int
        Views covering each cell of the left/right image.
    tilts : dict
        Views per tilt class.
    outlines : list of (side, corners, used)
        Every view's corners per image, for :func:`coverage_map`.
    """

    image_size: tuple
    left: np.ndarray = field(default_factory=lambda: np.zeros((ROWS, COLS), int))
    right: np.ndarray = field(default_factory=lambda: np.zeros((ROWS, COLS), int))
    tilts: dict = field(default_factory=lambda: {t: 0 for t in TILT_CLASSES})
    outlines: list = field(default_factory=list)

    def cells_of(self, corners: npt.ArrayLike) -> np.ndarray:
        """Boolean ``(3, 3)``: the cells holding at least :data:`MIN_CORNERS_IN_CELL` of ``corners``."""
        w, h = self.image_size
        pts = np.asarray(corners, float).reshape(-1, 2)
        col = np.clip((pts[:, 0] / w * COLS).astype(int), 0, COLS - 1)
        row = np.clip((pts[:, 1] / h * ROWS).astype(int), 0, ROWS - 1)
        counts = np.zeros((ROWS, COLS), int)
        np.add.at(counts, (row, col), 1)
        return counts >= MIN_CORNERS_IN_CELL

    def add(self, left: npt.ArrayLike | None = None, right: npt.ArrayLike | None = None, target2cam: npt.ArrayLike | None = None, used: bool = True) -> None:
        """Count one view: its corners in the left and/or right image and the board pose (camera frame)."""
        for side, corners in (("left", left), ("right", right)):
            if corners is None:
                continue
            self.outlines.append((side, np.asarray(corners, float).reshape(-1, 2), used))
            if used:
                getattr(self, side)[self.cells_of(corners)] += 1
        if used and target2cam is not None:
            kind, _ = tilt_class(target2cam)
            if kind is not None:
                self.tilts[kind] += 1

    def missing_cells(self, side: str) -> list[tuple[int, int]]:
        counts = getattr(self, side)
        return [(r, c) for r in range(ROWS) for c in range(COLS) if counts[r, c] == 0]

    def missing_tilts(self) -> list[str]:
        return [t for t in TILT_CLASSES if self.tilts[t] == 0]

    @property
    def complete(self) -> bool:
        """Every cell of both images and every tilt class has at least one view."""
        return not (self.missing_cells("left") or self.missing_cells("right") or self.missing_tilts())

    def next_hint(self) -> Hint | None:
        """The next place and tilt to hold the board, or ``None`` when the coverage is complete.

        Empty cells of the left image come first (reading order, centre last), then the right image's,
        combined with the first tilt class still missing.
        """
        order = sorted(((r, c) for r in range(ROWS) for c in range(COLS)), key=lambda rc: (rc == (1, 1), rc))
        tilts = self.missing_tilts()
        tilt = tilts[0] if tilts else None
        for side in ("left", "right"):
            empty = set(self.missing_cells(side))
            for cell in order:
                if cell in empty:
                    text = f"hold the board in the {CELL_NAMES[cell[0]][cell[1]]} of the {side} image"
                    if tilt:
                        text += ", " + _tilt_words(tilt)
                    return Hint(side, cell, tilt, text)
        if tilt:
            return Hint(None, None, tilt, "hold the board where both cameras see it, " + _tilt_words(tilt))
        return None

    def summary(self) -> str:
        """One line: covered cells per image and tilt classes seen."""
        n = ROWS * COLS
        seen = sum(1 for t in TILT_CLASSES if self.tilts[t])
        return (f"cells covered: left {n - len(self.missing_cells('left'))}/{n}, right "
                f"{n - len(self.missing_cells('right'))}/{n}; tilts {seen}/{len(TILT_CLASSES)}")

    def to_json(self) -> dict:
        return {"cells": [list(r) for r in CELL_NAMES], "left": self.left.tolist(), "right": self.right.tolist(),
                "tilts": dict(self.tilts), "missing_left": [CELL_NAMES[r][c] for r, c in self.missing_cells("left")],
                "missing_right": [CELL_NAMES[r][c] for r, c in self.missing_cells("right")],
                "missing_tilts": self.missing_tilts(), "complete": self.complete}


def _tilt_words(tilt: str) -> str:
    if tilt == "facing":
        return "facing the cameras squarely"
    return f"its {tilt.replace(' nearer', '')} nearer the cameras (turned about 30 deg)"


def coverage_map(coverage: Coverage, title: str = "", width: int = 640) -> np.ndarray:
    """A picture (BGR, uint8) of both images' coverage side by side.

    Each panel shows the 3 x 3 cells shaded by how many views cover them (empty cells red), every
    view's board outline (green: used, red: left out) and its corners, the count per cell, and a
    caption with the tilt classes; ``title`` goes on top.
    """
    w, h = coverage.image_size
    scale = width / w
    ph = int(round(h * scale))
    top = 28
    canvas = np.full((top + ph + 40, 2 * width + 10, 3), 32, np.uint8)
    for k, side in enumerate(("left", "right")):
        x_off = k * (width + 10)
        panel = np.full((ph, width, 3), 48, np.uint8)
        counts = getattr(coverage, side)
        for r in range(ROWS):
            for c in range(COLS):
                x0, x1 = int(c * width / COLS), int((c + 1) * width / COLS)
                y0, y1 = int(r * ph / ROWS), int((r + 1) * ph / ROWS)
                n = int(counts[r, c])
                colour = (40, 40, 110) if n == 0 else (40 + min(n, 8) * 12, 70 + min(n, 8) * 10, 40)
                cv2.rectangle(panel, (x0, y0), (x1 - 1, y1 - 1), colour, -1)
                cv2.rectangle(panel, (x0, y0), (x1 - 1, y1 - 1), (90, 90, 90), 1)
                cv2.putText(panel, str(n), (x0 + 6, y0 + 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (230, 230, 230), 1,
                            cv2.LINE_AA)
        overlay = panel.copy()
        for s, corners, used in coverage.outlines:
            if s != side:
                continue
            pts = (corners * scale).astype(np.int32)
            hull = cv2.convexHull(pts)
            cv2.polylines(overlay, [hull], True, (80, 220, 80) if used else (60, 60, 230), 1, cv2.LINE_AA)
            for p in pts[:: max(1, len(pts) // 40)]:
                cv2.circle(overlay, (int(p[0]), int(p[1])), 1, (200, 255, 200) if used else (120, 120, 255), -1)
        panel = cv2.addWeighted(overlay, 0.8, panel, 0.2, 0)
        canvas[top:top + ph, x_off:x_off + width] = panel
        cv2.putText(canvas, f"{side} image", (x_off + 4, top + ph + 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                    (220, 220, 220), 1, cv2.LINE_AA)
    tilts = ", ".join(f"{t}: {n}" for t, n in coverage.tilts.items())
    cv2.putText(canvas, f"tilts - {tilts}", (4, top + ph + 34), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (200, 200, 200), 1,
                cv2.LINE_AA)
    if title:
        cv2.putText(canvas, title[:140], (4, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (240, 240, 240), 1, cv2.LINE_AA)
    return canvas
