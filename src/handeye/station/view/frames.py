"""The live view's images: a stereo frame downscaled, the corners drawn, encoded as JPEG (OpenCV).

The detected corners (the capture's measurement, or for a live frame a quick search on the small
image, ``cv2.findChessboardCorners`` with ``CALIB_CB_FAST_CHECK``) are drawn as green dots with the
board's outline and corner 0 (the target frame's origin) circled in blue; where a calibration
predicts them, red crosses.
"""

from __future__ import annotations

import base64

import numpy as np

__all__ = ["VIEW_WIDTH_PX", "encode_side", "quick_corners"]

#: Width of the images on the page, px (the height keeps the camera's aspect).
VIEW_WIDTH_PX = 400
_JPEG_QUALITY = 70


def _small_bgr(image: np.ndarray, width: int) -> tuple[np.ndarray, float]:
    import cv2

    image = np.asarray(image)
    scale = width / image.shape[1]
    small = cv2.resize(image, (width, max(1, round(image.shape[0] * scale))), interpolation=cv2.INTER_AREA)
    if small.ndim == 2:
        small = cv2.cvtColor(small, cv2.COLOR_GRAY2BGR)
    return small, scale


def quick_corners(image: np.ndarray, corners: tuple, width: int = VIEW_WIDTH_PX) -> np.ndarray | None:
    """The board's inner corners ``(m, 2)`` in the full-size image's pixels, found on a copy ``width``
    px wide (fast; None when not found there)."""
    import cv2

    small, scale = _small_bgr(image, width)
    gray = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
    found, points = cv2.findChessboardCorners(gray, tuple(int(c) for c in corners),
                                              flags=cv2.CALIB_CB_FAST_CHECK | cv2.CALIB_CB_ADAPTIVE_THRESH)
    return points.reshape(-1, 2) / scale if found else None


def encode_side(image: np.ndarray, corners: tuple, found_px=None, predicted_px=None,
                width: int = VIEW_WIDTH_PX) -> str:
    """One camera's image for the page: a ``data:image/jpeg;base64,...`` URL.

    Parameters
    ----------
    image : ndarray, shape (h, w) or (h, w, 3), uint8
    corners : tuple of int
        Inner corners of the board along x and y.
    found_px : ndarray, shape (m, 2), optional
        Detected corners in the full-size image (px).
    predicted_px : ndarray, shape (m, 2), optional
        Where the calibration expects them (px).
    """
    import cv2

    small, scale = _small_bgr(image, width)
    if found_px is not None and len(found_px):
        points = np.asarray(found_px, float).reshape(-1, 2) * scale
        cv2.polylines(small, [np.round(points[[0, corners[0] - 1, -1, -corners[0]]]).astype(np.int32)], True,
                      (0, 200, 0), 1, cv2.LINE_AA)  # the board's outline through its four outer corners
        for u, v in points:
            cv2.circle(small, (int(round(u)), int(round(v))), 2, (0, 200, 0), -1, cv2.LINE_AA)
        cv2.circle(small, tuple(int(round(c)) for c in points[0]), 5, (255, 0, 0), 2, cv2.LINE_AA)  # corner 0
    if predicted_px is not None:
        for u, v in np.asarray(predicted_px, float).reshape(-1, 2) * scale:
            if np.isfinite(u) and np.isfinite(v) and 0 <= u < small.shape[1] and 0 <= v < small.shape[0]:
                cv2.drawMarker(small, (int(round(u)), int(round(v))), (0, 0, 255), cv2.MARKER_CROSS, 9, 1)
    ok, buffer = cv2.imencode(".jpg", small, [cv2.IMWRITE_JPEG_QUALITY, _JPEG_QUALITY])
    return "data:image/jpeg;base64," + base64.b64encode(buffer.tobytes()).decode("ascii")
