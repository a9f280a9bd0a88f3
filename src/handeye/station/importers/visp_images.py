"""Board poses measured from images, for ViSP app folders that hold robot poses and images only.

ViSP's hand-eye app folder (``apps/calibration/hand-eye``) keeps ``<robot>_pose_rPe_<i>.yaml``,
``<robot>_image-<i>.png``, the intrinsics ``<robot>_camera.xml`` (vpXmlParserCamera) and
``chessboard-data.txt``; the board poses ``pose_cPo_<i>.yaml`` are computed from the images by
``visp-compute-chessboard-poses``. This module does that step with OpenCV: chessboard corners
(``findChessboardCorners`` + sub-pixel refinement), then ``solvePnP`` with the ViSP intrinsics.

The target frame follows the conventions: origin at the first inner corner, x along the rows of
``corners[0]`` corners, z into the board; for an even x odd square count the corner order is turned
180 deg when needed so that x runs from the edge whose corner squares are black to the edge whose
corner squares are white (OpenCV alone may return either order).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...geometry import BoardGeometry, board_corners
from ...base import SessionError
from ...base import check_regular_file, read_file_bytes, read_text_file
from ...calibration import MAX_CORNERS, MAX_LENGTH_MM

__all__ = ["IMAGE_PATTERN", "CameraIntrinsics", "read_visp_camera", "read_chessboard_data", "find_images",
           "canonical_corner_order", "measure_board_pose", "measure_tag_pose", "tag_corners"]

#: ``franka_image-3.png``: the image of posture 3.
IMAGE_PATTERN = re.compile(r"image-(\d+)\.(?:png|jpe?g|bmp|pgm|ppm|tiff?)$", re.IGNORECASE)


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics (pixels) with ViSP's one radial coefficient ``kud`` (= OpenCV ``k1``)."""

    px: float
    py: float
    u0: float
    v0: float
    kud: float = 0.0

    def matrix(self) -> np.ndarray:
        return np.array([[self.px, 0.0, self.u0], [0.0, self.py, self.v0], [0.0, 0.0, 1.0]])

    def distortion(self) -> np.ndarray:
        return np.array([self.kud, 0.0, 0.0, 0.0, 0.0])


def read_visp_camera(path) -> CameraIntrinsics:
    """Intrinsics from a vpXmlParserCamera file (the first camera's ``perspectiveProj*`` model).

    Raises
    ------
    SessionError
    """
    data = read_file_bytes(path, "camera file", SessionError, missing=f"{path}: no such file")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        line = exc.position[0] if getattr(exc, "position", None) else "?"
        raise SessionError(f"{path}: not valid XML (line {line})") from None
    model = root.find("./camera/model")
    if model is None:
        raise SessionError(f"{path}: no <camera><model> (a ViSP camera parameter file is expected)")
    values = {}
    for key in ("px", "py", "u0", "v0", "kud"):
        node = model.find(key)
        if node is None or node.text is None:
            if key == "kud":
                values[key] = 0.0
                continue
            raise SessionError(f"{path}: <model> lacks <{key}>")
        try:
            values[key] = float(node.text)
        except ValueError:
            raise SessionError(f"{path}: <{key}> is not a number ({node.text.strip()!r})") from None
    if not (values["px"] > 0 and values["py"] > 0):
        raise SessionError(f"{path}: px and py must be positive")
    return CameraIntrinsics(**values)


