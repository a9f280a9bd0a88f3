"""OpenCV's ``calibrateHandEye`` as a reference solver, for benchmarks and cross-checks.

OpenCV 4.x exposes five methods in Python; the 5.0 wheels dropped the function. ``method`` is passed
as a keyword on purpose: passed positionally it lands on an output argument and Tsai runs silently.
"""

from __future__ import annotations

import numpy as np

from ..geometry import transform_from_rotation_translation

__all__ = ["OPENCV_METHODS", "opencv_available", "solve_opencv"]

OPENCV_METHODS = ("tsai", "park", "horaud", "andreff", "daniilidis")


def opencv_available() -> bool:
    """True when the installed OpenCV has ``calibrateHandEye``."""
    try:
        import cv2
    except ImportError:  # pragma: no cover - opencv-python-headless is a dependency
        return False
    return hasattr(cv2, "calibrateHandEye")


def solve_opencv(hand, target2cam, name: str) -> np.ndarray:
    """X (4x4) by one of OpenCV's methods.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand).
    target2cam : array-like, shape (n, 4, 4)
        Board poses, same length unit.
    name : str
        One of :data:`OPENCV_METHODS`.
    """
    import cv2

    h = np.asarray(hand, dtype=float)
    b = np.asarray(target2cam, dtype=float)
    flag = getattr(cv2, f"CALIB_HAND_EYE_{name.upper()}")
    r, t = cv2.calibrateHandEye(list(h[:, :3, :3]), list(h[:, :3, 3]), list(b[:, :3, :3]), list(b[:, :3, 3]), method=flag)
    return transform_from_rotation_translation(r, np.ravel(t))
