"""``handeye stereo calibrate --board charuco`` (issue 37): ChArUco pairs rendered through a known raw
stereo model; whole views are used, partial ones left out saying why."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

import stereo_scene as ss
from handeye.geometry.targets import CharucoBoard
from handeye.drivers.camera.stereo import load_stereo_model
from handeye.mocks.camera import StereoRenderer
from handeye.mocks.world import PrintedBoard, sample_board_views
from handeye.station.cli import main

BOARD = CharucoBoard((9, 6), 30.0, 22.0, "DICT_5X5_100")  # 10 x 7 squares


PARTIAL = {0: (60.0, 150.0), 3: (150.0, 240.0), 6: (0.0, 90.0), 9: (90.0, 180.0), 12: (30.0, 120.0)}  # mm covered


def test_stereo_calibrate_takes_charuco_views_of_part_of_the_board(tmp_path, capsys):
    """Issue 37: pairs that see part of the board (a band over a third of it) enter both cameras' intrinsics
    and the pair, their corners matched by id; the head comes out at the rendering truth. A pair whose
    common corners cannot fix the board's pose is left out of the pair, saying why."""
    from scipy.spatial.transform import Rotation

    model = ss.truth_model()
    printed = PrintedBoard(BOARD, 20.0)
    poses = sample_board_views(17, model, printed, seed=4, distance_mm=(450.0, 800.0), tilt_deg=(0, 40),
                               offset_px=250, views=("left", "right"), border_px=4)
    renderer = StereoRenderer(model, printed, seed=4)
    for k, pose in enumerate(poses):
        renderer.band = PARTIAL.get(k, (0.0, 180.0) if k == 16 else None)  # pair 016: 3 of 9 columns left
        left, right = renderer.gray_pair(pose)
        cv2.imwrite(str(tmp_path / f"{k:03d}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"{k:03d}_right.png"), right)
    out = tmp_path / "cal" / "xb3.yaml"
    code = main(["stereo", "calibrate", "--images", str(tmp_path), "--board", "charuco:squares=10x7,square_mm=30",
                 "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    calibrated = load_stereo_model(out)
    assert calibrated.baseline_mm == pytest.approx(np.linalg.norm(model.T), rel=0.005)
    assert np.allclose(calibrated.K1[:2, :3], model.K1[:2, :3], atol=5.0)
    assert np.allclose(calibrated.K2[:2, :3], model.K2[:2, :3], atol=5.0)
    turn = Rotation.from_matrix(np.asarray(calibrated.R) @ np.asarray(model.R).T).magnitude()
    assert np.degrees(turn) < 0.1
    report = json.loads((tmp_path / "cal" / "xb3.json").read_text())
    views = {v["name"]: v for v in report["views"]}
    for k in PARTIAL:  # the partial pairs are used, with a pair error like the whole ones'
        view = views[f"{k:03d}"]
        assert view["used_left"] and view["used_right"] and view["used_pair"], view
        assert view["pair_rms_px"] < 3 * report["rms_px"] + 0.2
    assert not views["016"]["used_pair"] and any("too little to fix its pose" in r for r in views["016"]["reasons"])


def test_pairs_are_matched_by_id_and_each_view_takes_the_points_of_its_ids():
    """``calibrate_stereo`` on exact projections: the right image of each pair sees other ids than the left
    (each loses a different part); the fit is exact (RMS ~ 0) only when the corners are matched by id."""
    from handeye.drivers.camera.stereo_fit import ViewCorners, calibrate_stereo

    model = ss.truth_model()
    grid = BOARD.grid()
    poses = sample_board_views(12, model, PrintedBoard(BOARD, 20.0), seed=2, distance_mm=(500.0, 800.0),
                               tilt_deg=(10, 40), offset_px=200, views=("left", "right"), border_px=4)
    rng = np.random.default_rng(0)
    views = []
    for k, pose in enumerate(poses):
        pts = grid @ pose[:3, :3].T + pose[:3, 3]
        lids = np.sort(rng.choice(BOARD.count, 40, replace=False)) if k % 2 else None
        rids = np.sort(rng.choice(BOARD.count, 44, replace=False)) if k % 2 else None
        left = model.project(pts, "left")
        right = model.project(pts, "right")
        views.append(ViewCorners(f"{k:02d}", left if lids is None else left[lids], right if rids is None else right[rids],
                                 left_ids=lids, right_ids=rids))
    pts = grid @ poses[0][:3, :3].T + poses[0][:3, 3]
    col = np.arange(BOARD.count) % BOARD.corners[0]
    lids, rids = np.flatnonzero(col < 4), np.flatnonzero(col >= 6)  # the two images share no corner
    views.append(ViewCorners("apart", model.project(pts, "left")[lids], model.project(pts, "right")[rids],
                             left_ids=lids, right_ids=rids))
    result = calibrate_stereo(views, BOARD, model.image_size, refine=False)
    assert result.rms_px < 1e-3 and result.pairs_used == 12
    apart = next(v for v in result.views if v.name == "apart")
    assert apart.used_left and apart.used_right and not apart.used_pair
    assert any(r.startswith("pair: the corners both images saw (matched by id): only 0 corners") for r in apart.reasons), apart.reasons
    assert result.baseline_mm == pytest.approx(np.linalg.norm(model.T), rel=1e-4)


def test_triangulate_takes_a_charuco_board_and_writes_the_corner_ids(tmp_path, capsys):
    from handeye.geometry.targets import STATION_CHARUCO
    from handeye.mocks.camera import MockCamera

    camera = MockCamera(board=PrintedBoard(STATION_CHARUCO), seed=5, output="gray", render_centre=False)
    camera.renderer.band = (120.0, 240.0)
    with camera:
        frame = camera.grab()
    cv2.imwrite(str(tmp_path / "l.png"), frame.left)
    cv2.imwrite(str(tmp_path / "r.png"), frame.right)
    code = main(["triangulate", "--left", str(tmp_path / "l.png"), "--right", str(tmp_path / "r.png"), "--board", "charuco",
                 "--json", str(tmp_path / "t.json")])
    assert code == 0, capsys.readouterr().err
    data = json.loads((tmp_path / "t.json").read_text())
    ids = np.array(data["corner_ids"])
    assert data["board"]["type"] == "charuco" and len(ids) == len(data["points_mm"]) < 104
    truth = frame.info["target2cam_truth"]
    true_points = STATION_CHARUCO.grid() @ truth[:3, :3].T + truth[:3, 3]
    assert np.sqrt(np.mean(np.sum((np.array(data["points_mm"]) - true_points[ids]) ** 2, axis=1))) < 0.6
    col = ids % 13
    assert not np.any((col >= 5) & (col <= 7))  # the covered columns (x 150-210 mm) are not among them
