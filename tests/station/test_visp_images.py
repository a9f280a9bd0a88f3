"""Real photographs (ViSP, Franka Panda eye-in-hand): the same detector plus a PnP pose per image
must calibrate to a sensible camera pose.

Data: ``shared/datasets/visp-apps-eye-in-hand`` (8 grey 640x480 images of a 9x6-corner board with
23.6 mm squares; intrinsics px = 607.59, py = 607.57, u0 = 323.46, v0 = 243.26, no distortion;
``franka_pose_rPe_i.yaml`` = end effector in base as ViSP pose vectors [t (m), theta-u (rad)]).
Checks: every image gives the full board in the canonical order with a small reprojection error;
the calibration agrees with OpenCV's own hand-eye solvers on the same poses; and it is plausible
against ViSP's published eMc for the same robot and camera type (another data set, so not the truth).
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from helpers import shared_dataset
from handeye.geometry.board import BoardGeometry
from handeye.calibration.session import Posture, Session
from handeye.calibration.solve import calibrate_session
from handeye.drivers.camera.checkerboard import board_pose_from_corners, detect_board
from handeye.station.opencv_reference import solve_opencv

K = np.array([[607.5931396484375, 0.0, 323.46282958984375], [0.0, 607.574951171875, 243.25529479980469], [0.0, 0.0, 1.0]])
BOARD = BoardGeometry((9, 6), 23.6)
# ViSP's eMc of the 2018 tutorial (visp-eye-in-hand README): same robot type, another session.
VISP_T_MM = np.array([53.46, -9.52, -45.10])
VISP_THETA_U = np.array([-0.02347, -0.07939, 1.57459])


def pose_from_visp(path) -> np.ndarray:
    """4x4 (mm) from a ViSP pose vector file [tx, ty, tz, θux, θuy, θuz] (m, rad)."""
    values = np.array(yaml.safe_load(path.read_text())["data"], float).ravel()
    out = np.eye(4)
    out[:3, :3] = Rotation.from_rotvec(values[3:]).as_matrix()
    out[:3, 3] = values[:3] * 1000.0
    return out


@pytest.fixture(scope="module")
def postures():
    folder = shared_dataset("visp-apps-eye-in-hand")
    out = []
    for i in range(1, 9):
        image = cv2.imread(str(folder / f"franka_image-{i}.png"), cv2.IMREAD_GRAYSCALE)
        det = detect_board(image, BOARD, what=f"franka_image-{i}.png")
        target2cam, rms = board_pose_from_corners(det.corners_px, BOARD, K)
        out.append((Posture(index=i - 1, tool0_in_base=pose_from_visp(folder / f"franka_pose_rPe_{i}.yaml"),
                            target_in_camera=target2cam), det, rms))
    return out


def test_every_photograph_gives_the_full_board_in_canonical_order(postures):
    for posture, det, rms in postures:
        assert det.corners_px.shape == (54, 2)
        assert not det.ambiguous  # 10x7 squares: the pattern fixes the orientation
        assert rms < 1.0
        # the board is 0.25-0.4 m in front of the camera, seen from its printed side (z away from the camera)
        t = posture.target_in_camera
        assert 250 < np.linalg.norm(t[:3, 3]) < 450
        assert t[2, 2] > 0.5


def test_calibration_is_sensible(postures):
    session = Session(setup="eye_in_hand", target=BOARD, postures=[p for p, _, _ in postures])
    result = calibrate_session(session, "mcb")
    x = result.x
    # Consistent board poses: with the answer the board stays put in the base frame to a few mm.
    assert result.metrics["d_org_mm"] < 10.0
    # OpenCV's Tsai and Park solvers on the same board and robot poses agree within a few mm / a degree.
    hand = [p.tool0_in_base for p, _, _ in postures]
    board = [p.target_in_camera for p, _, _ in postures]
    for method in ("tsai", "park"):
        reference = solve_opencv(hand, board, method)
        assert np.linalg.norm(x[:3, 3] - reference[:3, 3]) < 5.0
        assert np.degrees(Rotation.from_matrix(reference[:3, :3].T @ x[:3, :3]).magnitude()) < 1.0
    # Plausible against ViSP's eMc for the same robot and camera type (another session): the camera
    # sits ~5 cm off the flange axis, ~4.5 cm behind the flange, turned ~90 deg about z.
    angle = np.degrees((Rotation.from_rotvec(VISP_THETA_U).inv() * Rotation.from_matrix(x[:3, :3])).magnitude())
    assert angle < 10.0
    assert np.linalg.norm(x[:3, 3] - VISP_T_MM) < 40.0
    assert abs(np.linalg.norm(x[:3, 3]) - np.linalg.norm(VISP_T_MM)) < 20.0
