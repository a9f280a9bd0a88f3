"""Checkerboard detection: canonical corner order and orientation from the printed pattern, rejections.

The first tests draw a board by hand (no renderer): pixel ``i`` covers ``[i - 0.5, i + 0.5]``, so a
square edge between pixels ``i - 1`` and ``i`` lies at ``i - 0.5`` and the corner positions are
known exactly. The square between corners 0, 1, nx and nx + 1 is black (conventions: x runs from
the edge whose corner squares are black towards the edge whose corner squares are white).
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.drivers.camera import checkerboard as cb
from handeye.drivers.camera.checkerboard import board_pose_from_corners, detect_board, observe_board
from handeye.drivers.camera.errors import BoardNotFound, CameraError, FrameError, StereoMismatch
from handeye.drivers.camera.stereo import nominal_xb3_model
from handeye.mocks.camera import StereoRenderer
from handeye.mocks.world import PrintedBoard, board_view

SQ = 24  # px per square in the hand-drawn images


def drawn_board(nx=13, ny=8, margin=30, pad=40, black=30, white=220, background=110, blur=0.7):
    """A fronto-parallel board image and its inner corners ``(ny, nx, 2)`` in canonical order."""
    sx, sy = (nx + 1) * SQ, (ny + 1) * SQ
    h, w = sy + 2 * margin + 2 * pad, sx + 2 * margin + 2 * pad
    img = np.full((h, w), background, np.float32)
    img[pad:h - pad, pad:w - pad] = white
    x0, y0 = pad + margin, pad + margin  # first pixel of square (0, 0)
    for b in range(ny + 1):
        for a in range(nx + 1):
            if (a + b) % 2 == 0:
                img[y0 + b * SQ: y0 + (b + 1) * SQ, x0 + a * SQ: x0 + (a + 1) * SQ] = black
    if blur:
        img = cv2.GaussianBlur(img, (0, 0), blur)
    cols, rows = np.meshgrid(np.arange(nx), np.arange(ny))
    corners = np.stack([x0 + (cols + 1) * SQ - 0.5, y0 + (rows + 1) * SQ - 0.5], axis=-1).astype(float)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), corners


def rotate(points, k, shape):
    """Positions of ``points`` after ``np.rot90(image, k)`` (counter-clockwise quarter turns)."""
    h, w = shape
    x, y = points[..., 0], points[..., 1]
    for _ in range(k % 4):
        x, y, h, w = y, w - 1 - x, w, h
    return np.stack([x, y], axis=-1)


@pytest.mark.parametrize("corners", [(13, 8), (9, 6), (8, 5)])
def test_drawn_board_is_found_in_canonical_order(corners):
    img, truth = drawn_board(*corners)
    det = detect_board(img, corners)
    assert not det.ambiguous
    assert det.corners_px.shape == (corners[0] * corners[1], 2)
    np.testing.assert_allclose(det.corners_px, truth.reshape(-1, 2), atol=0.05)
    assert det.pattern_score > 100


@pytest.mark.parametrize("k", [1, 2, 3])
def test_turned_images_give_the_same_physical_corners(k):
    img, truth = drawn_board(13, 8)
    turned = np.ascontiguousarray(np.rot90(img, k))
    det = detect_board(turned, (13, 8))
    expected = rotate(truth, k, img.shape).reshape(-1, 2)
    np.testing.assert_allclose(det.corners_px, expected, atol=0.05)


def test_black_corner_squares_are_at_the_x_origin_edge():
    img, _ = drawn_board(13, 8, blur=0)
    det = detect_board(np.ascontiguousarray(np.rot90(img, 3)), (13, 8))
    grid = det.grid
    nx, ny = 13, 8
    # Square centres just outside the grid, extrapolated from the detected corners.
    def outer(col, row, dc, dr):
        p = grid[row, col]
        step_x = grid[row, 1] - grid[row, 0]
        step_y = grid[1, col] - grid[0, col]
        return p + dc * 0.5 * step_x + dr * 0.5 * step_y

    turned = np.rot90(img, 3)
    def value(p):
        return float(turned[int(round(p[1])), int(round(p[0]))])

    assert value(outer(0, 0, -1, -1)) < 80 and value(outer(0, ny - 1, -1, 1)) < 80          # x-min edge: black
    assert value(outer(nx - 1, 0, 1, -1)) > 180 and value(outer(nx - 1, ny - 1, 1, 1)) > 180  # x-max edge: white
    # the grid turns clockwise in the image (z = x cross y points into the board)
    ex, ey = grid[0, 1] - grid[0, 0], grid[1, 0] - grid[0, 0]
    assert ex[0] * ey[1] - ex[1] * ey[0] > 0


def test_symmetric_board_is_flagged_ambiguous_with_x_to_the_right():
    img, truth = drawn_board(8, 6)  # 9x7 squares: looks the same turned by 180 deg
    for k in (0, 2):
        det = detect_board(np.ascontiguousarray(np.rot90(img, k)), (8, 6))
        assert det.ambiguous
        x_axis = det.grid[0, -1] - det.grid[0, 0]
        assert x_axis[0] > 0
        assert len(det.alternatives) == 1


def test_no_board_half_board_and_wrong_counts_are_refused():
    img, _ = drawn_board(13, 8)
    with pytest.raises(BoardNotFound, match="no checkerboard in the image"):
        detect_board(np.full_like(img, 120), (13, 8))
    noise = np.random.default_rng(0).integers(0, 255, img.shape).astype(np.uint8)
    with pytest.raises(BoardNotFound):
        detect_board(noise, (13, 8))
    half = img.copy()
    half[:, img.shape[1] // 2:] = 110
    with pytest.raises(BoardNotFound, match="in the left image"):  # either message (the hint is heuristic)
        detect_board(half, (13, 8), what="left image")
    # one corner off in either direction (or squares counted instead of corners): the count is named
    for wrong in ((14, 8), (12, 8), (13, 7), (14, 9), (12, 7)):
        with pytest.raises(BoardNotFound, match=f"has 13x8 inner corners, not {wrong[0]}x{wrong[1]}: give --board 13x8"):
            detect_board(img, wrong)
    # any other count: findChessboardCornersSB sees the whole board, OpenCV's detector confirms its count
    for wrong in ((9, 6), (16, 10)):
        with pytest.raises(BoardNotFound, match=f"has 13x8 inner corners, not {wrong[0]}x{wrong[1]}: give --board 13x8"):
            detect_board(img, wrong)


def test_a_grid_inside_a_larger_board_is_refused(monkeypatch):
    # OpenCV's detector does not return part of a larger board today; if one ever does (another
    # version or detector), the squares beyond the grid still alternate and the detection is refused.
    img, truth = drawn_board(13, 8)
    sub = truth[:, :12].reshape(-1, 2)
    monkeypatch.setattr(cb, "find_grid", lambda gray, pattern, search="full": cb.GridSearch(sub.copy(), "roi"))
    with pytest.raises(BoardNotFound, match="part of a larger checkerboard"):
        detect_board(img, (12, 8))
    full = truth.reshape(-1, 2)
    monkeypatch.setattr(cb, "find_grid", lambda gray, pattern, search="full": cb.GridSearch(full.copy(), "roi"))
    assert detect_board(img, (13, 8)).corners_px.shape == (104, 2)


def test_low_contrast_is_refused_with_the_reason(monkeypatch):
    img, truth = drawn_board(13, 8, black=120, white=128, background=124, blur=0)
    monkeypatch.setattr(cb, "find_grid", lambda gray, pattern, search="full": cb.GridSearch(truth.reshape(-1, 2).copy(), "roi"))
    with pytest.raises(BoardNotFound, match="grey levels"):
        detect_board(img, (13, 8), refine=False)


def test_board_spec_errors():
    with pytest.raises(CameraError, match="NXxNY"):
        cb.as_board("13-8")
    with pytest.raises(CameraError, match="at least 2x2"):
        cb.as_board((1, 8))
    assert cb.as_board("13x8", 30.0) == BoardGeometry((13, 8), 30.0)


# ----------------------------------------------------------------------------- stereo pairs

MODEL = nominal_xb3_model()
BOARD = PrintedBoard()
GRID = board_corners(BOARD.corners, BOARD.square_mm)


def _pair(pose, seed=0):
    return StereoRenderer(MODEL, BOARD, seed=seed).gray_pair(pose)


@pytest.mark.parametrize("roll", [5.0, 95.0, 185.0, -80.0])
def test_stereo_detections_are_consistent_and_canonical(roll):
    pose = board_view(1000, 25, 60, roll, BOARD, (110, 0))
    left, right = _pair(pose)
    obs = observe_board(left, right, MODEL, BOARD.geometry)
    truth = GRID @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_allclose(obs.left.corners_px, MODEL.project(truth, "left"), atol=0.15)
    np.testing.assert_allclose(obs.right.corners_px, MODEL.project(truth, "right"), atol=0.15)
    assert np.sqrt(np.mean(np.sum((obs.points_mm - truth) ** 2, axis=1))) < 0.5
    q = obs.quality
    assert q["corners"] == q["corners_left"] == q["corners_right"] == 104
    assert q["orientation"] == "pattern"
    assert q["row_disagreement_rms_px"] < 0.1
    assert q["plane_rms_mm"] < 0.3
    assert q["distance_mm"] == pytest.approx(np.linalg.norm(truth.mean(axis=0)), abs=1.0)
    assert q["tilt_deg"] == pytest.approx(25, abs=0.5)
    assert q["square_mm_measured"] == pytest.approx(30, abs=0.05)


def test_pnp_pose_of_a_rendered_board():
    pose = board_view(900, 30, 200, 20, BOARD, (100, 0))
    left, _ = _pair(pose, 3)
    det = detect_board(left, BOARD.geometry)
    target2cam, rms = board_pose_from_corners(det.corners_px, BOARD.geometry, MODEL.K1)
    assert rms < 0.1
    np.testing.assert_allclose(target2cam[:3, 3], pose[:3, 3], atol=2.0)
    angle = np.degrees(np.arccos(np.clip((np.trace(target2cam[:3, :3].T @ pose[:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 0.2


def test_stereo_bad_inputs():
    pose = board_view(1000, 10, 0, 0, BOARD, (120, 0))
    left, right = _pair(pose)
    with pytest.raises(FrameError, match="left image is 640x480 but right image is 1280x960"):
        observe_board(left[:480, :640], right, MODEL, BOARD.geometry)
    with pytest.raises(FrameError, match="stereo model is for 1280x960"):
        observe_board(left[:480, :640], right[:480, :640], MODEL, BOARD.geometry)
    with pytest.raises(StereoMismatch, match="swapped"):
        observe_board(right, left, MODEL, BOARD.geometry)
    other_left, _ = _pair(board_view(1100, 30, 90, 0, BOARD, (100, 40)))
    with pytest.raises(StereoMismatch, match="rectified rows"):
        observe_board(other_left, right, MODEL, BOARD.geometry)
    with pytest.raises(BoardNotFound, match="right image"):
        observe_board(left, np.full_like(right, 100), MODEL, BOARD.geometry)
    with pytest.raises(FrameError, match="empty"):
        observe_board(np.zeros((0, 0), np.uint8), right, MODEL, BOARD.geometry)


def test_symmetric_board_stereo_orders_agree_through_the_rectified_rows():
    board = PrintedBoard(BoardGeometry((8, 6), 40.0), 30.0)  # 9x7 squares: no printed orientation
    grid = board_corners(board.corners, board.square_mm)
    for roll in (88.0, 92.0, 180.0):
        pose = board_view(1000, 15, 30, roll, board, (120, 0))
        left, right = StereoRenderer(MODEL, board, seed=1).gray_pair(pose)
        obs = observe_board(left, right, MODEL, board.geometry)
        assert obs.quality["orientation"] == "ambiguous"
        assert obs.quality["row_disagreement_rms_px"] < 0.1
        truth = grid @ pose[:3, :3].T + pose[:3, 3]
        turned = truth.reshape(6, 8, 3)[::-1, ::-1].reshape(-1, 3)  # the same board read turned by 180 deg
        err = min(np.abs(obs.points_mm - truth).max(), np.abs(obs.points_mm - turned).max())
        assert err < 1.5


def test_conflicting_pattern_readings_are_refused(monkeypatch):
    pose = board_view(1000, 10, 0, 0, BOARD, (120, 0))
    left, right = _pair(pose)
    real = cb.detect_board

    def misread_right(image, board, **kw):
        det = real(image, board, **kw)
        if kw.get("what") == "right image":  # as if glare made the right image read the board turned
            return cb.Detection(det.alternatives[0], det.board, det.image_size, False, det.pattern_score,
                                (det.corners_px,))
        return det

    monkeypatch.setattr(cb, "detect_board", misread_right)
    with pytest.raises(StereoMismatch, match="different board orientations"):
        observe_board(left, right, MODEL, BOARD.geometry)


def test_a_larger_grid_seen_in_part_says_the_board_is_larger(monkeypatch):
    # findChessboardCornersSB with CALIB_CB_LARGER may see only part of a larger board (glare, shadow); OpenCV's
    # detector does not confirm that count, so the message says "at least" instead of naming a count
    img, truth = drawn_board(13, 8)
    part = truth[:3].reshape(-1, 1, 2).astype(np.float32)   # 3 rows of 13 corners
    meta = np.zeros((3, 13), np.uint8)
    monkeypatch.setattr(cb.cv2, "findChessboardCornersSBWithMeta", lambda *a, **k: (True, part, meta))
    with pytest.raises(BoardNotFound, match="has more inner corners than 9x6 \\(13x3 seen at least\\): give its full"):
        detect_board(img, (9, 6))


def test_a_board_cut_by_the_image_edge_is_not_given_another_count():
    # 13x8 board whose last two corner columns are outside the image: the 11x8 corners in view must not
    # be taken for a whole 11x8 (or 12x8) board
    img, truth = drawn_board(13, 8)
    cut = int(truth[0, 10, 0] + SQ // 2)
    part = np.ascontiguousarray(img[:, :cut])
    for asked in ((13, 8), (12, 8)):
        with pytest.raises(BoardNotFound) as info:
            detect_board(part, asked)
        assert "inner corners, not" not in str(info.value)
