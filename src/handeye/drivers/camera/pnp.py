"""A monocular pose from known object points and their pixels (``cv2.solvePnP``), with its
reprojection RMS: what a board pose (``checkerboard``) and a tag pose (the ViSP importer) share."""

from __future__ import annotations

from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["pnp_pose", "pose_from_rvec"]


def pnp_pose(objects: npt.ArrayLike, pixels: npt.ArrayLike, camera_matrix: npt.ArrayLike, dist_coeffs: npt.ArrayLike | None, flags: int = cv2.SOLVEPNP_ITERATIVE,
             refine: bool = False) -> tuple[np.ndarray, float] | None:
    """The pose of the object frame in the camera and the reprojection RMS, or None when PnP fails.

    Parameters
    ----------
    objects : array-like, shape (n, 3)
        Points in the object frame (mm).
    pixels : array-like, shape (n, 2)
        Their image points (px).
    camera_matrix : array-like, shape (3, 3)
    dist_coeffs : array-like
        OpenCV distortion coefficients.
    flags : int
        The ``cv2.solvePnP`` method.
    refine : bool
        Polish the pose with ``cv2.solvePnPRefineLM``.

    Returns
    -------
    (pose, rms_px) : (ndarray of shape (4, 4), float), or None
        ``pose`` maps object coordinates (mm) to camera coordinates (mm).
    """
    objects = np.asarray(objects, dtype=np.float64)
    pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    k = np.asarray(camera_matrix, dtype=np.float64)
    d = np.asarray(dist_coeffs, dtype=np.float64)
    ok, rvec, tvec = cv2.solvePnP(objects, pixels, k, d, flags=flags)
    if not ok:
        return None
    if refine:
        rvec, tvec = cv2.solvePnPRefineLM(objects, pixels, k, d, rvec, tvec)
    projected, _ = cv2.projectPoints(objects, rvec, tvec, k, d)
    rms = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - pixels) ** 2, axis=1))))
    return pose_from_rvec(rvec, tvec), rms


def pose_from_rvec(rvec: npt.ArrayLike, tvec: npt.ArrayLike) -> np.ndarray:
    """The 4x4 pose of OpenCV's rotation vector and translation (``solvePnP``, ``calibrateCamera``)."""
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(np.asarray(rvec, float))[0]
    pose[:3, 3] = np.asarray(tvec, float).ravel()
    return pose
