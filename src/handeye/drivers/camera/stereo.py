"""Stereo model of the head: intrinsics, extrinsics, rectification and triangulation to millimetres.

File format (conventions.md): an OpenCV FileStorage file (YAML or XML) with ``image_width``,
``image_height``, ``K1``, ``D1``, ``K2``, ``D2``, ``R``, ``T``, in OpenCV ``stereoCalibrate``
meaning: camera 1 is the left camera (the ``camera`` frame of the project), a point ``X1`` in
camera 1 is ``R @ X1 + T`` in camera 2 (the right camera), ``T`` in millimetres. Optional ``K3``,
``D3``, ``R3``, ``T3`` describe the centre sensor of a 3-sensor head the same way (used by the mock
camera; a missing centre is put half-way between left and right with camera 1's intrinsics).

The nominal model (:func:`nominal_xb3_model`) is a Bumblebee XB3 wide pair (3.8 mm lenses,
1280x960) as Triclops exports it rectified: f = 983 px, (cx, cy) = (643.6, 493.4), no distortion,
baseline 239.98 mm along +x (the right camera sits at x = +239.98 mm in the left camera's frame,
so ``T = (-239.98, 0, 0)``). It is a good start for a factory-rectified head; a head calibrated
with OpenCV ``stereoCalibrate`` should use its own file.

Triangulation works on corner positions, not on resampled images: the points of both images are
rectified with ``undistortPointsIter`` (R1/P1, R2/P2 of ``stereoRectify``), the depth comes from
the disparity through ``Q`` and the vertical coordinate from the mean rectified row; the result is
rotated back from the rectified frame to camera 1. The rectification itself (``stereoRectify``) is
computed once per model, and so are the pixel maps of :meth:`StereoModel.rectification_maps`
(used to show or save rectified images).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import cv2
import numpy as np

from ...base import read_text_file
from .errors import StereoMismatch, StereoModelError

if TYPE_CHECKING:
    import os

    import numpy.typing as npt

__all__ = [
    "NOMINAL_XB3",
    "Rectification",
    "StereoModel",
    "refuse_base64_filestorage",
    "Triangulation",
    "nominal_xb3_model",
    "load_stereo_model",
    "save_stereo_model",
]

#: Typical rectified values of a 3.8 mm XB3 wide pair at 1280x960 (see the module docstring).
NOMINAL_XB3 = {"width": 1280, "height": 960, "f_px": 983.0, "cx": 643.6, "cy": 493.4, "baseline_mm": 239.98}

_SUBPIXEL_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-12)


def _matrix(value, shape, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise StereoModelError(f"{what} is not a matrix of numbers") from None
    if arr.size != int(np.prod(shape)):
        raise StereoModelError(f"{what} must have {int(np.prod(shape))} values ({'x'.join(map(str, shape))}); got {arr.size}")
    arr = arr.reshape(shape)
    if not np.all(np.isfinite(arr)):
        raise StereoModelError(f"{what} holds NaN or inf")
    return arr


def _distortion(value, what: str) -> np.ndarray:
    if value is None:
        return np.zeros(5)
    arr = np.asarray(value, dtype=float).ravel()
    if arr.size not in (4, 5, 8, 12, 14):
        raise StereoModelError(f"{what} must hold 4, 5, 8, 12 or 14 OpenCV distortion coefficients; got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise StereoModelError(f"{what} holds NaN or inf")
    return arr


def _check_camera_matrix(k: np.ndarray, what: str) -> None:
    if k[0, 0] <= 0 or k[1, 1] <= 0 or k[2, 2] != 1 or k[1, 0] != 0 or k[2, 0] != 0 or k[2, 1] != 0:
        raise StereoModelError(f"{what} is not a camera matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")


def _check_rotation(r: np.ndarray, what: str) -> None:
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-5) or np.linalg.det(r) < 0:
        raise StereoModelError(f"{what} is not a rotation matrix (R @ R.T != I or det < 0)")


@dataclass(frozen=True)
class Rectification:
    """``cv2.stereoRectify`` output of a model (horizontal pairs).

    Attributes
    ----------
    R1, R2 : ndarray, shape (3, 3)
        Rotations from camera 1 (2) to its rectified frame.
    P1, P2 : ndarray, shape (3, 4)
        Rectified projection matrices (pixels, mm).
    Q : ndarray, shape (4, 4)
        Disparity-to-depth matrix: ``Q @ [x, y, d, 1]`` is the point in the rectified camera-1 frame.
    """

    R1: np.ndarray
    R2: np.ndarray
    P1: np.ndarray
    P2: np.ndarray
    Q: np.ndarray


@dataclass(frozen=True)
class Triangulation:
    """Triangulated points and how well the two images agree.

    Attributes
    ----------
    points_mm : ndarray, shape (n, 3)
        Points in the camera frame (camera 1, left), mm.
    rect_left, rect_right : ndarray, shape (n, 2)
        Rectified pixel coordinates of the points in both images.
    row_disagreement_px : ndarray, shape (n,)
        Rectified row of the left point minus that of the right point (zero for a perfect pair).
    disparity_px : ndarray, shape (n,)
    """

    points_mm: np.ndarray
    rect_left: np.ndarray
    rect_right: np.ndarray
    row_disagreement_px: np.ndarray
    disparity_px: np.ndarray


@dataclass(frozen=True, eq=False)
class StereoModel:
    """A calibrated stereo pair (camera 1 = left = the ``camera`` frame), optionally with the centre sensor.

    Attributes
    ----------
    image_size : tuple of int
        ``(width, height)`` in pixels.
    K1, K2 : ndarray, shape (3, 3)
        Camera matrices of the left and right cameras.
    D1, D2 : ndarray, shape (k,)
        OpenCV distortion coefficients (k1, k2, p1, p2[, k3, ...]).
    R : ndarray, shape (3, 3)
    T : ndarray, shape (3,)
        ``X2 = R @ X1 + T`` (mm).
    K3, D3, R3, T3 : optional
        The centre sensor, ``X3 = R3 @ X1 + T3``.
    name : str
        Where the model came from (file path or "nominal XB3 wide pair").
    """

    image_size: tuple
    K1: np.ndarray
    D1: np.ndarray
    K2: np.ndarray
    D2: np.ndarray
    R: np.ndarray
    T: np.ndarray
    K3: np.ndarray | None = None
    D3: np.ndarray | None = None
    R3: np.ndarray | None = None
    T3: np.ndarray | None = None
    name: str = ""
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        w, h = (int(v) for v in self.image_size)
        if w <= 0 or h <= 0:
            raise StereoModelError(f"image size must be positive; got {w}x{h}")
        object.__setattr__(self, "image_size", (w, h))
        for key, shape in (("K1", (3, 3)), ("K2", (3, 3)), ("R", (3, 3)), ("T", (3,))):
            object.__setattr__(self, key, _matrix(getattr(self, key), shape, key))
        for key in ("D1", "D2"):
            object.__setattr__(self, key, _distortion(getattr(self, key), key))
        _check_camera_matrix(self.K1, "K1")
        _check_camera_matrix(self.K2, "K2")
        _check_rotation(self.R, "R")
        if np.linalg.norm(self.T) < 1e-6:
            raise StereoModelError("T is zero: the two cameras cannot sit at the same place")
        if abs(self.T[0]) <= abs(self.T[1]):
            raise StereoModelError(f"T = {self.T.tolist()} mm describes a vertical pair; only side-by-side heads are supported")
        if self.T[0] >= 0:
            raise StereoModelError(
                f"T[0] = {self.T[0]:g} mm: camera 2 must be the RIGHT camera (T[0] < 0 in OpenCV's convention); "
                f"swap the cameras of the calibration"
            )
        if self.K3 is not None:
            object.__setattr__(self, "K3", _matrix(self.K3, (3, 3), "K3"))
            object.__setattr__(self, "D3", _distortion(self.D3, "D3"))
            r3 = _matrix(self.R3 if self.R3 is not None else np.eye(3), (3, 3), "R3")
            object.__setattr__(self, "R3", r3)
            object.__setattr__(self, "T3", _matrix(self.T3 if self.T3 is not None else 0.5 * self.T, (3,), "T3"))
            _check_camera_matrix(self.K3, "K3")
            _check_rotation(r3, "R3")

    # ------------------------------------------------------------------ geometry
    @property
    def baseline_mm(self) -> float:
        """Distance between the two optical centres (mm)."""
        return float(np.linalg.norm(self.T))

    def view(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(K, D, R, T)`` of the view ``left``, ``right`` or ``centre``: ``X_view = R @ X_camera + T``.

        Without a calibrated centre sensor the centre is half-way along the baseline with camera 1's
        intrinsics and orientation.
        """
        if name == "left":
            return self.K1, self.D1, np.eye(3), np.zeros(3)
        if name == "right":
            return self.K2, self.D2, self.R, self.T
        if name == "centre":
            if self.K3 is not None and self.D3 is not None and self.R3 is not None and self.T3 is not None:
                return self.K3, self.D3, self.R3, self.T3  # (__post_init__ sets all four with K3)
            return self.K1, self.D1, np.eye(3), 0.5 * self.T
        raise ValueError(f"view must be left, right or centre; got {name!r}")

    def project(self, points_mm: npt.ArrayLike, view: str = "left") -> np.ndarray:
        """Pixel coordinates ``(n, 2)`` of points ``(n, 3)`` given in the camera frame."""
        k, d, r, t = self.view(view)
        pts = np.asarray(points_mm, dtype=float).reshape(-1, 3)
        rvec, _ = cv2.Rodrigues(r)
        out, _ = cv2.projectPoints(pts, rvec, t.astype(float), k, d)
        return out.reshape(-1, 2)

    # ------------------------------------------------------------ rectification
    @cached_property
    def rectification(self) -> Rectification:
        """``stereoRectify`` of the pair (zero disparity at infinity, all pixels kept), computed once."""
        r1, r2, p1, p2, q, _, _ = cv2.stereoRectify(
            self.K1, self.D1, self.K2, self.D2, self.image_size, self.R, self.T.reshape(3, 1),
            flags=cv2.CALIB_ZERO_DISPARITY, alpha=-1,
        )
        return Rectification(r1, r2, p1, p2, q)

    def rectification_maps(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Pixel maps ``(map1x, map1y, map2x, map2y)`` (float32, ``(h, w)``) for ``cv2.remap``; computed once."""
        maps = self._cache.get("maps")
        if maps is None:
            rect = self.rectification
            m1 = cv2.initUndistortRectifyMap(self.K1, self.D1, rect.R1, rect.P1, self.image_size, cv2.CV_32FC1)
            m2 = cv2.initUndistortRectifyMap(self.K2, self.D2, rect.R2, rect.P2, self.image_size, cv2.CV_32FC1)
            maps = (m1[0], m1[1], m2[0], m2[1])
            self._cache["maps"] = maps
        return maps

    def rectify_images(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rectified copies of a left/right image pair (bilinear), rows aligned."""
        m1x, m1y, m2x, m2y = self.rectification_maps()
        return (cv2.remap(left, m1x, m1y, cv2.INTER_LINEAR), cv2.remap(right, m2x, m2y, cv2.INTER_LINEAR))

    def rectify_points(self, left_px: npt.ArrayLike, right_px: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Rectified pixel coordinates ``(n, 2)`` of raw (distorted) pixel coordinates in each image."""
        rect = self.rectification
        left = np.asarray(left_px, dtype=np.float64).reshape(-1, 1, 2)
        right = np.asarray(right_px, dtype=np.float64).reshape(-1, 1, 2)
        rl = cv2.undistortPointsIter(left, self.K1, self.D1, rect.R1, rect.P1, _SUBPIXEL_CRITERIA)
        rr = cv2.undistortPointsIter(right, self.K2, self.D2, rect.R2, rect.P2, _SUBPIXEL_CRITERIA)
        return rl.reshape(-1, 2), rr.reshape(-1, 2)

    def triangulate(self, left_px: npt.ArrayLike, right_px: npt.ArrayLike) -> Triangulation:
        """Points in the camera frame (mm) from corresponding pixel coordinates in the left and right images.

        Parameters
        ----------
        left_px, right_px : array-like, shape (n, 2)
            Raw (as captured, distorted) pixel coordinates, pixel centres at integers.

        Returns
        -------
        Triangulation

        Raises
        ------
        StereoMismatch
            If a disparity is not positive (the point would be behind the cameras: swapped images?).
        """
        left = np.asarray(left_px, dtype=float).reshape(-1, 2)
        right = np.asarray(right_px, dtype=float).reshape(-1, 2)
        if left.shape != right.shape:
            raise StereoMismatch(f"left has {len(left)} points and right {len(right)}; they must correspond")
        rect = self.rectification
        rl, rr = self.rectify_points(left, right)
        disparity = rl[:, 0] - rr[:, 0]
        if np.any(disparity <= 0):
            raise StereoMismatch(
                f"{int(np.sum(disparity <= 0))} of {len(disparity)} points have no positive disparity "
                f"(min {disparity.min():.1f} px): are the left and right images swapped?"
            )
        row = 0.5 * (rl[:, 1] + rr[:, 1])
        homogeneous = np.column_stack([rl[:, 0], row, disparity, np.ones(len(row))]) @ rect.Q.T
        points_rect = homogeneous[:, :3] / homogeneous[:, 3:4]
        points = points_rect @ rect.R1  # rows: R1.T @ p, back from the rectified frame to camera 1
        return Triangulation(points, rl, rr, rl[:, 1] - rr[:, 1], disparity)

    # ------------------------------------------------------------------- files
    def to_filestorage_dict(self) -> dict:
        out = {"image_width": self.image_size[0], "image_height": self.image_size[1],
               "K1": self.K1, "D1": self.D1.reshape(1, -1), "K2": self.K2, "D2": self.D2.reshape(1, -1),
               "R": self.R, "T": self.T.reshape(3, 1)}
        if self.K3 is not None and self.D3 is not None and self.R3 is not None and self.T3 is not None:
            out.update({"K3": self.K3, "D3": self.D3.reshape(1, -1), "R3": self.R3, "T3": self.T3.reshape(3, 1)})
        return out


def nominal_xb3_model(width: int = 1280, height: int = 960) -> StereoModel:
    """The nominal Bumblebee XB3 wide pair (rectified, no distortion), scaled to ``width x height``.

    f = 983 px, (cx, cy) = (643.6, 493.4) at 1280x960, baseline 239.98 mm (right camera at +x),
    centre sensor half-way (119.99 mm). Scaling to another Format_7 size keeps pixel centres:
    ``c' = (c + 0.5) * s - 0.5``.
    """
    sx = width / NOMINAL_XB3["width"]
    sy = height / NOMINAL_XB3["height"]
    k = np.array([[NOMINAL_XB3["f_px"] * sx, 0.0, (NOMINAL_XB3["cx"] + 0.5) * sx - 0.5],
                  [0.0, NOMINAL_XB3["f_px"] * sy, (NOMINAL_XB3["cy"] + 0.5) * sy - 0.5],
                  [0.0, 0.0, 1.0]])
    b = NOMINAL_XB3["baseline_mm"]
    return StereoModel((width, height), k, np.zeros(5), k.copy(), np.zeros(5), np.eye(3), np.array([-b, 0.0, 0.0]),
                       K3=k.copy(), D3=np.zeros(5), R3=np.eye(3), T3=np.array([-0.5 * b, 0.0, 0.0]),
                       name="nominal XB3 wide pair (f 983 px, baseline 239.98 mm)")


def _node_value(n):
    """A FileStorage node as a number, an array (``!!opencv-matrix``) or nested lists of numbers."""
    if n.isInt() or n.isReal():
        return n.real()
    if n.isSeq():
        return [_node_value(n.at(i)) for i in range(n.size())]
    if n.isMap():
        mat = n.mat()
        if mat is not None:
            return mat
    return None


def refuse_base64_filestorage(text: str, path: object, error: type[Exception]) -> None:
    """Refuse FileStorage text holding a base64 (``!!binary``) value before cv2 parses it.

    OpenCV 4's YAML reader loops forever (in C++, beyond any timeout or Ctrl-C of Python) on a damaged
    ``!!binary`` value, e.g. ``data: !!binary AAAA 1.0, 2.0, ...``; intact ones cannot be told apart
    cheaply, so base64 files are not read at all (OpenCV writes them only with ``FileStorage.BASE64``).
    """
    if "!!binary" in text:
        line = text[:text.index("!!binary")].count("\n") + 1
        raise error(f"{path}: line {line} holds a base64 (!!binary) value, which OpenCV's reader can loop "
                    f"forever on; save the file without FileStorage.BASE64 (plain numbers)")


def _open_filestorage(path: Path, text: str):
    """Open ``path`` (whose ``text`` was read and checked) with cv2.FileStorage; plain YAML without the
    ``%YAML:1.0`` line is accepted too."""
    def attempt(source, flags):
        try:
            fs = cv2.FileStorage(source, flags)
        except (cv2.error, SystemError):
            return None
        return fs if fs.isOpened() else None

    fs = attempt(str(path), cv2.FILE_STORAGE_READ)
    if fs is None:
        if not text.lstrip().startswith(("%YAML", "<?xml")):
            fs = attempt("%YAML:1.0\n---\n" + text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)
    if fs is None:
        raise StereoModelError(
            f"{path} is not an OpenCV FileStorage file (YAML or XML with image_width, image_height, K1, D1, K2, D2, R, T)"
        )
    return fs


def load_stereo_model(path: str | os.PathLike[str]) -> StereoModel:
    """Read a stereo model from an OpenCV FileStorage file (YAML/XML, see the module docstring).

    Matrices may be ``!!opencv-matrix`` entries or plain nested lists.

    Raises
    ------
    StereoModelError
        Missing file, not a regular file, not UTF-8 text, over 64 MB, missing or malformed entries.
    """
    path = Path(path)
    text = read_text_file(path, "stereo model", StereoModelError, missing=f"stereo file not found: {path}")
    refuse_base64_filestorage(text, path, StereoModelError)
    fs = _open_filestorage(path, text)
    try:
        def node(key: str, required: bool = True) -> object:
            n = fs.getNode(key)
            if n.empty() or n.isNone():
                if required:
                    raise StereoModelError(f"missing {key} (needs image_width, image_height, K1, D1, K2, D2, R, T)")
                return None
            value = _node_value(n)
            if value is None:
                raise StereoModelError(f"{key} is neither a number, an !!opencv-matrix nor a list of numbers")
            return value

        def array(key: str, required: bool = True) -> np.ndarray | None:
            value = node(key, required)
            if value is None:
                return None
            try:
                return np.asarray(value, dtype=float)
            except (TypeError, ValueError):  # ragged lists, text
                raise StereoModelError(f"{key} is not a matrix of numbers") from None

        def needed(key: str) -> np.ndarray:
            value = array(key)
            if value is None:  # node() raises for a missing required key
                raise StereoModelError(f"missing {key}")
            return value

        width, height = node("image_width"), node("image_height")
        if not isinstance(width, float) or not isinstance(height, float):
            raise StereoModelError("image_width and image_height must be numbers")
        k3 = d3 = r3 = t3 = None
        if node("K3", required=False) is not None:
            k3, d3, r3, t3 = needed("K3"), array("D3", False), array("R3", False), array("T3", False)
        model = StereoModel((int(width), int(height)), needed("K1"), needed("D1"), needed("K2"), needed("D2"), needed("R"),
                            needed("T"), K3=k3, D3=d3, R3=r3, T3=t3, name=str(path))
    except StereoModelError as exc:
        raise StereoModelError(f"{path}: {exc}") from None
    finally:
        fs.release()
    return model


def save_stereo_model(path: str | os.PathLike[str], model: StereoModel, extra: dict | None = None) -> Path:
    """Write ``model`` as an OpenCV FileStorage YAML file; returns the path.

    ``extra`` adds entries after the model's (numbers or strings, e.g. the calibration's RMS error);
    :func:`load_stereo_model` ignores them.
    """
    path = Path(path)
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        for key, value in model.to_filestorage_dict().items():
            if isinstance(value, (int, float)):
                fs.write(key, int(value))
            else:
                fs.write(key, np.asarray(value, dtype=np.float64))
        for key, value in (extra or {}).items():
            if isinstance(value, str):
                fs.write(key, value)
            elif isinstance(value, (bool, np.bool_)):
                fs.write(key, int(value))
            elif isinstance(value, (int, np.integer)):
                fs.write(key, int(value))
            else:
                fs.write(key, float(value))
    finally:
        fs.release()
    return path
