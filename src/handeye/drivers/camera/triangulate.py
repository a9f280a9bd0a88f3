"""Library entry of ``handeye triangulate``: a stereo frame in, the board corners in millimetres out.

Inputs: a left/right image pair (arrays or image files, e.g. PNG) or one raw Bumblebee XB3 frame
(3-sensor RGB8 layout, wide pair). Output: :class:`TriangulationResult` with the corners in the
camera frame (camera 1 = left) in target index order, the posture's quality figures and
``runtime_s``.

``runtime_s`` covers decoding (PNG decompression, or de-interleaving and debayering the raw frame),
detection in both images, ordering and triangulation. It excludes reading the bytes from disk and
loading the stereo model, whose rectification is computed once per model before the clock starts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import time
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from ...geometry import STATION_BOARD, BoardGeometry
from ...base import read_file_bytes
from ...geometry import SQUARE_TOLERANCE
from .checkerboard import as_board, observe_board
from .decode import decode_xb3_frame, frame_bytes
from .errors import FrameError, FrameUsageError, SquareSizeMismatch
from .stereo import StereoModel, load_stereo_model, nominal_xb3_model

if TYPE_CHECKING:
    import os

__all__ = [
    "TriangulationResult",
    "read_image_bytes",
    "decode_image",
    "triangulate_images",
    "triangulate_xb3_frame",
    "triangulate_files",
]


@dataclass
class TriangulationResult:
    """Board corners of one stereo frame.

    Attributes
    ----------
    points_mm : ndarray, shape (nx*ny, 3)
        Corners in the camera frame (mm), index ``row * nx + col`` of the target frame.
    quality : dict
        Corner counts, rectified row disagreement (px), plane-fit residual (mm), distance (mm),
        tilt (deg), measured square size (mm) and its error against the declared one.
    runtime_s : float
        Decode + detect + triangulate (see the module docstring).
    board : BoardGeometry
    stereo : str
        Name of the stereo model used.
    source : str
        ``"images"`` or ``"xb3-raw"``.
    left_px, right_px : ndarray, shape (nx*ny, 2)
        The corners in the two (raw) images.
    """

    points_mm: np.ndarray
    quality: dict
    runtime_s: float
    board: BoardGeometry
    stereo: str
    source: str
    left_px: np.ndarray | None = field(repr=False, default=None)
    right_px: np.ndarray | None = field(repr=False, default=None)
    #: Target index of each row of ``points_mm`` for a board seen by id (ChArUco, circles); None: a checkerboard.
    corner_ids: np.ndarray | None = field(repr=False, default=None)

    def to_json(self) -> dict:
        """The JSON of ``handeye triangulate --json`` (conventions.md keys first)."""
        board: dict[str, object] = {"corners": [int(c) for c in self.board.corners]}
        if self.board.square_mm is not None:
            board["square_mm"] = float(self.board.square_mm)
        if self.corner_ids is not None:
            from ...geometry import target_to_dict  # noqa: PLC0415

            board = target_to_dict(self.board)
        ids = {} if self.corner_ids is None else {"corner_ids": [int(i) for i in self.corner_ids]}
        return {
            "points_mm": [[round(float(v), 6) for v in p] for p in self.points_mm],
            **ids,
            "runtime_s": float(self.runtime_s),
            "quality": self.quality,
            "board": board,
            "stereo": self.stereo,
            "source": self.source,
        }


#: Largest image or raw frame file read (an XB3 raw frame is 3.7 MB, a 16-bit TIFF pair some tens).
MAX_IMAGE_BYTES = 512 * 1024 * 1024


def read_image_bytes(path: str | os.PathLike[str]) -> bytes:
    """The bytes of an image or frame file; :class:`FrameError` naming the file when it cannot be read."""
    path = Path(path)
    data = read_file_bytes(path, "image", FrameError, missing=f"file not found: {path}", max_bytes=MAX_IMAGE_BYTES)
    if not data:
        raise FrameError(f"{path} is empty")
    return data


def decode_image(data: bytes, name: str = "image") -> np.ndarray:
    """Decode image file bytes (PNG, TIFF, ...) to a grey uint8 array (16-bit images are scaled)."""
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise FrameError(f"{name} is not an image OpenCV can read (PNG, TIFF, BMP, JPEG)")
    image = np.asarray(image)  # imdecode gives an ndarray (its stub says MatLike, which may be a UMat)
    if image.dtype == np.uint16:
        image = (image.view(np.uint16) >> 8).astype(np.uint8)
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    return image


def _prepare(model: StereoModel | None, board, square_mm) -> tuple[StereoModel, BoardGeometry]:
    model = model or nominal_xb3_model()
    _ = model.rectification  # computed once per model, before the clock starts
    return model, as_board(board, square_mm)


def _result(obs, board: BoardGeometry, model: StereoModel, source: str, start: float) -> TriangulationResult:
    runtime = time.perf_counter() - start
    quality = dict(obs.quality)
    if board.square_mm is not None:
        quality["square_error_mm"] = quality["square_mm_measured"] - float(board.square_mm)
        if abs(quality["square_error_mm"]) > SQUARE_TOLERANCE * board.square_mm:
            raise SquareSizeMismatch(
                f"the board's corners measure {quality['square_mm_measured']:.4g} mm apart but the square size given is "
                f"{board.square_mm:g} mm (more than {100 * SQUARE_TOLERANCE:.0f} % off): check the square size "
                "(--square-mm, target.square_mm) and that the stereo model's T is in mm")
    return TriangulationResult(obs.points_mm, quality, runtime, board, model.name, source,
                               obs.left.corners_px, obs.right.corners_px, getattr(obs, "corner_ids", None))


def triangulate_images(left: np.ndarray, right: np.ndarray, board: BoardGeometry | tuple[int, int] | str = STATION_BOARD.corners, square_mm: float | None = None,
                       model: StereoModel | None = None) -> TriangulationResult:
    """Corners in mm from a left/right image pair already in memory (grey or BGR arrays).

    Raises
    ------
    FrameError, BoardNotFound, StereoMismatch, SquareSizeMismatch
    """
    model, board = _prepare(model, board, square_mm)
    start = time.perf_counter()
    obs = observe_board(left, right, model, board)
    return _result(obs, board, model, "images", start)


def triangulate_xb3_frame(buffer: bytes | bytearray | memoryview | np.ndarray, board: BoardGeometry | tuple[int, int] | str = STATION_BOARD.corners, square_mm: float | None = None, model: StereoModel | None = None,
                          *, colour: bool = True, width: int | None = None,
                          height: int | None = None) -> TriangulationResult:
    """Corners in mm from one raw XB3 frame (3-sensor RGB8 layout; the wide left-right pair).

    Parameters
    ----------
    buffer : bytes-like or ndarray of uint8
        ``width * height * 3`` bytes; per pixel byte 0 = right, 1 = centre, 2 = left.
    colour : bool
        GBRG mosaics (colour head) or grey planes (mono head).
    width, height : int, optional
        Frame size; defaults to the stereo model's image size.

    Raises
    ------
    FrameError, BoardNotFound, StereoMismatch, SquareSizeMismatch
    """
    model, board = _prepare(model, board, square_mm)
    width = width or model.image_size[0]
    height = height or model.image_size[1]
    start = time.perf_counter()
    frame = decode_xb3_frame(buffer, "rgb8", width, height, colour=colour, output="gray", centre=False)
    obs = observe_board(frame.left, frame.right, model, board)
    return _result(obs, board, model, "xb3-raw", start)


def triangulate_files(*, left: str | os.PathLike[str] | None = None, right: str | os.PathLike[str] | None = None,
                      xb3_raw: str | os.PathLike[str] | None = None, stereo: str | os.PathLike[str] | None = None,
                      board: BoardGeometry | tuple[int, int] | str = STATION_BOARD.corners, square_mm: float | None = STATION_BOARD.square_mm,
                      colour: bool = True) -> TriangulationResult:
    """:func:`triangulate_images` or :func:`triangulate_xb3_frame` on files.

    Parameters
    ----------
    left, right : path, optional
        The image pair (give both, or ``xb3_raw``).
    xb3_raw : path, optional
        One raw XB3 frame (3-sensor RGB8 layout).
    stereo : path, optional
        OpenCV FileStorage stereo model; ``None`` = the nominal XB3 wide pair.
    board : str or tuple or BoardGeometry
    square_mm : float, optional

    Raises
    ------
    FrameError, StereoModelError, BoardNotFound, StereoMismatch, SquareSizeMismatch
    """
    if (xb3_raw is None) == (left is None and right is None):
        raise FrameUsageError("give either --left and --right images or one --xb3-raw frame")
    if xb3_raw is None and (left is None or right is None):
        raise FrameUsageError("give both --left and --right (or one --xb3-raw frame)")
    model = load_stereo_model(stereo) if stereo else nominal_xb3_model()
    if xb3_raw is not None:
        data = read_image_bytes(xb3_raw)
        w, h = model.image_size
        if len(data) != frame_bytes("rgb8", w, h):
            raise FrameError(
                f"{xb3_raw}: {len(data)} bytes, but a {w}x{h} 3-sensor RGB8 XB3 frame has {frame_bytes('rgb8', w, h)}"
                f"{' (truncated?)' if len(data) < frame_bytes('rgb8', w, h) else ''}; the stereo model sets the frame size"
            )
        return triangulate_xb3_frame(data, board, square_mm, model, colour=colour)
    assert left is not None and right is not None  # refused above without both
    left_bytes, right_bytes = read_image_bytes(left), read_image_bytes(right)
    model, geometry = _prepare(model, board, square_mm)
    start = time.perf_counter()
    left_image = decode_image(left_bytes, str(left))
    right_image = decode_image(right_bytes, str(right))
    obs = observe_board(left_image, right_image, model, geometry)
    return _result(obs, geometry, model, "images", start)

