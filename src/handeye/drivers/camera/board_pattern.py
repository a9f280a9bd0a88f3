"""The printed checker pattern of a detected grid: which corner orderings have the target frame's
handedness, which one the pattern picks (the square between corners 0, 1, nx and nx + 1 is BLACK),
its contrast, and whether the squares just outside the grid continue the pattern (a larger board
than asked for). See :mod:`~handeye.drivers.camera.checkerboard` for the canonical order."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["MIN_CONTRAST", "MAX_OUTER_ALTERNATION", "canonical_orderings", "pattern_score", "outer_alternation"]


#: Smallest black/white difference (grey levels) at which the printed pattern is trusted.
MIN_CONTRAST = 12.0
#: Alternation (as a fraction of the contrast) beyond the grid above which the board is larger than asked.
MAX_OUTER_ALTERNATION = 0.5


def _handedness(grid: np.ndarray) -> float:
    """2-D cross product of the grid's mean x and y steps in the image (> 0: turns clockwise = z into the board)."""
    ex = np.mean(grid[:, 1:] - grid[:, :-1], axis=(0, 1))
    ey = np.mean(grid[1:, :] - grid[:-1, :], axis=(0, 1))
    return float(ex[0] * ey[1] - ex[1] * ey[0])


def canonical_orderings(grid: np.ndarray) -> list[np.ndarray]:
    """The re-orderings of a detector grid ``(ny, nx, 2)`` whose axes turn clockwise in the image.

    Two for a non-square grid (one and its 180-deg turn); four for a square one (transposes too).
    """
    ny, nx = grid.shape[:2]
    candidates = [grid, grid[:, ::-1], grid[::-1, :], grid[::-1, ::-1]]
    if nx == ny:
        t = grid.transpose(1, 0, 2)
        candidates += [t, t[:, ::-1], t[::-1, :], t[::-1, ::-1]]
    return [np.ascontiguousarray(c) for c in candidates if _handedness(c) > 0]


def _square_samples(grid: np.ndarray, a: np.ndarray, b: np.ndarray, image: np.ndarray) -> np.ndarray:
    """Mean grey level near the centres of squares ``(a, b)`` (square ``(a, b)`` spans columns
    ``a-1..a`` and rows ``b-1..b`` of the grid); NaN where the samples leave the image."""
    ny, nx = grid.shape[:2]
    src = np.stack(np.meshgrid(np.arange(nx), np.arange(ny)), axis=-1).reshape(-1, 2).astype(np.float64)
    homography, _ = cv2.findHomography(src, grid.reshape(-1, 2), 0)
    offsets = np.array([(dx, dy) for dx in (-0.2, 0.0, 0.2) for dy in (-0.2, 0.0, 0.2)])
    centres = np.stack([a - 0.5, b - 0.5], axis=-1).astype(np.float64)
    pts = (centres[:, None, :] + offsets[None, :, :]).reshape(-1, 1, 2)
    img_pts = cv2.perspectiveTransform(pts, homography).reshape(len(centres), len(offsets), 2)
    h, w = image.shape
    xi = np.rint(img_pts[..., 0]).astype(int)
    yi = np.rint(img_pts[..., 1]).astype(int)
    inside = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
    values = np.where(inside, image[np.clip(yi, 0, h - 1), np.clip(xi, 0, w - 1)], 0).astype(np.float64)
    out = values.mean(axis=1)
    out[~inside.all(axis=1)] = np.nan
    return out


def pattern_score(grid: np.ndarray, image: np.ndarray) -> float:
    """Mean grey level of the inner squares that should be white minus those that should be black.

    In the canonical ordering square ``(a, b)`` is black when ``a + b`` is even, so the score is
    positive for the canonical ordering (and negative for its 180-deg turn on an even x odd board).
    """
    ny, nx = grid.shape[:2]
    a, b = np.meshgrid(np.arange(1, nx), np.arange(1, ny))
    a, b = a.ravel(), b.ravel()
    values = _square_samples(grid, a, b, image)
    even = (a + b) % 2 == 0
    return float(np.nanmean(values[~even]) - np.nanmean(values[even]))


def outer_alternation(grid: np.ndarray, image: np.ndarray, contrast: float) -> float:
    """Largest alternation of the checker pattern one square ring beyond the outer squares, per side,
    as a fraction of the contrast (about 1 when the board continues, about 0 on the white margin)."""
    ny, nx = grid.shape[:2]
    sides = [
        (np.full(ny + 1, -1), np.arange(0, ny + 1)),       # beyond the x-min edge
        (np.full(ny + 1, nx + 1), np.arange(0, ny + 1)),   # beyond the x-max edge
        (np.arange(0, nx + 1), np.full(nx + 1, -1)),       # beyond the y-min edge
        (np.arange(0, nx + 1), np.full(nx + 1, ny + 1)),   # beyond the y-max edge
    ]
    worst = 0.0
    for a, b in sides:
        values = _square_samples(grid, a, b, image)
        ok = np.isfinite(values)
        if ok.sum() < 3:
            continue
        sign = np.where((a + b) % 2 == 0, -1.0, 1.0)[ok]  # +1 where a continued board would be white
        v = values[ok] - values[ok].mean()
        worst = max(worst, float(np.mean(v * sign)) / (0.5 * contrast))
    return worst
