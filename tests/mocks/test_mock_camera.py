"""The mock XB3: rendering geometry, the XB3 byte layout, accuracy of the whole chain, the back end."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from handeye.geometry.board import board_corners
from handeye.drivers.camera import open_camera
from handeye.drivers.camera.checkerboard import detect_board, observe_board
from handeye.drivers.camera.decode import decode_xb3_frame
from handeye.drivers.camera.errors import CameraError
from handeye.drivers.camera.stereo import StereoModel, nominal_xb3_model
from handeye.drivers.camera.triangulate import triangulate_images, triangulate_xb3_frame
from handeye.mocks.camera import MockCamera, RenderOptions, StereoRenderer
from handeye.mocks.world import PrintedBoard, board_view, sample_board_views, sheet_in_view

MODEL = nominal_xb3_model()
BOARD = PrintedBoard()
GRID = board_corners(BOARD.corners, BOARD.square_mm)
CLEAN = RenderOptions(supersample=8, jitter=False, blur_sigma_px=0.0, read_noise_dn=0.0, shot_noise=0.0, colour=False)


def truth_points(pose):
    return GRID @ pose[:3, :3].T + pose[:3, 3]


def rms(a, b):
    return float(np.sqrt(np.mean(np.sum((np.asarray(a) - np.asarray(b)) ** 2, axis=1))))


def test_printed_pattern_follows_the_conventions():
    # Square centres just outside the grid: the two at the x-min edge black, the two at x-max white.
    pose = board_view(900, 0, 0, 0, BOARD, (120, 0))
    image = StereoRenderer(MODEL, BOARD, CLEAN).ideal(pose, "left")
    nx, ny, s = *BOARD.corners, BOARD.square_mm
    probes = {(-0.5, -0.5): "black", (-0.5, ny - 0.5): "black", (nx - 0.5, -0.5): "white", (nx - 0.5, ny - 0.5): "white",
              (0.5, 0.5): "black", (nx + 0.8, 3): "white"}  # last: the white margin
    for (u, v), colour in probes.items():
        x, y = MODEL.project(pose[:3, :3] @ [u * s, v * s, 0] + pose[:3, 3], "left")[0]
        value = image[int(round(y)), int(round(x))]
        assert (value < 50) if colour == "black" else (value > 200), (u, v, value)


def test_supersampling_has_no_pixel_centre_bias():
    # A wrong sub-sample mapping (x_hi = s*x instead of s*x + (s-1)/2) would shift every corner by
    # (s-1)/(2s) = 0.44 px at s = 8; the correct one leaves no bias.
    # Edges turned by 7 deg so that the phase of the edges in the pixels varies along them.
    pose = board_view(800, 0, 0, 7, BOARD, (130, 0))
    image = cv2.GaussianBlur(StereoRenderer(MODEL, BOARD, CLEAN).ideal(pose, "left"), (0, 0), 0.6)
    det = detect_board(np.clip(np.rint(image), 0, 255).astype(np.uint8), BOARD.geometry)
    error = det.corners_px - MODEL.project(truth_points(pose), "left")
    assert np.abs(error.mean(axis=0)).max() < 0.01
    assert np.sqrt(np.mean(error**2)) < 0.04


def test_xb3_frame_layout_left_centre_right():
    pose = board_view(1000, 15, 30, 10, BOARD, (120, 0))
    frame = StereoRenderer(MODEL, BOARD, seed=1).xb3_frame(pose)
    assert frame.shape == (960, 1280, 3) and frame.dtype == np.uint8
    decoded = decode_xb3_frame(frame.tobytes(), output="gray")
    truth = truth_points(pose)
    for view in ("left", "centre", "right"):
        det = detect_board(getattr(decoded, view), BOARD.geometry, what=view)
        assert rms(det.corners_px, MODEL.project(truth, view)) < 0.1, view
    # byte 2 is the left sensor: the board sits further right in the left image than in the right one
    assert MODEL.project(truth, "left")[:, 0].mean() > MODEL.project(truth, "right")[:, 0].mean() + 200


def test_corner_accuracy_png_pairs_and_raw_colour_frames():
    poses = sample_board_views(4, MODEL, BOARD, distance_mm=(700, 1200), seed=11)
    renderer = StereoRenderer(MODEL, BOARD, seed=5)
    png, raw = [], []
    for pose in poses:
        truth = truth_points(pose)
        left, right = renderer.gray_pair(pose)
        png.append(triangulate_images(left, right, BOARD.geometry, model=MODEL).points_mm - truth)
        raw.append(triangulate_xb3_frame(renderer.xb3_frame(pose), BOARD.geometry, model=MODEL).points_mm - truth)
    png_rms = np.sqrt(np.mean(np.sum(np.concatenate(png) ** 2, axis=1)))
    raw_rms = np.sqrt(np.mean(np.sum(np.concatenate(raw) ** 2, axis=1)))
    assert png_rms <= 0.35
    assert raw_rms <= 0.5


def test_lens_distortion_is_rendered_and_undone():
    k = MODEL.K1
    distorted = StereoModel(MODEL.image_size, k, [-0.12, 0.08, 0.0006, -0.0004, 0.0], k, [-0.1, 0.06, -0.0003, 0.0005, 0.0],
                            np.eye(3), MODEL.T)
    pose = board_view(950, 20, 120, -15, BOARD, (110, 0))
    assert sheet_in_view(pose, distorted, BOARD)
    left, right = StereoRenderer(distorted, BOARD, seed=2).gray_pair(pose)
    truth = truth_points(pose)
    obs = observe_board(left, right, distorted, BOARD.geometry)
    assert rms(obs.left.corners_px, distorted.project(truth, "left")) < 0.06
    assert rms(obs.points_mm, truth) < 0.35
    # the same images read with the distortion-free model are clearly worse: distortion was rendered
    ideal = observe_board(left, right, MODEL, BOARD.geometry)
    assert rms(ideal.points_mm, truth) > 3 * rms(obs.points_mm, truth)


def test_seeded_renders_are_reproducible():
    pose = board_view(1000, 10, 0, 0, BOARD, (120, 0))
    a = StereoRenderer(MODEL, BOARD, seed=4).xb3_frame(pose)
    b = StereoRenderer(MODEL, BOARD, seed=4).xb3_frame(pose)
    c = StereoRenderer(MODEL, BOARD, seed=5).xb3_frame(pose)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_mock_back_end_follows_the_camera_pose_provider(no_leaked_threads):
    target2base = np.eye(4)
    target2base[:3, 3] = [300.0, -100.0, 0.0]
    # cam2base such that target2cam = inv(cam2base) @ target2base is the board_view pose
    view = board_view(1000, 20, 45, 0, BOARD, (120, 0))
    pose = {"cam2base": target2base @ np.linalg.inv(view)}
    with open_camera("mock", target2base=target2base, cam2base=lambda: pose["cam2base"], seed=3, output="gray") as camera:
        assert isinstance(camera, MockCamera) and camera.is_connected
        frame = camera.grab()
        assert frame.serial == camera.serial and frame.layout == "rgb8" and frame.colour
        assert frame.raw.shape == (960, 1280, 3)
        np.testing.assert_allclose(camera.target2cam(), view, atol=1e-9)
        obs = observe_board(frame.left, frame.right, MODEL, BOARD.geometry)
        assert rms(obs.points_mm, truth_points(view)) < 0.5
        # the provider is asked again at every grab
        view2 = board_view(800, 30, 200, 170, BOARD, (140, 0))
        pose["cam2base"] = target2base @ np.linalg.inv(view2)
        obs2 = observe_board(*_lr(camera.grab()), MODEL, BOARD.geometry)
        assert rms(obs2.points_mm, truth_points(view2)) < 0.5
        camera.set_scene(cam2base=np.eye(4))  # a fixed pose instead of the provider
        np.testing.assert_allclose(camera.target2cam(), target2base)
    assert not camera.is_connected
    with pytest.raises(CameraError, match="not connected"):
        camera.grab()


def _lr(frame):
    return frame.left, frame.right


def test_mock_default_scene_shows_the_board_and_options_work():
    with open_camera("mock", options=replace(RenderOptions(), colour=False), render_centre=False, seed=1) as camera:
        frame = camera.grab()
        assert frame.centre is None and not frame.colour
        assert frame.left.ndim == 3  # BGR output by default
        obs = observe_board(frame.left, frame.right, camera.model, camera.board.geometry)
        assert obs.quality["distance_mm"] == pytest.approx(np.linalg.norm(camera.target2cam()[:3, 3] + camera.target2cam()[:3, :3] @ BOARD.centre()), abs=2)


def test_unknown_back_end():
    with pytest.raises(CameraError, match="unknown camera back end 'gige'"):
        open_camera("gige")


def test_drivers_import_neither_mocks_nor_station():
    import ast
    from pathlib import Path

    import handeye.drivers.camera as package

    for path in Path(package.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                assert "mocks" not in name and "station" not in name, f"{path.name} imports {name}"


def test_importing_the_camera_package_loads_neither_opencv_nor_libdc1394():
    import subprocess
    import sys
    from pathlib import Path

    if not Path("/proc/self/maps").exists():
        pytest.skip("needs /proc/self/maps to see the loaded shared libraries")
    code = ("import sys, handeye.drivers.camera, handeye.drivers.camera.xb3; "
            "print('cv2' in sys.modules, 'dc1394' in open('/proc/self/maps').read())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False"]