def read_chessboard_data(path) -> BoardGeometry:
    """``chessboard-data.txt`` of ViSP's app: ``9 x 6`` inner corners and ``square size: 0.0236 m``."""
    text = read_text_file(path, "chessboard file", SessionError, missing=f"{path}: no such file")
    corners = re.search(r"(\d{1,4})\s*[xX]\s*(\d{1,4})", text)
    square = re.search(r"square\s*size\s*:?\s*([0-9.eE+-]+)\s*(mm|m)?", text, re.IGNORECASE)
    expected = f"{path}: expected '<nx> x <ny>' and 'square size: <value> m'; pass --board and --square-mm"
    if not corners or not square:
        raise SessionError(expected)
    nx, ny = int(corners.group(1)), int(corners.group(2))
    try:
        size = float(square.group(1)) * (1000.0 if (square.group(2) or "m").lower() == "m" else 1.0)
    except ValueError:
        raise SessionError(expected) from None
    if not (2 <= min(nx, ny) and max(nx, ny) <= MAX_CORNERS and 0 < size <= MAX_LENGTH_MM):
        raise SessionError(f"{path}: a board of {nx} x {ny} inner corners with {size:g} mm squares is not plausible "
                           f"(2..{MAX_CORNERS} corners, squares within 10 km); pass --board and --square-mm")
    return BoardGeometry((max(nx, ny), min(nx, ny)), size)


def read_apriltag_data(path) -> float:
    """The tag's side in mm from ``apriltag-data.txt`` of ViSP's app (written beside the images).

    The line that names the size (``size``, ``tag size``, ``tag_size``: a number and an optional unit,
    metres when none is written, as ViSP's apps take ``--tag-size`` in metres) gives it; a family other
    than 36h11, when the file names one, is refused (only 36h11 is detected).
    """
    text = read_text_file(path, "AprilTag file", SessionError, missing=f"{path}: no such file")
    size = re.search(r"size\s*[:=]?\s*([0-9.eE+-]+)\s*(mm|cm|m)?\b", text, re.IGNORECASE)
    expected = f"{path}: expected a line 'size: <value> m' (the tag's black square); pass --tag-mm"
    if not size:
        raise SessionError(expected)
    try:
        value = float(size.group(1)) * {"m": 1000.0, "cm": 10.0, "mm": 1.0}[(size.group(2) or "m").lower()]
    except ValueError:
        raise SessionError(expected) from None
    family = re.search(r"(\d{2}h\d{1,2})", text)
    if family and family.group(1) != "36h11":
        raise SessionError(f"{path}: an AprilTag of family {family.group(1)}; only 36h11 is detected")
    if not 0 < value <= MAX_LENGTH_MM:
        raise SessionError(f"{path}: a tag of {value:g} mm is not plausible; pass --tag-mm")
    return value


def find_images(files) -> dict:
    """``{number: path}`` of the posture images among ``files``."""
    out = {}
    for p in files:
        found = IMAGE_PATTERN.search(Path(p).name)
        if found:
            out[int(found.group(1))] = Path(p)
    return out


def _mean_patch(image, point, radius: int) -> float | None:
    x, y = int(round(point[0])), int(round(point[1]))
    h, w = image.shape[:2]
    if not (radius <= x < w - radius and radius <= y < h - radius):
        return None
    return float(image[y - radius:y + radius + 1, x - radius:x + radius + 1].mean())


def canonical_corner_order(image, corners, pattern) -> tuple[np.ndarray, bool]:
    """Turn the detected order by 180 deg when the corner square beyond the first corner is white.

    Parameters
    ----------
    image : ndarray, shape (h, w)
        Grey image.
    corners : ndarray, shape (nx * ny, 2)
        Detected corners, rows of ``nx``.
    pattern : tuple of int
        ``(nx, ny)`` inner corners.

    Returns
    -------
    corners : ndarray, shape (nx * ny, 2)
    turned : bool
        Whether the order was reversed. Boards whose pattern is 180-deg symmetric, or whose outer
        squares are out of the image, are left as detected.
    """
    nx, ny = pattern
    grid = np.asarray(corners, dtype=float).reshape(ny, nx, 2)
    if nx % 2 == ny % 2:  # odd x odd squares (even corners both ways or odd both ways): symmetric
        return grid.reshape(-1, 2), False
    # Centres of the board's corner squares beyond the first and the last inner corner: on a board
    # that is not 180-deg symmetric they have opposite colours; the first must be the black one
    # (for an odd corners[0] this is the conventions' "x from the black-cornered edge").
    first = grid[0, 0] + 0.5 * (grid[0, 0] - grid[1, 1])
    last = grid[-1, -1] + 0.5 * (grid[-1, -1] - grid[-2, -2])
    radius = max(1, int(0.15 * np.linalg.norm(grid[0, 1] - grid[0, 0])))
    a, b = _mean_patch(image, first, radius), _mean_patch(image, last, radius)
    if a is None or b is None or a <= b:
        return grid.reshape(-1, 2), False
    return grid[::-1, ::-1].reshape(-1, 2), True


