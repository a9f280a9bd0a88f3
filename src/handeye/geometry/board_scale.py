"""The board's square size as the measured corners show it, robust to the camera's noise.

The mean distance between neighbouring measured corners is lengthened by noise (a 10 mm noise on
30 mm squares reads 31.5 mm), so the size is estimated instead by fitting the board's grid with a
free scale to each posture's corners (a similarity fit, Umeyama 1991): with the noise-free grid as
the source, the scale ``s = trace(D S) / sum |g_k - g|^2`` is a regression of the measured corners
on the grid, unbiased under zero-mean noise. The estimate of the session is the median over the
postures, with its standard error ``1.2533 * std / sqrt(n)``.

:func:`judge_square_size` says whether ``target.square_mm`` disagrees: only when the estimate is off
by more than :data:`SQUARE_TOLERANCE` (5 %) *and* by more than :data:`SQUARE_SIGMAS` (4) standard
errors; and then whether it looks like a unit (a factor 10, 25.4, 100 or 1000) or a wrong size.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["BoardScale", "SQUARE_TOLERANCE", "SQUARE_SIGMAS", "board_scale", "grid_scales", "judge_square_size"]

#: Largest relative difference tolerated between the estimated square size and ``target.square_mm``.
SQUARE_TOLERANCE = 0.05
#: The difference must also exceed this many standard errors of the estimate to refuse.
SQUARE_SIGMAS = 4.0
#: Unit factors a square size is commonly off by (cm, inch, dm, m) and how much slack each gets.
_UNIT_FACTORS = {10.0: "cm", 25.4: "inches", 100.0: "dm", 1000.0: "m"}


@dataclass(frozen=True)
class BoardScale:
    """The square size the corners show.

    Attributes
    ----------
    square_mm : float
        Median over the postures of the fitted grid scale (mm per square).
    stderr_mm : float
        Its standard error (0 with one posture).
    per_posture_mm : ndarray, shape (n,)
        The fitted scale of each posture.
    """

    square_mm: float
    stderr_mm: float
    per_posture_mm: np.ndarray


@dataclass(frozen=True)
class SquareJudgement:
    """``verdict`` is ``ok``, ``units``, ``square_size`` (both refuse) or ``noise`` (off, but too noisy to judge)."""

    verdict: str
    message: str
    scale: BoardScale


def grid_scales(points_mm: npt.ArrayLike, corners: Sequence[int]) -> np.ndarray:
    """The similarity-fit scale of the unit grid to each posture's corners.

    Parameters
    ----------
    points_mm : array-like, shape (n, nx*ny, 3) or (nx*ny, 3)
        Measured corners in target index order (``k = row * nx + col``), camera frame, mm.
    corners : tuple of int
        ``(nx, ny)`` inner corners along x and y.

    Returns
    -------
    ndarray, shape (n,)
        mm per square for each posture (``s`` of ``p_k = s R g_k + t``, ``g_k = (col, row, 0)``).
    """
    nx, ny = (int(c) for c in corners)
    points = np.asarray(points_mm, float).reshape(-1, nx * ny, 3)
    cols, rows = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    grid = np.stack([cols.ravel(), rows.ravel(), np.zeros(nx * ny)], axis=1)
    grid -= grid.mean(axis=0)
    centred = points - points.mean(axis=1, keepdims=True)
    cross = np.einsum("nki,kj->nij", centred, grid)  # (n, 3, 3): sum_k p_k g_k^T
    u, d, vt = np.linalg.svd(cross)
    sign = np.sign(np.linalg.det(u @ vt))  # a reflection keeps the last singular value negative
    d = d.copy()
    d[:, 2] *= np.where(sign == 0, 1.0, sign)
    return d.sum(axis=1) / float(np.sum(grid ** 2))


def board_scale(points_mm: npt.ArrayLike, corners: Sequence[int]) -> BoardScale:
    """The session's square size (median of :func:`grid_scales`) and its standard error."""
    scales = grid_scales(points_mm, corners)
    if not np.all(np.isfinite(scales)):
        scales = np.where(np.isfinite(scales), scales, 0.0)
    n = len(scales)
    stderr = 1.2533 * float(np.std(scales, ddof=1)) / np.sqrt(n) if n > 1 else 0.0
    return BoardScale(float(np.median(scales)), stderr, scales)


def _unit_word(ratio: float) -> str | None:
    for factor, word in _UNIT_FACTORS.items():
        for r, direction in ((factor, "larger"), (1.0 / factor, "smaller")):
            if abs(ratio / r - 1.0) < SQUARE_TOLERANCE:
                return f"{factor:g} times {direction}: a unit ({word} for mm)"
    return None


def judge_square_size(points_mm: npt.ArrayLike, corners: Sequence[int], square_mm: float) -> SquareJudgement:
    """Whether the corners contradict ``square_mm`` (module docstring), and the one line saying so."""
    scale = board_scale(points_mm, corners)
    seen = scale.square_mm
    off = abs(seen - square_mm)
    head = (f"the measured board corners are {seen:.4g} mm apart but target.square_mm is {square_mm:g} mm "
            f"(grid fit, median of {len(scale.per_posture_mm)} postures, standard error {scale.stderr_mm:.2g} mm)")
    if off <= SQUARE_TOLERANCE * square_mm:
        return SquareJudgement("ok", "", scale)
    if off <= SQUARE_SIGMAS * scale.stderr_mm:
        return SquareJudgement("noise", f"{head}: within {SQUARE_SIGMAS:g} standard errors, the corners are too noisy "
                                        f"to judge the square size", scale)
    ratio = seen / square_mm if square_mm else np.inf
    unit = _unit_word(ratio) if np.isfinite(ratio) and ratio > 0 else None
    if unit:
        return SquareJudgement("units", f"{head}, {unit}: write target.square_mm in mm, or check the stereo "
                                        f"calibration's units (T in mm)", scale)
    return SquareJudgement("square_size", f"{head}, {100 * off / square_mm:.0f} % off and "
                                          f"{off / max(scale.stderr_mm, 1e-12):.0f} standard errors: correct the square "
                                          f"size in session.yaml, or the stereo calibration's units (T in mm)", scale)
