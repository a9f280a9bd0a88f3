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


def test_stereo_calibrate_takes_a_charuco_board(tmp_path, capsys):
    model = ss.truth_model()
    printed = PrintedBoard(BOARD, 20.0)
    poses = sample_board_views(16, model, printed, seed=4, distance_mm=(450.0, 800.0), tilt_deg=(0, 40),
                               offset_px=250, views=("left", "right"), border_px=4)
    renderer = StereoRenderer(model, printed, seed=4)
    for k, pose in enumerate(poses):
        renderer.band = (60.0, 150.0) if k == 0 else None  # one pair sees part of the board
        left, right = renderer.gray_pair(pose)
        cv2.imwrite(str(tmp_path / f"{k:03d}_left.png"), left)
        cv2.imwrite(str(tmp_path / f"{k:03d}_right.png"), right)
    out = tmp_path / "cal" / "xb3.yaml"
    code = main(["stereo", "calibrate", "--images", str(tmp_path), "--board", "charuco:squares=10x7,square_mm=30",
                 "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    calibrated = load_stereo_model(out)
    assert calibrated.baseline_mm == pytest.approx(np.linalg.norm(model.T), rel=0.01)
    assert np.allclose(calibrated.K1[:2, :3], model.K1[:2, :3], atol=8.0)
    report = json.loads((tmp_path / "cal" / "xb3.json").read_text())
    first = next(v for v in report["views"] if v["name"] == "000")
    assert not first["used_pair"] and any("whole board" in r for r in first["reasons"])


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
