"""Checkerboard corners in images, in the canonical order of the target frame, and their 3D positions.

Detection tries cheap searches first and OpenCV's exhaustive ones only when those fail, so that a
board is found wherever ``cv2.findChessboardCorners`` with its default flags finds it, but usually in
a fraction of its time (:data:`SEARCH_STAGES`, :func:`find_grid`):

1. ``roi``: the board's region is located on a small copy of the image (where strong horizontal and
   vertical gradients meet: the squares' corners), cropped at full size with a margin, and searched
   by ``findChessboardCorners`` with the adaptive threshold alone. Without the global histogram
   equalisation of ``CALIB_CB_NORMALIZE_IMAGE`` a glare spot or a shadow does not wash out the rest
   of the board, and the crop keeps the search cheap (tens of ms at 1280x960), found or not.
2. ``fast``: ``findChessboardCorners`` with the fast check (adaptive threshold, normalised image), on
   a half-size copy of large images (``INTER_AREA``, so a half-size pixel ``x`` is full-size
   ``2x + 0.5``): a few milliseconds when there is no board.
3. ``full``: ``findChessboardCorners(image, pattern)`` exactly as OpenCV's default call, on the whole
   image: the guarantee that nothing OpenCV finds is missed (slow when it fails: up to seconds).
4. ``sb``: ``findChessboardCornersSB`` (normalised, exhaustive) on the region of stage 1 (or a
   half-size copy of large images): another detector, which survives blur and noise.

Then ``cv2.cornerSubPix`` on the full image with a half-window of 0.4 x the smallest corner spacing.
``search="fast"`` stops after stage 1 (a live preview that must keep up with the camera). Measured
on hard renders and real photographs: ``benchmarks/vision/bench_detection.py``. Every detection is
checked for corners off the smooth grid through the others (:func:`off_grid_corners`): a glare spot
or a shadow edge can move a corner by many pixels without the detector noticing; such corners are
listed (``Detection.off_grid``) and :func:`observe_board` refuses the board.

Canonical order (target frame of conventions.md): corner index ``k = row * nx + col``; the origin
is a corner of the grid, x runs along the rows (``nx = corners[0]`` corners), y along the
columns, and z = x × y points into the board, away from a camera that sees the printed face. In
the image this means the grid's x and y directions turn clockwise (image y points down).
The detector may start at any corner and run either way; of the orderings with the right handedness
the printed pattern picks one: the square between corners 0, 1, nx and nx + 1 is BLACK. For a
board of even × odd squares (e.g. 13x8 inner corners = 14x9 squares) that is exactly "x runs from
the edge whose two corner squares are black towards the edge whose corner squares are white". A
board whose squares are odd × odd or even × even looks the same turned by 180 degrees; there the
ordering whose x axis points most to the right in the left image is taken and the detection is
flagged ``ambiguous`` (the right image then follows the left through the rectified rows).

A detection is refused (:class:`BoardNotFound`, one line) when the grid is not found, when the
pattern contrast is too low to read the orientation, or when the squares just outside the detected
grid continue the checker pattern (the board has more corners than asked for).

Modules: ``grid_search`` (the stages of :func:`find_grid`), ``board_pattern`` (orderings, the
printed pattern, its contrast); this one detects, refines, checks and triangulates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import cv2
import numpy as np

from ...geometry import BoardGeometry, board_corners
from .board_pattern import MAX_OUTER_ALTERNATION, MIN_CONTRAST, canonical_orderings, outer_alternation, pattern_score
from .errors import BoardNotFound, CameraError, FrameError, StereoMismatch
from .grid_search import SEARCH_STAGES, GridSearch, board_region, find_grid, refuse_missing_grid
from .pnp import pnp_pose
from .stereo import StereoModel

if TYPE_CHECKING:
    import numpy.typing as npt

    from .charuco import CharucoDetection

__all__ = [
    "Detection",
    "BoardObservation",
    "as_board",
    "detect_board",
    "find_grid",
    "off_grid_corners",
    "GridSearch",
    "board_region",
    "SEARCH_STAGES",
    "canonical_orderings",
    "pattern_score",
    "board_pose_from_corners",
    "observe_board",
    "board_quality",
    "plane_fit",
]


SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-4)
#: Refinement half-window as a fraction of the smallest corner spacing, and its bounds (px).
WINDOW_FRACTION = 0.4
WINDOW_MIN, WINDOW_MAX = 2, 15
#: A corner further than this from the smooth grid through the others is off the grid (px, and as a
#: fraction of the corner spacing): glare or a shadow edge moved it.
OFF_GRID_PX, OFF_GRID_FRACTION = 1.5, 0.06
#: Largest RMS rectified row disagreement (px) of a stereo detection before it is refused.
MAX_ROW_DISAGREEMENT_PX = 2.0


def as_board(board: BoardGeometry | str | Sequence[int], square_mm: float | None = None) -> BoardGeometry:
    """A :class:`BoardGeometry` from a geometry, ``(nx, ny)`` or ``"13x8"`` (long side first).

    Raises
    ------
    CameraError
        Not two counts, fewer than 2x2 corners, the short side first, a square size <= 0.
    """
    if isinstance(board, BoardGeometry):
        if square_mm is not None and board.square_mm != square_mm:
            return replace(board, square_mm=float(square_mm))  # a ChArUco board or circle grid stays one
        return board
    if isinstance(board, str):
        parts = board.lower().replace("×", "x").split("x")
        try:
            board = tuple(int(p) for p in parts)
        except ValueError:
            board = ()
        if len(board) != 2:
            raise CameraError(f"board must be written as inner corners NXxNY, e.g. 13x8; got {'x'.join(parts)!r}")
    nx, ny = (int(v) for v in board)
    if nx < 2 or ny < 2:
        raise CameraError(f"a board needs at least 2x2 inner corners; got {nx}x{ny}")
    if nx < ny:
        raise CameraError(f"give the board's long side first: {ny}x{nx}, not {nx}x{ny} (x runs along the long side; "
                          "the corner order follows it)")
    if square_mm is not None and not (np.isfinite(square_mm) and square_mm > 0):
        raise CameraError(f"square size must be a positive number of mm; got {square_mm}")
    return BoardGeometry((nx, ny), None if square_mm is None else float(square_mm))


@dataclass(frozen=True)
class Detection:
    """Corners of one board in one image, canonical order.

    Attributes
    ----------
    corners_px : ndarray, shape (nx*ny, 2)
        Pixel coordinates (pixel centres at integers), index ``row * nx + col``.
    board : BoardGeometry
    image_size : tuple of int
        ``(width, height)``.
    ambiguous : bool
        The pattern cannot tell the board from itself turned by 180 deg (odd x odd or even x even squares).
    pattern_score : float
        Mean white minus mean black grey level of the inner squares in this ordering (> 0).
    alternatives : tuple of ndarray
        The other ordering(s) with the right handedness (the 180-deg turn), for stereo matching.
    stage : str
        The search stage of :func:`find_grid` that found the board (``fast``, ``roi``, ``full``, ``sb``).
    off_grid : tuple of int
        Indices of corners that do not lie on the smooth grid through the others (:func:`off_grid_corners`:
        glare or a shadow edge moved them); the detector found the board, but these corners are not
        measurements. Triangulation refuses such a board; calibration leaves the view out.
    off_grid_px : float
        The largest distance of a corner from that grid.
    """

    corners_px: np.ndarray
    board: BoardGeometry
    image_size: tuple
    ambiguous: bool
    pattern_score: float
    alternatives: tuple = ()
    stage: str = ""
    off_grid: tuple = ()
    off_grid_px: float = 0.0

    def off_grid_message(self, what: str = "image") -> str:
        """One line for a board whose corners are off its grid (empty when they are all on it)."""
        if not self.off_grid:
            return ""
        return (f"{len(self.off_grid)} corner(s) of the board in the {what} are up to {self.off_grid_px:.1f} px off its "
                f"grid (glare or a shadow edge on the board): move the light or turn the board")

    @property
    def grid(self) -> np.ndarray:
        """Corners as ``(ny, nx, 2)``."""
        nx, ny = self.board.corners
        return self.corners_px.reshape(ny, nx, 2)


def _gray_u8(image: np.ndarray, what: str = "image") -> np.ndarray:
    if not isinstance(image, np.ndarray) or image.size == 0:
        raise FrameError(f"{what} is empty")
    if image.ndim == 3 and image.shape[2] in (3, 4):
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    elif image.ndim == 3 and image.shape[2] == 1:
        image = image[..., 0]
    if image.ndim != 2:
        raise FrameError(f"{what} must be a grey or BGR image; got shape {image.shape}")
    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    elif image.dtype != np.uint8:
        image = np.clip(image, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(image)


def _monomials(u: np.ndarray, v: np.ndarray, degree: int) -> np.ndarray:
    return np.column_stack([u**i * v**j for i in range(degree + 1) for j in range(degree + 1 - i)])


def off_grid_corners(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners that do not lie on the smooth grid through the others.

    A polynomial map from grid indices to pixels (cubic for 30 corners or more, quadratic from 12:
    perspective and lens distortion are smooth at the scale of a board) is fitted to all corners,
    then refitted without the worst one while it is further than ``max(OFF_GRID_PX,
    OFF_GRID_FRACTION x spacing)`` from the fit. Glare and shadow edges move single corners by
    several pixels; good corners stay within a few tenths.

    Parameters
    ----------
    grid : ndarray, shape (ny, nx, 2)

    Returns
    -------
    indices : ndarray of int
        Flat indices ``row * nx + col`` of the corners off the grid (empty when all fit).
    residuals_px : ndarray, shape (nx*ny,)
        Each corner's distance from the final fit.
    """
    ny, nx = grid.shape[:2]
    n = nx * ny
    degree = 3 if n >= 30 else 2 if n >= 12 else 0
    pts = grid.reshape(-1, 2)
    if degree == 0:
        return np.zeros(0, int), np.zeros(n)
    spacing = float(np.median(np.concatenate([np.linalg.norm(np.diff(grid, axis=1), axis=2).ravel(),
                                              np.linalg.norm(np.diff(grid, axis=0), axis=2).ravel()])))
    limit = max(OFF_GRID_PX, OFF_GRID_FRACTION * spacing)
    cols, rows = np.meshgrid(np.arange(nx), np.arange(ny))
    u = (cols.ravel() - (nx - 1) / 2) / max(nx - 1, 1)
    v = (rows.ravel() - (ny - 1) / 2) / max(ny - 1, 1)
    basis = _monomials(u, v, degree)
    keep = np.ones(n, bool)
    for _ in range(n // 4):
        coef, *_ = np.linalg.lstsq(basis[keep], pts[keep], rcond=None)
        residuals = np.linalg.norm(basis @ coef - pts, axis=1)
        worst = int(np.argmax(np.where(keep, residuals, -1.0)))
        if residuals[worst] <= limit or keep.sum() <= basis.shape[1] + 4:
            break
        keep[worst] = False
    return np.nonzero(np.greater(residuals, limit))[0], residuals


def _refine(gray: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """``cornerSubPix`` with a half-window of 0.4 x the smallest corner spacing; grid ``(ny, nx, 2)``."""
    spacing = min(np.linalg.norm(np.diff(grid, axis=1), axis=2).min(), np.linalg.norm(np.diff(grid, axis=0), axis=2).min())
    half = int(np.clip(np.floor(WINDOW_FRACTION * spacing), WINDOW_MIN, WINDOW_MAX))
    pts = grid.reshape(-1, 1, 2).astype(np.float32)
    refined = cv2.cornerSubPix(gray, pts, (half, half), (-1, -1), SUBPIX_CRITERIA)
    return refined.reshape(grid.shape).astype(np.float64)


def detect_board(image: np.ndarray, board: BoardGeometry | tuple[int, int] | str, *, refine: bool = True, check_outside: bool = True,
                 search: str = "full", what: str = "image") -> Detection:
    """Find the board's inner corners in one image and put them in canonical order.

    Parameters
    ----------
    image : ndarray, shape (h, w) or (h, w, 3)
        Grey or BGR image (uint8; uint16 is scaled down).
    board : BoardGeometry or (nx, ny) or "NXxNY"
    refine : bool
        Sub-pixel refinement (``cornerSubPix``).
    check_outside : bool
        Refuse grids that are part of a larger board.
    search : {"full", "fast"}
        ``"full"``: every stage of :func:`find_grid` before the board is declared missing (finds
        it wherever OpenCV's default ``findChessboardCorners`` does; slow when there is none);
        ``"fast"``: the region search only (a live preview).
    what : str
        Name of the image in messages ("left image", ...).

    Returns
    -------
    Detection

    Raises
    ------
    BoardNotFound
    FrameError
    """
    board = as_board(board)
    gray = _gray_u8(image, what)
    nx, ny = board.corners
    result = find_grid(gray, (nx, ny), search)
    corners = refuse_missing_grid(result, gray, (nx, ny), what)
    stage = result.stage
    grid = corners.reshape(ny, nx, 2)
    if refine:
        grid = _refine(gray, grid)
    candidates = canonical_orderings(grid)
    if not candidates:
        raise BoardNotFound(f"the corner grid in the {what} is degenerate (no consistent ordering)")
    scores = [pattern_score(c, gray) for c in candidates]
    contrast = max(abs(s) for s in scores)
    if not np.isfinite(contrast) or contrast < MIN_CONTRAST:
        raise BoardNotFound(
            f"the board's squares in the {what} differ by only {contrast:.0f} grey levels: too dark, "
            f"overexposed or blurred; adjust exposure or lighting"
        )
    distinguishable = (nx + ny) % 2 == 1
    if distinguishable:
        best = int(np.argmax(scores))
        ambiguous = False
    else:  # pattern symmetric under a half turn: x axis towards the image's right
        dirs = [np.mean(c[:, -1] - c[:, 0], axis=0) for c in candidates]
        best = int(np.argmax([d[0] / (np.linalg.norm(d) + 1e-12) for d in dirs]))
        ambiguous = True
    chosen = candidates[best]
    if check_outside:
        alternation = outer_alternation(chosen, gray, contrast)
        if alternation > MAX_OUTER_ALTERNATION:
            raise BoardNotFound(
                f"the {nx}x{ny} corners found in the {what} are part of a larger checkerboard: "
                f"give the board's full inner-corner count (--board)"
            )
    others = tuple(c.reshape(-1, 2) for k, c in enumerate(candidates) if k != best)
    h, w = gray.shape
    off, residuals = off_grid_corners(chosen)
    return Detection(chosen.reshape(-1, 2), board, (w, h), ambiguous, float(scores[best]), others, stage,
                     tuple(int(i) for i in off), float(residuals.max()) if len(off) else 0.0)


def board_pose_from_corners(corners_px: npt.ArrayLike, board: BoardGeometry | tuple[int, int] | str, camera_matrix: npt.ArrayLike,
                            dist_coeffs: npt.ArrayLike | None = None) -> tuple[np.ndarray, float]:
    """Board pose ``target2cam`` (mm) of a canonical detection with ``cv2.solvePnP`` (monocular).

    Parameters
    ----------
    corners_px : array-like, shape (nx*ny, 2)
    board : BoardGeometry with square_mm
    camera_matrix : array-like, shape (3, 3)
    dist_coeffs : array-like, optional

    Returns
    -------
    target2cam : ndarray, shape (4, 4)
    reprojection_rms_px : float
    """
    board = as_board(board)
    if board.square_mm is None:
        raise CameraError("the square size is needed for a board pose")
    solved = pnp_pose(board_corners(board.corners, board.square_mm), corners_px, camera_matrix,
                      np.zeros(5) if dist_coeffs is None else dist_coeffs, refine=True)
    if solved is None:
        raise BoardNotFound("solvePnP found no board pose for these corners")
    return solved


def plane_fit(points_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares plane of points ``(n, 3)``: ``(centroid, unit normal, signed distances)``."""
    centroid = points_mm.mean(axis=0)
    _, _, vt = np.linalg.svd(points_mm - centroid, full_matrices=False)
    normal = vt[2]
    return centroid, normal, (points_mm - centroid) @ normal


def board_quality(points_mm: np.ndarray, board: BoardGeometry, row_disagreement_px: np.ndarray | None = None) -> dict:
    """Per-posture quality figures of a triangulated board.

    Returns
    -------
    dict
        ``corners`` (count), ``row_disagreement_rms_px`` / ``_max_px`` (rectified rows, left minus right),
        ``plane_rms_mm`` / ``plane_max_mm`` (distance of the corners from their least-squares plane),
        ``distance_mm`` (camera origin to the board centre), ``tilt_deg`` (board normal against the
        optical axis; 0 = facing the camera), ``square_mm_measured`` (mean neighbour spacing).
    """
    nx, ny = board.corners
    centroid, normal, dist = plane_fit(points_mm)
    if normal[2] > 0:
        normal = -normal  # towards the camera
    grid = points_mm.reshape(ny, nx, 3)
    spacing = np.concatenate([np.linalg.norm(np.diff(grid, axis=1), axis=2).ravel(),
                              np.linalg.norm(np.diff(grid, axis=0), axis=2).ravel()])
    out = {
        "corners": int(len(points_mm)),
        "plane_rms_mm": float(np.sqrt(np.mean(dist**2))),
        "plane_max_mm": float(np.abs(dist).max()),
        "distance_mm": float(np.linalg.norm(centroid)),
        "tilt_deg": float(np.degrees(np.arccos(np.clip(-normal[2], -1.0, 1.0)))),
        "square_mm_measured": float(spacing.mean()),
    }
    if row_disagreement_px is not None:
        out["row_disagreement_rms_px"] = float(np.sqrt(np.mean(row_disagreement_px**2)))
        out["row_disagreement_max_px"] = float(np.abs(row_disagreement_px).max())
    return out


@dataclass(frozen=True)
class BoardObservation:
    """The board seen by the stereo pair at one posture.

    Attributes
    ----------
    points_mm : ndarray, shape (nx*ny, 3)
        Corners in the camera frame (camera 1 = left), target index order, mm.
    left, right : Detection, or CharucoDetection
        The two detections, consistently ordered (a board seen by id, :class:`~.charuco.PartialObservation`:
        ChArUco detections of the corners both images saw).
    quality : dict
        :func:`board_quality` figures plus ``corners_left``, ``corners_right``, ``orientation``.
    """

    points_mm: np.ndarray
    left: Detection | CharucoDetection
    right: Detection | CharucoDetection
    quality: dict


def observe_board(left: np.ndarray, right: np.ndarray, model: StereoModel, board: BoardGeometry | tuple[int, int] | str, *,
                  max_row_disagreement_px: float = MAX_ROW_DISAGREEMENT_PX) -> BoardObservation:
    """Detect the board in a left/right pair, order both detections consistently and triangulate.

    Parameters
    ----------
    left, right : ndarray
        Grey or BGR images of camera 1 (left) and camera 2 (right), raw (not rectified).
    model : StereoModel
    board : BoardGeometry or (nx, ny) or "NXxNY"

    Raises
    ------
    FrameError
        Image sizes differ from each other or from the model.
    BoardNotFound
        The board is not (completely) seen in one of the images, or some of its corners are off its
        grid (glare, a shadow edge: :attr:`Detection.off_grid`).
    StereoMismatch
        The two detections do not agree with the stereo model.
    """
    board = as_board(board)
    for name, image in (("left", left), ("right", right)):
        if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or image.size == 0:
            raise FrameError(f"the {name} image is empty or not an image")
    if left.shape[:2] != right.shape[:2]:
        raise FrameError(
            f"left image is {left.shape[1]}x{left.shape[0]} but right image is {right.shape[1]}x{right.shape[0]}: "
            f"give the two images of one stereo frame"
        )
    size = (left.shape[1], left.shape[0])
    if size != tuple(model.image_size):
        raise FrameError(
            f"images are {size[0]}x{size[1]} but the stereo model is for {model.image_size[0]}x{model.image_size[1]}: "
            f"use the stereo file of this camera and resolution"
        )
    if getattr(board, "kind", "checkerboard") != "checkerboard":  # ChArUco or circles: by id (issue 37)
        from .charuco import observe_partial  # noqa: PLC0415

        return observe_partial(left, right, model, board, max_row_disagreement_px=max_row_disagreement_px)
    det_left = detect_board(left, board, what="left image")
    det_right = detect_board(right, board, what="right image")
    for det, name in ((det_left, "left image"), (det_right, "right image")):
        if det.off_grid:
            raise BoardNotFound(det.off_grid_message(name))
    # Make the right ordering agree with the left one: among the right image's orderings with the
    # correct handedness, corresponding corners share rectified rows and have positive disparity.
    options = [det_right.corners_px, *det_right.alternatives]
    best, best_rms = None, np.inf
    for k, corners in enumerate(options):
        rl, rr = model.rectify_points(det_left.corners_px, corners)
        rms = float(np.sqrt(np.mean((rl[:, 1] - rr[:, 1]) ** 2)))
        if np.all(rl[:, 0] - rr[:, 0] > 0) and rms < best_rms:
            best, best_rms = k, rms
    if best is None:
        raise StereoMismatch(
            "no corner in the right image lies left of its match in the left image: are the left and right images swapped?"
        )
    if best_rms > max_row_disagreement_px:
        raise StereoMismatch(
            f"left and right corners disagree by {best_rms:.1f} px (RMS) in rectified rows: the stereo model does "
            f"not fit this camera, or the images are not one stereo frame"
        )
    if best != 0 and not (det_left.ambiguous or det_right.ambiguous):
        raise StereoMismatch(
            "the printed pattern gives different board orientations in the left and right images: check lighting "
            "(glare on the board)"
        )
    right_corners = options[best]
    if best != 0:
        rest = tuple(o for k, o in enumerate(options) if k != best)
        det_right = Detection(right_corners, board, det_right.image_size, det_right.ambiguous,
                              det_right.pattern_score, rest, det_right.stage)
    tri = model.triangulate(det_left.corners_px, right_corners)
    quality = board_quality(tri.points_mm, board, tri.row_disagreement_px)
    quality["corners_left"] = int(len(det_left.corners_px))
    quality["corners_right"] = int(len(right_corners))
    quality["orientation"] = "ambiguous" if det_left.ambiguous else "pattern"
    return BoardObservation(tri.points_mm, det_left, det_right, quality)
