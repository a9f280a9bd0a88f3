"""ChArUco boards (and asymmetric circle grids) in stereo images: OpenCV detects, ids match, we triangulate.

ChArUco (``cv2.aruco.CharucoDetector``, OpenCV >= 4.7): the markers are found and decoded, the chessboard
corners between them interpolated and refined by OpenCV; each corner carries its id, which is the
canonical target index (``row * nx + col``, :mod:`handeye.geometry.targets`). The left and right
detections are matched by id, the common corners triangulated and checked as a checkerboard's are
(rectified rows, plane fit, corner spacing between neighbours that were both seen). A view with fewer
than :data:`~handeye.calibration.partial_views.MIN_CORNERS` common corners, or whose corners span too
little of the board, is refused with the reason (:func:`~handeye.calibration.partial_views.view_refusal`).

Circle grids (``cv2.findCirclesGrid`` with ``CALIB_CB_ASYMMETRIC_GRID``) are found whole, in OpenCV's
order, which is the target index order of :class:`~handeye.geometry.targets.CircleGrid`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from ...geometry import view_refusal
from ...geometry import CharucoBoard, CircleGrid, describe
from .checkerboard import SUBPIX_CRITERIA, WINDOW_FRACTION, WINDOW_MAX, WINDOW_MIN, BoardObservation, _gray_u8, plane_fit
from .errors import BoardNotFound, NoBoardInView, StereoMismatch
from .stereo import StereoModel

__all__ = ["CharucoDetection", "opencv_board", "detect_charuco", "detect_circles", "observe_partial",
           "partial_quality"]

#: Largest RMS rectified row disagreement (px) of the matched corners before the pair is refused.
MAX_ROW_DISAGREEMENT_PX = 2.0
#: A matched corner whose rectified rows disagree by more than this (px), and this many times the median,
#: is dropped (a refinement pulled by a marker edge in one image): a partial view is allowed, a bad corner not.
ROW_OUTLIER_PX, ROW_OUTLIER_RATIO = 0.3, 4.0


@functools.lru_cache(maxsize=8)
def _opencv_board(squares: tuple, square_mm: float, marker_mm: float, dictionary: str, legacy: bool):
    board = cv2.aruco.CharucoBoard(squares, square_mm, marker_mm,
                                   cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)))
    board.setLegacyPattern(bool(legacy))
    return board


def opencv_board(board: CharucoBoard):
    """The ``cv2.aruco.CharucoBoard`` of a board description (cached)."""
    return _opencv_board(*_board_key(board))


def _board_key(board: CharucoBoard) -> tuple:
    """The cache key of a board: squares, square and marker size (mm), dictionary, legacy layout."""
    if board.square_mm is None or board.marker_mm is None:
        raise ValueError("a ChArUco board needs its square and marker sizes")
    return tuple(board.squares), float(board.square_mm), float(board.marker_mm), board.dictionary, bool(board.legacy)


@functools.lru_cache(maxsize=8)
def _detector(squares, square_mm, marker_mm, dictionary, legacy):
    board = _opencv_board(squares, square_mm, marker_mm, dictionary, legacy)
    params = cv2.aruco.DetectorParameters()
    # Small markers (a 22 mm marker at 1 m is ~21 px, 3 px per bit): sample each bit on 8 px, away from its
    # edges (OpenCV's defaults, 4 px and 13 %, lose a tenth of the markers there; measured on the mock's renders).
    params.perspectiveRemovePixelPerCell = 8
    params.perspectiveRemoveIgnoredMarginPerCell = 0.2
    charuco = cv2.aruco.CharucoParameters()
    charuco.tryRefineMarkers = True  # look again for the markers the board says are missing (85 -> 103 of 104
    # corners on average on 16 renders at 0.9-1.25 m, 20-45 deg tilt)
    return cv2.aruco.CharucoDetector(board, charuco, params)


def reference_detector(board: CharucoBoard):
    """OpenCV's ChArUco detector with its default parameters (what this module's detection is compared with)."""
    return cv2.aruco.CharucoDetector(opencv_board(board))


@dataclass(frozen=True)
class CharucoDetection:
    """Corners of a board seen (perhaps in part) in one image.

    Attributes
    ----------
    corners_px : ndarray, shape (k, 2)
        Pixel coordinates (pixel centres at integers), sorted by id.
    ids : ndarray of int, shape (k,)
        Target indices.
    board : BoardGeometry
    image_size : tuple of int
    markers : int
        Markers decoded (0 for a circle grid).
    """

    corners_px: np.ndarray
    ids: np.ndarray
    board: object
    image_size: tuple
    markers: int = 0
    ambiguous: bool = False
    alternatives: tuple = ()
    stage: str = "charuco"
    off_grid: tuple = ()
    off_grid_px: float = 0.0


def detect_charuco(image: np.ndarray, board: CharucoBoard, what: str = "image") -> CharucoDetection:
    """The ChArUco corners OpenCV finds in one image, by id.

    Raises
    ------
    NoBoardInView
        No marker of the board's dictionary at all.
    BoardNotFound
        Markers, but no chessboard corner between them.
    """
    gray = _gray_u8(image, what)
    key = _board_key(board)
    corners, ids, marker_corners, marker_ids = _detector(*key).detectBoard(gray)
    markers = 0 if marker_ids is None else len(marker_ids)
    if markers == 0:
        raise NoBoardInView(f"no {board.dictionary} marker of the ChArUco board in the {what}: is it in view and lit?")
    if ids is None or len(ids) == 0:
        raise BoardNotFound(f"{markers} markers but no ChArUco corner in the {what}: bring more of the board into view")
    ids = ids.ravel().astype(int)
    order = np.argsort(ids)
    h, w = gray.shape
    ids, px = ids[order], corners.reshape(-1, 2)[order].astype(np.float64)
    px = refine_without_markers(gray, px, ids, marker_corners, board)
    keep = on_grid(ids, px, board)
    return CharucoDetection(px[keep], ids[keep], board, (w, h), markers, off_grid=tuple(int(i) for i in ids[~keep]))


#: Marker quads are painted over this far beyond their detected outline (px): the blur of the marker's edge.
MARKER_MARGIN_PX = 1.0
#: A refined corner that moved further than this (px, and as a fraction of the window) keeps OpenCV's position.
MAX_SHIFT_PX, MAX_SHIFT_FRACTION = 1.0, 0.25


def paint_out_markers(gray: np.ndarray, marker_corners) -> np.ndarray:
    """A copy of ``gray`` ``(h, w)`` uint8 with every detected marker quad (grown by :data:`MARKER_MARGIN_PX`)
    filled with the median grey of a thin ring around it (the white paper between marker and squares)."""
    out = gray.copy()
    h, w = gray.shape
    for quad in marker_corners if marker_corners is not None else ():
        q = np.asarray(quad, np.float64).reshape(4, 2)
        centre = q.mean(axis=0)
        radial = (q - centre) / np.linalg.norm(q - centre, axis=1, keepdims=True)
        grown = [q + radial * grow * np.sqrt(2.0) for grow in (MARKER_MARGIN_PX, MARKER_MARGIN_PX + 1.5)]
        x0, y0 = np.maximum(np.floor(grown[1].min(axis=0)).astype(int) - 1, 0)
        x1, y1 = np.minimum(np.ceil(grown[1].max(axis=0)).astype(int) + 2, [w, h])
        if x1 <= x0 or y1 <= y0:
            continue
        inner, outer = (np.zeros((y1 - y0, x1 - x0), np.uint8) for _ in range(2))  # the marker's box only
        for mask, poly in ((inner, grown[0]), (outer, grown[1])):
            cv2.fillConvexPoly(mask, np.round((poly - [x0, y0]) * 16).astype(np.int32), 1, cv2.LINE_8, 4)
        box = gray[y0:y1, x0:x1]
        ring = box[(outer > 0) & (inner == 0)]
        out[y0:y1, x0:x1][inner > 0] = np.uint8(np.median(ring)) if len(ring) else np.uint8(255)
    return out


def refine_without_markers(gray: np.ndarray, px: np.ndarray, ids: np.ndarray, marker_corners, board) -> np.ndarray:
    """ChArUco corners ``(k, 2)`` refined as the checkerboard's are (``cornerSubPix``, half-window 0.4 x the
    smallest spacing of neighbours seen, same criteria), on the image with the markers painted out.

    OpenCV refines each ChArUco corner in a window small enough to miss the nearest marker (a few pixels at
    the station's distances: twice the checkerboard's corner error on the mock's renders); with the markers
    painted over, the squares' edges around a corner are a checkerboard's and the same window fits
    (``benchmarks/charuco/bench_corners.py``). Every corner OpenCV returns had both its neighbouring markers
    decoded (``minMarkers`` = 2), so their quads are known. A corner that moves further than
    :data:`MAX_SHIFT_PX` keeps OpenCV's position.
    """
    nx = int(board.corners[0])
    index = {int(i): k for k, i in enumerate(ids)}
    gaps = [np.linalg.norm(px[index[i]] - px[index[j]]) for i in index for j in (i + 1, i + nx)
            if j in index and (j != i + 1 or (i + 1) % nx)]
    if not gaps:
        return px
    half = int(np.clip(np.floor(WINDOW_FRACTION * min(gaps)), WINDOW_MIN, WINDOW_MAX))
    painted = paint_out_markers(gray, marker_corners)
    refined = cv2.cornerSubPix(painted, px.reshape(-1, 1, 2).astype(np.float32), (half, half), (-1, -1),
                               SUBPIX_CRITERIA).reshape(-1, 2).astype(np.float64)
    moved = np.linalg.norm(refined - px, axis=1) > max(MAX_SHIFT_PX, MAX_SHIFT_FRACTION * half)
    refined[moved] = px[moved]
    return refined


#: A ChArUco corner further than this from the smooth grid through the others is dropped (px, and as a
#: fraction of the corner spacing): the gap between a square's corner and its neighbouring markers is a
#: few pixels at the station's distances, and a refinement window that reaches a marker edge moves the
#: corner (up to ~1 px on the mock's renders, against < 0.3 px for the others).
OFF_GRID_PX, OFF_GRID_FRACTION = 0.5, 0.02


def on_grid(ids: np.ndarray, px: np.ndarray, board) -> np.ndarray:
    """Mask ``(k,)`` of the corners on the smooth (cubic, from 30 corners; quadratic from 12) map from grid
    indices to pixels fitted to the others; the worst is left out and the map refitted while it is off."""
    nx, ny = (int(c) for c in board.corners)
    n = len(ids)
    degree = 3 if n >= 30 else 2 if n >= 12 else 0
    if degree == 0:
        return np.ones(n, bool)
    from .checkerboard import _monomials  # noqa: PLC0415

    col, row = ids % nx, ids // nx
    basis = _monomials((col - (nx - 1) / 2) / max(nx - 1, 1), (row - (ny - 1) / 2) / max(ny - 1, 1), degree)
    keep = np.ones(n, bool)
    residuals = np.zeros(n)
    for _ in range(n // 4):
        coef, *_ = np.linalg.lstsq(basis[keep], px[keep], rcond=None)
        residuals = np.linalg.norm(basis @ coef - px, axis=1)
        scale = np.median(np.linalg.norm(np.diff(basis @ coef, axis=0), axis=1))  # about one spacing
        limit = max(OFF_GRID_PX, OFF_GRID_FRACTION * scale)
        worst = int(np.argmax(np.where(keep, residuals, -1.0)))
        if residuals[worst] <= limit or keep.sum() <= basis.shape[1] + 4:
            break
        keep[worst] = False
    return keep


def detect_circles(image: np.ndarray, board: CircleGrid, what: str = "image") -> CharucoDetection:
    """An asymmetric circle grid found whole (``cv2.findCirclesGrid``), in OpenCV's (= target index) order."""
    gray = _gray_u8(image, what)
    found, centres = cv2.findCirclesGrid(gray, tuple(int(c) for c in board.corners), flags=cv2.CALIB_CB_ASYMMETRIC_GRID)
    if not found:
        raise NoBoardInView(f"no {board.corners[0]}x{board.corners[1]} asymmetric circle grid in the {what}")
    h, w = gray.shape
    return CharucoDetection(centres.reshape(-1, 2).astype(np.float64), np.arange(board.count), board, (w, h))


def partial_quality(points_mm: np.ndarray, ids: np.ndarray, board, row_disagreement_px=None) -> dict:
    """:func:`~handeye.drivers.camera.checkerboard.board_quality` on a seen subset: the plane fit of the seen
    corners, and the spacing of neighbours (along x and along y) that were both seen."""
    centroid, normal, dist = plane_fit(points_mm)
    if normal[2] > 0:
        normal = -normal
    model = board.grid(1.0)
    index = {int(i): k for k, i in enumerate(ids)}
    nx = int(board.corners[0])
    pairs = [(index[i], index[j]) for i in index for j in (i + 1, i + nx)
             if j in index and (j != i + 1 or (i + 1) % nx) and np.isclose(np.linalg.norm(model[i] - model[j]), 1.0)]
    spacing = np.array([np.linalg.norm(points_mm[a] - points_mm[b]) for a, b in pairs]) if pairs else np.array([np.nan])
    if getattr(board, "kind", "") == "circles":  # neighbours of one row are one spacing apart
        row = np.arange(len(ids)) // nx
        steps = np.linalg.norm(np.diff(points_mm, axis=0), axis=1)[np.diff(row) == 0]
        spacing = steps
    out = {
        "corners": int(len(points_mm)),
        "corners_of_board": int(board.count),
        "plane_rms_mm": float(np.sqrt(np.mean(dist**2))),
        "plane_max_mm": float(np.abs(dist).max()),
        "distance_mm": float(np.linalg.norm(centroid)),
        "tilt_deg": float(np.degrees(np.arccos(np.clip(-normal[2], -1.0, 1.0)))),
        "square_mm_measured": float(np.nanmean(spacing)),
    }
    if row_disagreement_px is not None:
        out["row_disagreement_rms_px"] = float(np.sqrt(np.mean(row_disagreement_px**2)))
        out["row_disagreement_max_px"] = float(np.abs(row_disagreement_px).max())
    return out


@dataclass(frozen=True)
class PartialObservation(BoardObservation):
    """A :class:`BoardObservation` of the corners both images saw: ``corner_ids`` ``(k,)`` says which."""

    corner_ids: np.ndarray | None = None


def _detect(image, board, what: str) -> CharucoDetection:
    return detect_circles(image, board, what) if getattr(board, "kind", "") == "circles" else detect_charuco(image, board, what)


def observe_partial(left: np.ndarray, right: np.ndarray, model: StereoModel, board, *,
                    max_row_disagreement_px: float = MAX_ROW_DISAGREEMENT_PX) -> PartialObservation:
    """Detect a ChArUco board (or a circle grid) in both images, match the corners by id, check and triangulate.

    Raises
    ------
    BoardNotFound
        Not seen, or the common corners cannot fix the board's pose (too few, too small a span: the reason).
    StereoMismatch
        The matched corners do not agree with the stereo model (swapped or unrelated images).
    """
    det_left = _detect(left, board, "left image")
    det_right = _detect(right, board, "right image")
    common, li, ri = np.intersect1d(det_left.ids, det_right.ids, return_indices=True)
    why = view_refusal(common, board)
    if why:
        raise BoardNotFound(f"{describe(board)}: {len(det_left.ids)} corners in the left image, {len(det_right.ids)} "
                            f"in the right, {len(common)} in both: {why}")
    lp, rp = det_left.corners_px[li], det_right.corners_px[ri]
    rl, rr = model.rectify_points(lp, rp)
    if not np.all(rl[:, 0] - rr[:, 0] > 0):
        raise StereoMismatch("no corner in the right image lies left of its match in the left image: are the left and "
                             "right images swapped?")
    rows = rl[:, 1] - rr[:, 1]
    bad = np.abs(rows) > max(ROW_OUTLIER_PX, ROW_OUTLIER_RATIO * float(np.median(np.abs(rows))))
    if bad.any() and not view_refusal(common[~bad], board):  # a corner the two images disagree on: drop it
        common, lp, rp, rl, rr = common[~bad], lp[~bad], rp[~bad], rl[~bad], rr[~bad]
    rms = float(np.sqrt(np.mean((rl[:, 1] - rr[:, 1]) ** 2)))
    if rms > max_row_disagreement_px:
        raise StereoMismatch(f"left and right corners of the same id disagree by {rms:.1f} px (RMS) in rectified rows: the "
                             "stereo model does not fit this camera, or the images are not one stereo frame")
    tri = model.triangulate(lp, rp)
    quality = partial_quality(tri.points_mm, common, board, tri.row_disagreement_px)
    quality["corners_left"], quality["corners_right"] = int(len(det_left.ids)), int(len(det_right.ids))
    quality["orientation"] = "ids"
    left_det = CharucoDetection(lp, common, board, det_left.image_size, det_left.markers)
    right_det = CharucoDetection(rp, common, board, det_right.image_size, det_right.markers)
    return PartialObservation(tri.points_mm, left_det, right_det, quality, common.astype(int))
