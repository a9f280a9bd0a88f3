"""Stereo camera side: the camera interface and back ends (``xb3``, ``mock``), XB3 frame decoding,
the stereo model, checkerboard detection in canonical order and triangulation to millimetres.

Importing this package is cheap (no OpenCV, no libdc1394); the modules ``decode``, ``stereo``,
``checkerboard``, ``triangulate``, ``stereo_calibration`` (calibrating the head), ``coverage``
(where the board has been, hints, the coverage map) and ``triclops`` (the factory calibration's
rectified model) use OpenCV, ``xb3`` loads libdc1394 only when it connects.
"""

from .errors import BoardNotFound, CameraError, FrameError, StereoMismatch, StereoModelError
from .interface import BACKENDS, Camera, StereoFrame, open_camera, register_backend

__all__ = [
    "BACKENDS",
    "BoardNotFound",
    "Camera",
    "CameraError",
    "FrameError",
    "StereoFrame",
    "StereoMismatch",
    "StereoModelError",
    "open_camera",
    "register_backend",
]
