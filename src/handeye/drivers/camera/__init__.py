"""Stereo camera side: the camera interface and back ends by name (``xb3``, ``mock`` once
``handeye.mocks`` is imported, or one a plug-in registers), XB3 frame decoding, the stereo model,
checkerboard detection in canonical order and triangulation to millimetres.

Importing this package is cheap (no OpenCV, no libdc1394): names load on first use; the modules
``decode``, ``stereo``, ``checkerboard``, ``triangulate``, ``stereo_calibration`` (calibrating the
head), ``coverage`` (where the board has been, hints, the coverage map) and ``triclops`` (the
factory calibration's rectified model) use OpenCV, ``xb3`` loads libdc1394 only when it connects.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...base import lazy_exports

_EXPORTS = {
    "CAMERAS": "backends",
    "CameraBackend": "backends",
    "register_backend": "backends",
    "Camera": "interface",
    "StereoFrame": "interface",
    "open_camera": "interface",
    "CameraError": "errors",
    "BoardNotFound": "errors",
    "FrameError": "errors",
    "StereoMismatch": "errors",
    "StereoModelError": "errors",
    "SquareSizeMismatch": "errors",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .backends import CAMERAS, CameraBackend, register_backend  # noqa: F401
    from .errors import BoardNotFound, CameraError, FrameError, SquareSizeMismatch, StereoMismatch, StereoModelError  # noqa: F401
    from .interface import Camera, StereoFrame, open_camera  # noqa: F401
