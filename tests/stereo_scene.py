"""Rendered stereo pairs made hard the way real ones are, shared by the stereo calibration tests.

The head is not rectified (different intrinsics, lens distortion, a small rotation), the board is
9x6 corners of 30 mm with a 20 mm margin, 0.45-1.0 m away, tilted up to 45 deg, often near the image
edges; every pair gets its own blur, uneven light with vignetting, glare or a shadow on the board,
sensor noise and JPEG artefacts (``mocks.camera.hard_options``). Rendered once per test process.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.drivers.camera.board_pattern import canonical_orderings, pattern_score
from handeye.drivers.camera.stereo import StereoModel
from handeye.mocks.camera import StereoRenderer, hard_options
from handeye.mocks.world import PrintedBoard, sample_board_views

BOARD = PrintedBoard(BoardGeometry((9, 6), 30.0), 20.0)
GEOMETRY = BOARD.geometry
OBJ = board_corners(GEOMETRY.corners, GEOMETRY.square_mm).astype(np.float32)


def truth_model() -> StereoModel:
    """The rendering model: a raw (unrectified) wide pair with distortion and a small rotation."""
    k1 = np.array([[990.0, 0.0, 650.0], [0.0, 985.0, 480.0], [0.0, 0.0, 1.0]])
    k2 = np.array([[975.0, 0.0, 630.0], [0.0, 978.0, 500.0], [0.0, 0.0, 1.0]])
    r = Rotation.from_euler("xyz", [0.4, -1.2, 0.3], degrees=True).as_matrix()
    return StereoModel((1280, 960), k1, [-0.08, 0.05, 0.0005, -0.0003, 0.0], k2,
                       [-0.07, 0.04, -0.0002, 0.0004, 0.0], r, [-240.5, 1.2, -0.8], name="rendering truth")


@dataclass
class Scene:
    folder: Path
    model: StereoModel
    poses: list
    names: list

    def image(self, name: str, side: str) -> np.ndarray:
        return cv2.imread(str(self.folder / f"{name}_{side}.png"), cv2.IMREAD_GRAYSCALE)

    def truth_px(self, k: int, side: str) -> np.ndarray:
        pose = self.poses[k]
        return self.model.project(OBJ.astype(float) @ pose[:3, :3].T + pose[:3, 3], side)


@lru_cache(maxsize=None)
def hard_scene(n: int = 18, seed: int = 1, distance_mm=(450.0, 1000.0)) -> Scene:
    """``n`` hard pairs written as ``NNN_left.png`` / ``NNN_right.png`` into a temporary folder."""
    model = truth_model()
    folder = Path(tempfile.mkdtemp(prefix="handeye-stereo-scene-"))
    atexit.register(shutil.rmtree, folder, True)
    rng = np.random.default_rng(seed)
    poses = sample_board_views(n, model, BOARD, seed=seed, distance_mm=distance_mm, tilt_deg=(0, 45),
                               offset_px=300, views=("left", "right"), border_px=2)
    renderer = StereoRenderer(model, BOARD, seed=seed)
    names = []
    for k, pose in enumerate(poses):
        renderer.options = hard_options(rng, BOARD)
        left, right = renderer.gray_pair(pose)
        name = f"{k:03d}"
        cv2.imwrite(str(folder / f"{name}_left.png"), left)
        cv2.imwrite(str(folder / f"{name}_right.png"), right)
        names.append(name)
    return Scene(folder, model, poses, names)


def opencv_corners(image: np.ndarray, pattern=GEOMETRY.corners):
    """Plain OpenCV: ``findChessboardCorners`` (default flags) + ``cornerSubPix`` (11x11), or None.

    OpenCV does not fix which corner comes first (a board turned by 180 deg swaps the order), so
    the grid is put in the canonical order by the printed pattern; nothing else is changed.
    """
    found, corners = cv2.findChessboardCorners(image, pattern)
    if not found:
        return None
    corners = cv2.cornerSubPix(image, corners, (11, 11), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001))
    nx, ny = pattern
    options = canonical_orderings(corners.reshape(ny, nx, 2).astype(np.float64))
    best = max(options, key=lambda g: pattern_score(g, image))
    return best.reshape(-1, 2)


def opencv_stereo(left_list, right_list, size=(1280, 960)):
    """Plain OpenCV calibration: ``calibrateCamera`` for each camera, then ``stereoCalibrate``
    (``CALIB_FIX_INTRINSIC``), default flags. Returns ``(rms, K1, D1, K2, D2, R, T)``."""
    obj = [OBJ] * len(left_list)
    lp = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in left_list]
    rp = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in right_list]
    _, k1, d1, _, _ = cv2.calibrateCamera(obj, lp, size, None, None)
    _, k2, d2, _, _ = cv2.calibrateCamera(obj, rp, size, None, None)
    rms, k1, d1, k2, d2, r, t, _, _ = cv2.stereoCalibrate(obj, lp, rp, k1, d1, k2, d2, size, flags=cv2.CALIB_FIX_INTRINSIC)
    return rms, k1, d1.ravel(), k2, d2.ravel(), r, t.ravel()


def opencv_triangulate(k1, d1, k2, d2, r, t, left_px, right_px) -> np.ndarray:
    """OpenCV's own triangulation: ``undistortPoints`` to normalised coordinates, ``triangulatePoints``
    with ``P1 = [I | 0]``, ``P2 = [R | T]``; points in the left camera frame (mm)."""
    ul = cv2.undistortPoints(np.asarray(left_px, np.float64).reshape(-1, 1, 2), k1, d1)
    ur = cv2.undistortPoints(np.asarray(right_px, np.float64).reshape(-1, 1, 2), k2, d2)
    p1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    p2 = np.hstack([r, np.asarray(t, float).reshape(3, 1)])
    h = cv2.triangulatePoints(p1, p2, ul.reshape(-1, 2).T, ur.reshape(-1, 2).T)
    return (h[:3] / h[3]).T