def _read_gray(image_path):
    """The image as 8-bit grey (ValueError: not a regular file, or not an image OpenCV reads)."""
    import cv2

    check_regular_file(image_path, "image", ValueError, max_bytes=None)
    image = cv2.imread(str(image_path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise ValueError("cannot read the image")
    return image


def _pnp(objects, pixels, camera, flags) -> tuple[np.ndarray, float]:
    """Pose (4x4, mm) and reprojection RMS (px) with the ViSP intrinsics (ValueError: PnP failed)."""
    from ...drivers import pnp_pose

    solved = pnp_pose(objects, pixels, camera.matrix(), camera.distortion(), flags)
    if solved is None:
        raise ValueError("solvePnP failed")
    return solved


def measure_board_pose(image_path, board: BoardGeometry, camera: CameraIntrinsics) -> dict:
    """Board pose ``target_in_camera`` (mm) from one image.

    Returns
    -------
    dict
        ``pose`` (4x4, mm), ``rms_px`` (reprojection RMS), ``turned`` (corner order reversed).

    Raises
    ------
    ValueError
        Unreadable image, or the board is not found.
    """
    import cv2

    image = _read_gray(image_path)
    pattern = tuple(int(c) for c in board.corners)
    found, corners = cv2.findChessboardCorners(image, pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        raise ValueError(f"no {pattern[0]}x{pattern[1]} chessboard found")
    corners = cv2.cornerSubPix(image, corners, (5, 5), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)).reshape(-1, 2)
    corners, turned = canonical_corner_order(image, corners, pattern)
    if board.square_mm is None:
        raise ValueError(f"the {pattern[0]}x{pattern[1]} board's square size is unknown")
    pose, rms = _pnp(board_corners(pattern, board.square_mm), corners, camera, cv2.SOLVEPNP_ITERATIVE)
    return {"pose": pose, "rms_px": rms, "turned": bool(turned)}


def tag_corners(size_mm: float) -> np.ndarray:
    """The four outer corners of a square tag in its frame, in the order OpenCV's ArUco detector
    returns them (clockwise from the top-left corner as printed).

    The tag frame follows the conventions' target: origin at the tag centre, x to the right and y
    down as printed, z = x x y into the tag (away from a camera that sees it).
    """
    h = size_mm / 2.0
    return np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])


def measure_tag_pose(image_path, size_mm: float, camera: CameraIntrinsics, tag_id: int | None = None) -> dict:
    """Pose of one AprilTag 36h11 (``target_in_camera``, mm) in an image, as ViSP's
    ``visp-compute-apriltag-poses`` measures it (one tag per image; ``size_mm`` is the black square's side).

    Returns
    -------
    dict
        ``pose`` (4x4, mm), ``rms_px`` (reprojection RMS of the four corners), ``id`` (tag number).

    Raises
    ------
    ValueError
        Unreadable image, no tag, or several tags (and ``tag_id`` does not pick one).
    """
    import cv2

    image = _read_gray(image_path)
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_APRILTAG
    corners, ids, _ = cv2.aruco.ArucoDetector(dictionary, parameters).detectMarkers(image)
    if ids is None or len(ids) == 0:
        raise ValueError("no AprilTag 36h11 found")
    found = [(int(i), c.reshape(4, 2)) for i, c in zip(ids.ravel(), corners)]
    if tag_id is not None:
        found = [f for f in found if f[0] == tag_id]
    if len(found) != 1:
        raise ValueError(f"{len(found)} AprilTags found (ids {', '.join(str(f[0]) for f in found)}); one is needed")
    number, points = found[0]
    pose, rms = _pnp(tag_corners(size_mm), points, camera, cv2.SOLVEPNP_IPPE)
    return {"pose": pose, "rms_px": rms, "id": number}
