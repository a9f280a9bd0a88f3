"""The mock XB3 renders OpenCV's ChArUco print into real XB3 frames, and covers a share of the postures
with a band (``mock.occlude``, issue 37)."""

import numpy as np
import pytest

from handeye.base.errors import ConfigError
from handeye.geometry.targets import STATION_CHARUCO
from handeye.drivers.camera.checkerboard import observe_board
from handeye.drivers.camera.errors import BoardNotFound
from handeye.mocks.camera import MockCamera
from handeye.mocks.printed_targets import Occlusion, OcclusionPicker
from handeye.mocks.world import PrintedBoard
from handeye.station.config.station import config_from_dict

MOCK = {"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}


def _observed(board):
    """One mock XB3 frame of ``board`` through the real detection: the observation and each corner's
    distance (mm) from the mock's true corner of the same id."""
    camera = MockCamera(board=PrintedBoard(board), seed=2, render_centre=False)
    with camera:
        frame = camera.grab()
    obs = observe_board(frame.left, frame.right, camera.model, board)
    truth = frame.info["target2cam_truth"]
    true_points = board.grid() @ truth[:3, :3].T + truth[:3, 3]
    return obs, np.linalg.norm(obs.points_mm - true_points[obs.corner_ids], axis=1)


def test_a_charuco_frame_through_the_xb3_layout_is_detected_by_id_at_the_true_corners():
    obs, error = _observed(STATION_CHARUCO)
    assert len(obs.corner_ids) >= 95
    assert np.sqrt(np.mean(error**2)) < 0.5


def test_the_occlusion_covers_the_asked_share_never_the_start_and_the_same_posture_alike():
    picker = OcclusionPicker(Occlusion(0.3, (0.2, 0.4)), STATION_CHARUCO, seed=7)
    poses = [np.eye(4) for _ in range(31)]
    for k, pose in enumerate(poses):
        pose[:3, 3] = [10.0 * k, 0.0, 0.0]
    bands = [picker.band(p) for p in poses]
    assert bands[0] is None and sum(b is not None for b in bands[1:]) == 9
    length = 14 * 30.0
    for band in filter(None, bands):
        assert 0.2 * length - 1e-9 <= band[1] - band[0] <= 0.4 * length + 1e-9
    assert [picker.band(p) for p in poses] == bands


def test_a_checkerboard_under_the_band_is_lost_and_a_charuco_board_kept():
    for board, keeps in ((None, False), (STATION_CHARUCO, True)):
        camera = MockCamera(board=PrintedBoard(board) if board else None, seed=3, render_centre=False, output="gray")
        camera.renderer.band = (90.0, 210.0)
        with camera:
            frame = camera.grab()
        geometry = camera.board.geometry
        if keeps:
            assert 40 <= len(observe_board(frame.left, frame.right, camera.model, geometry).corner_ids) < 104
        else:
            with pytest.raises(BoardNotFound):
                observe_board(frame.left, frame.right, camera.model, geometry)


def test_the_station_config_takes_a_board_section_and_mock_occlude():
    config = config_from_dict({**MOCK, "board": {"type": "charuco", "squares": [14, 9]}, "mock": {"occlude": {"postures": 0.3}}})
    assert config.target == STATION_CHARUCO and config.mock.occlude == Occlusion(0.3, (0.2, 0.4))
    with pytest.raises(ConfigError, match="not both"):
        config_from_dict({**MOCK, "board": {"type": "charuco"}, "target": {"corners": [13, 8]}})
    with pytest.raises(ConfigError, match="mock.occlude.postures"):
        config_from_dict({**MOCK, "mock": {"occlude": {"postures": 2}}})
    with pytest.raises(ConfigError, match="marker_mm"):
        config_from_dict({**MOCK, "board": {"type": "charuco", "marker_mm": 40}})


def test_a_circle_grid_frame_is_found_whole_at_the_true_centres():
    from handeye.geometry.targets import STATION_CIRCLES

    obs, error = _observed(STATION_CIRCLES)
    assert len(obs.corner_ids) == STATION_CIRCLES.count
    assert np.sqrt(np.mean(error**2)) < 0.5
    assert abs(obs.quality["square_mm_measured"] - STATION_CIRCLES.square_mm) < 0.1


def test_the_circle_sheet_is_black_discs_of_half_the_row_spacing_on_white():
    from handeye.geometry.targets import STATION_CIRCLES
    from handeye.mocks.printed_targets import circle_labels

    board = PrintedBoard(STATION_CIRCLES)
    centres = STATION_CIRCLES.grid()
    r = 0.25 * STATION_CIRCLES.square_mm
    u = np.concatenate([centres[:, 0] + 0.9 * r, centres[:, 0] + 1.1 * r])
    v = np.concatenate([centres[:, 1], centres[:, 1]])
    labels = circle_labels(u, v, np.ones(len(u), bool), board)
    n = len(centres)
    assert np.all(labels[:n] == 2) and np.all(labels[n:] == 1)
