"""The search for a checkerboard's grid of inner corners (:func:`find_grid`): the cheap stages first
and OpenCV's exhaustive ones only when they fail (:data:`SEARCH_STAGES`: ``roi``, ``fast``,
``full``, ``sb``; the stages are described in :mod:`~handeye.drivers.camera.checkerboard`), with
what the search met when nothing is found (:class:`GridSearch`, :func:`refuse_missing_grid`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from .board_pattern import MAX_OUTER_ALTERNATION, MIN_CONTRAST, canonical_orderings, outer_alternation, pattern_score
from .errors import BoardNotFound, NoBoardInView

__all__ = ["DETECT_FLAGS", "OPENCV_DEFAULT_FLAGS", "ROI_FLAGS", "SB_FLAGS", "SEARCH_STAGES", "GridSearch", "board_region",
           "find_grid", "refuse_missing_grid"]


DETECT_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
#: OpenCV's default flags of ``findChessboardCorners`` (stage ``full``).
OPENCV_DEFAULT_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
#: Stage ``roi``: adaptive threshold without the global equalisation.
ROI_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH
SB_FLAGS = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE
#: The searches of :func:`find_grid`, in the order they are tried.
SEARCH_STAGES = ("roi", "fast", "full", "sb")
#: Images at least this wide are searched at half size in stages ``fast`` and ``sb``.
HALF_SIZE_FROM_WIDTH = 1000
#: The board region is located on a copy about this wide.
REGION_WIDTH = 320


def _half(gray: np.ndarray) -> np.ndarray:
    h, w = gray.shape
    return cv2.resize(gray, (w // 2, h // 2), interpolation=cv2.INTER_AREA)


def _opencv_grid(image: np.ndarray, pattern, flags: int) -> np.ndarray | None:
    found, corners = cv2.findChessboardCorners(image, pattern, flags=flags)
    return corners.reshape(-1, 2).astype(np.float64) if found else None


def board_region(gray: np.ndarray) -> tuple[int, int, int, int] | None:
    """Bounding box ``(x0, y0, x1, y1)`` (full-size pixels, ``x1``/``y1`` exclusive) of where the board
    probably is, or ``None``.

    On a copy about :data:`REGION_WIDTH` pixels wide, the corner energy ``min(blur|gx|, blur|gy|)``
    (large where a square's vertical and horizontal edges meet, small along a single edge, a shadow's
    border or in flat areas) is thresholded at a quarter of its maximum; the box holds every blob of
    at least a fifth of the largest one's area (a shadow may cut the board in two), plus a margin of
    10 % of its size and 8 px (OpenCV refuses corners within 8 px of the image's border).
    """
    h, w = gray.shape
    scale = max(1, int(round(w / REGION_WIDTH)))
    small = cv2.resize(gray, (max(1, w // scale), max(1, h // scale)), interpolation=cv2.INTER_AREA)
    gx = np.abs(cv2.Sobel(small, cv2.CV_32F, 1, 0, ksize=3))
    gy = np.abs(cv2.Sobel(small, cv2.CV_32F, 0, 1, ksize=3))
    energy = cv2.blur(np.minimum(cv2.blur(gx, (5, 5)), cv2.blur(gy, (5, 5))), (9, 9))
    peak = float(energy.max())
    if peak < 4.0:  # flat image
        return None
    mask = (energy > 0.25 * peak).astype(np.uint8)
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask)
    if n <= 1:
        return None
    areas = stats[1:, cv2.CC_STAT_AREA]
    big = 1 + np.nonzero(areas >= 0.2 * areas.max())[0]
    x0, y0 = stats[big, 0].min(), stats[big, 1].min()
    x1 = (stats[big, 0] + stats[big, 2]).max()
    y1 = (stats[big, 1] + stats[big, 3]).max()
    margin = 0.1 * max(x1 - x0, y1 - y0) * scale + 8
    box = (int(max(0, x0 * scale - margin)), int(max(0, y0 * scale - margin)),
           int(min(w, x1 * scale + margin)), int(min(h, y1 * scale + margin)))
    if box[2] - box[0] < 16 or box[3] - box[1] < 16:
        return None
    return box


@dataclass(frozen=True)
class GridSearch:
    """What :func:`find_grid` found.

    Attributes
    ----------
    corners : ndarray, shape (nx*ny, 2), or None
        Detector corners at full-size pixel coordinates (not yet refined, in the detector's order).
    stage : str
        The stage of :data:`SEARCH_STAGES` that found them (``""`` when none did).
    other_pattern : tuple of int or None
        Inner corners ``(nx, ny)`` of a whole board found instead when the asked count was not (the
        count given is wrong).
    larger_seen : tuple of int or None
        A grid of more inner corners than asked seen in the board's region (long side first): the
        board is larger than the count given.
    seconds : dict
        Time spent per stage tried.
    """

    corners: np.ndarray | None
    stage: str = ""
    other_pattern: tuple | None = None
    larger_seen: tuple | None = None
    seconds: dict = field(default_factory=dict)


def _neighbour_patterns(pattern) -> list[tuple[int, int]]:
    """Counts one off the asked one (squares given for corners first), long side first, at least 3x3."""
    nx, ny = pattern
    out = []
    for dx, dy in ((-1, -1), (1, 1), (-1, 0), (0, -1), (1, 0), (0, 1)):
        a, b = nx + dx, ny + dy
        if a >= b and b >= 3 and (a, b) not in out:
            out.append((a, b))
    return out


def _whole_board(corners: np.ndarray, pattern, gray: np.ndarray) -> bool:
    """Whether a grid found for ``pattern`` is a whole board of its own: its outer squares lie inside the
    image (a board cut by the image's edge shows fewer corners than it has) and no checker pattern
    continues beyond them."""
    nx, ny = pattern
    grid = corners.reshape(ny, nx, 2)
    h, w = gray.shape
    beyond = np.concatenate([2 * grid[:, 0] - grid[:, 1], 2 * grid[:, -1] - grid[:, -2],
                             2 * grid[0] - grid[1], 2 * grid[-1] - grid[-2]])
    if np.any(beyond < 2) or np.any(beyond[:, 0] > w - 3) or np.any(beyond[:, 1] > h - 3):
        return False
    candidates = canonical_orderings(grid)
    if not candidates:
        return False
    contrast = max(abs(pattern_score(c, gray)) for c in candidates)
    return bool(np.isfinite(contrast) and contrast >= MIN_CONTRAST
                and outer_alternation(candidates[0], gray, contrast) <= MAX_OUTER_ALTERNATION)


def _another_count(crop, region, pattern, gray, lap) -> dict | None:
    """In a region OpenCV says holds a checkerboard: ``{"other": (a, b)}`` for a whole board one corner
    off (or of another count OpenCV confirms), ``{"larger": (a, b)}`` for a grid larger than asked, else
    ``None``; ``lap("count")`` times the stage."""
    for other in _neighbour_patterns(pattern):
        found = _opencv_grid(crop, other, ROI_FLAGS)
        if found is not None and _whole_board(found + region[:2], other, gray):
            lap("count")
            return {"other": other}
    # A grid larger than asked (findChessboardCornersSB may return more corners than its pattern):
    # whatever OpenCV's exhaustive search could find would be part of that larger board.
    ok, seen, meta = cv2.findChessboardCornersSBWithMeta(crop, (3, 3), flags=cv2.CALIB_CB_LARGER | SB_FLAGS)
    lap("count")
    if ok and meta is not None and seen is not None and len(seen) == meta.shape[0] * meta.shape[1]:
        rows, cols = (int(v) for v in meta.shape[:2])
        a, b = max(rows, cols), min(rows, cols)
        if (a, b) != tuple(pattern) and a >= 3 and b >= 3:  # a whole board of another count? OpenCV confirms
            found = _opencv_grid(crop, (a, b), ROI_FLAGS)
            lap("count")
            if found is not None and _whole_board(found + region[:2], (a, b), gray):
                return {"other": (a, b)}
        if a > pattern[0] or b > pattern[1]:
            return {"larger": (a, b)}
    return None


def find_grid(gray: np.ndarray, pattern: tuple[int, int], search: str = "full") -> GridSearch:
    """Search the board with the stages of :data:`SEARCH_STAGES` in turn (see the module docstring).

    Parameters
    ----------
    gray : ndarray, shape (h, w), uint8
    pattern : (nx, ny)
        Inner corners.
    search : {"full", "fast"}
        ``"full"`` tries every stage before giving up; ``"fast"`` only the first (``roi``).

    Returns
    -------
    GridSearch
        With ``search="full"``, when the cheap stages fail but a checkerboard is in view, boards one
        corner off in either direction are looked for in its region (a wrong count makes OpenCV's
        exhaustive search take up to tens of seconds); a whole board found that way ends the search
        with ``other_pattern`` set, and so does a grid larger than asked (``findChessboardCornersSB``
        with ``CALIB_CB_LARGER``), with ``larger_seen``.
    """
    if search not in ("full", "fast"):
        raise ValueError(f"search must be 'full' or 'fast'; got {search!r}")
    h, w = gray.shape
    large = w >= HALF_SIZE_FROM_WIDTH
    seconds = {}
    clock = time.perf_counter()

    def lap(stage):
        nonlocal clock
        now = time.perf_counter()
        seconds[stage] = now - clock
        clock = now

    region = board_region(gray)
    crop = None
    if region is not None:
        x0, y0, x1, y1 = region
        crop = np.ascontiguousarray(gray[y0:y1, x0:x1])
        corners = _opencv_grid(crop, pattern, ROI_FLAGS)
        lap("roi")
        if corners is not None:
            return GridSearch(corners + (x0, y0), "roi", seconds=seconds)
    if search == "fast":
        return GridSearch(None, seconds=seconds)
    searched = _half(gray) if large else gray  # the image of stages fast and sb
    corners = _opencv_grid(searched, pattern, DETECT_FLAGS)
    lap("fast")
    if corners is not None:
        return GridSearch(corners * 2.0 + 0.5 if large else corners, "fast", seconds=seconds)
    if crop is not None and cv2.checkChessboard(crop, pattern):
        other = _another_count(crop, region, pattern, gray, lap)
        if other is not None:
            return GridSearch(None, other_pattern=other.get("other"), larger_seen=other.get("larger"), seconds=seconds)
    corners = _opencv_grid(gray, pattern, OPENCV_DEFAULT_FLAGS)
    lap("full")
    if corners is not None:
        return GridSearch(corners, "full", seconds=seconds)
    # SB costs grow with the area searched: the region when it is small, else the half-size image
    if crop is not None and region is not None and (region[2] - region[0]) * (region[3] - region[1]) < 0.25 * w * h:
        found, corners = cv2.findChessboardCornersSB(crop, pattern, flags=SB_FLAGS)
        offset, scale = np.array(region[:2], float), 1.0
    else:
        found, corners = cv2.findChessboardCornersSB(searched, pattern, flags=SB_FLAGS)
        offset, scale = (np.array([0.5, 0.5]) if large else np.zeros(2)), (2.0 if large else 1.0)
    lap("sb")
    if found:
        return GridSearch(corners.reshape(-1, 2).astype(np.float64) * scale + offset, "sb", seconds=seconds)
    return GridSearch(None, seconds=seconds)


def refuse_missing_grid(result: GridSearch, gray: np.ndarray, pattern: tuple, what: str) -> np.ndarray:
    """Raise :class:`BoardNotFound` saying why ``result`` holds no grid of ``pattern`` (another count,
    a larger board, a board partly out of view, none at all); return its corners when it holds one."""
    nx, ny = pattern
    if result.other_pattern is not None:
        a, b = result.other_pattern
        raise BoardNotFound(f"the board in the {what} has {a}x{b} inner corners, not {nx}x{ny}: give --board {a}x{b} "
                            f"(inner corners, long side first)")
    if result.larger_seen is not None:
        a, b = result.larger_seen
        raise BoardNotFound(f"the board in the {what} has more inner corners than {nx}x{ny} ({a}x{b} seen at least): "
                            f"give its full inner-corner count (--board, long side first)")
    if result.corners is None:
        if cv2.checkChessboard(gray, (nx, ny)):
            raise BoardNotFound(
                f"a checkerboard is in the {what} but not all of its {nx}x{ny} inner corners were found: check that "
                f"the whole board with its white margin is in view and that {nx}x{ny} is its inner-corner count "
                f"(--board; e.g. 13x8 for 14x9 squares)"
            )
        raise NoBoardInView(f"no checkerboard in the {what}: check that the board is in view, lit evenly and in focus")
    return result.corners
