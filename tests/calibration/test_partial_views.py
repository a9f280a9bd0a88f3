"""ChArUco targets and partial views (issue 37): the target registry, the session format, and solving
from views that saw part of the board, checked against the synthetic truth."""

from dataclasses import replace

import numpy as np
import pytest

from handeye.base.errors import CalibrationError, SessionError
from handeye.calibration.partial_views import MIN_CORNERS, board_arrays, rigid_fit, view_refusal
from handeye.calibration.session import Posture, Session, create_session, read_session, write_postures
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from handeye.geometry.targets import (STATION_CHARUCO, STATION_CIRCLES, CharucoBoard, TARGETS, parse_target_spec,
                                         target_from_dict, target_to_dict)
from handeye.geometry.transforms import rotation_error_deg, translation_error_mm


def test_the_registry_holds_the_three_kinds_and_round_trips_them():
    assert {"checkerboard", "charuco", "circles"} <= set(TARGETS.names())
    for board in (STATION_CHARUCO, STATION_CIRCLES, CharucoBoard((9, 6), 25.0, 18.0, "DICT_4X4_50", True)):
        assert target_from_dict(target_to_dict(board)) == board
    assert parse_target_spec("charuco") == STATION_CHARUCO
    assert parse_target_spec("charuco:squares=10x7,square_mm=25,marker_mm=18,legacy=true") == CharucoBoard(
        (9, 6), 25.0, 18.0, "DICT_5X5_100", True)


@pytest.mark.parametrize("data, words", [
    ({"type": "charuco", "marker_mm": 30}, "smaller than square_mm"),
    ({"type": "charuco", "dictionary": "DICT_4X4_50"}, "needs 63 markers"),
    ({"type": "charuco", "squares": [9, 14]}, "long side first"),
    ({"type": "hexagons"}, "type must be one of"),
])
def test_a_bad_description_is_refused_in_one_line(data, words):
    with pytest.raises(ValueError, match=words):
        target_from_dict(data)


def test_circle_grid_points_are_opencvs_asymmetric_layout():
    grid = STATION_CIRCLES.grid()
    assert grid.shape == (44, 3)
    assert np.allclose(grid[1] - grid[0], [40.0, 0, 0])        # one spacing along a row
    assert np.allclose(grid[4], [20.0, 20.0, 0])               # the second row is shifted by half a spacing


def test_a_view_too_small_to_fix_the_pose_is_refused_with_the_reason():
    nx = STATION_CHARUCO.corners[0]
    assert "only 4 corners" in view_refusal([0, 1, 2, 3], STATION_CHARUCO)
    one_column = [r * nx for r in range(8)] + [r * nx + 1 for r in range(8)]
    assert "span only" in view_refusal(one_column, STATION_CHARUCO)
    assert view_refusal(np.arange(STATION_CHARUCO.count), STATION_CHARUCO) == ""
    assert MIN_CORNERS >= 6


def _partial_session(seed=1, sigma=0.3, share=0.5):
    """A synthetic ChArUco session; every other posture sees a band of columns only."""
    scene = make_scene(SceneConfig(postures=20, seed=seed))
    scene = replace(scene, board=STATION_CHARUCO)
    session = sample_session(scene, NoiseConfig(sigma_cam_mm=sigma, camera_model="gaussian", seed=seed))
    rng = np.random.default_rng(seed)
    nx, ny = STATION_CHARUCO.corners
    col = np.arange(STATION_CHARUCO.count) % nx
    for p in session.postures:
        if rng.random() < share:
            start = rng.integers(0, 5)
            ids = np.nonzero((col < start) | (col >= start + 5))[0]  # a band of 5 of 13 columns covered
            p.points_mm, p.corner_ids = p.points_mm[ids], ids
    return scene, session


def test_partial_views_solve_to_the_truth_with_the_default_and_a_classic_method():
    scene, session = _partial_session()
    assert any(p.corner_ids is not None for p in session.postures)
    problem = problem_from_session(session)
    assert problem.seen is not None and not problem.seen.all()
    for method in (None, "daniilidis"):
        result = calibrate(problem, method)
        assert translation_error_mm(result.x, scene.x_true) < 0.5
        assert rotation_error_deg(result.x, scene.x_true) < 0.05


def test_the_unseen_corners_do_not_move_the_ml_fit():
    scene, session = _partial_session(seed=3)
    problem = problem_from_session(session)
    moved = problem.points_cam.copy()
    moved[~problem.seen] += 50.0  # the filled-in corners carry no weight
    a = calibrate(problem).x
    b = calibrate(replace(problem, points_cam=moved)).x
    assert translation_error_mm(a, b) < 1e-6 and rotation_error_deg(a, b) < 1e-7


def test_board_arrays_fill_the_unseen_corners_from_the_rigid_fit():
    board = STATION_CHARUCO
    model = board.grid()
    pose = rigid_fit(model[:3], model[:3] + [5.0, 0, 900.0])
    pts = model @ pose[:3, :3].T + pose[:3, 3]
    ids = np.arange(40, 90)
    points, seen, poses = board_arrays([Posture(0, np.eye(4), points_mm=pts[ids], corner_ids=ids)], board, 30.0)
    assert seen[0].sum() == 50 and np.allclose(points[0], pts) and np.allclose(poses[0], pose)


def test_sessions_keep_the_target_and_the_corner_ids(tmp_path):
    _, session = _partial_session(seed=2)
    create_session(tmp_path / "s", session)
    write_postures(tmp_path / "s", session.postures)
    back = read_session(tmp_path / "s")
    assert back.target == STATION_CHARUCO
    for a, b in zip(session.postures, back.postures):
        assert (a.corner_ids is None) == (b.corner_ids is None)
        if a.corner_ids is not None:
            assert np.array_equal(a.corner_ids, b.corner_ids)


def test_an_old_checkerboard_header_is_written_as_before(tmp_path):
    scene = make_scene(SceneConfig(postures=5))
    header = Session(target=scene.board).header()
    assert header["target"] == {"type": "checkerboard", "corners": [13, 8], "square_mm": 30.0}


def test_corner_ids_that_do_not_match_the_points_are_refused(tmp_path):
    _, session = _partial_session(seed=4, share=1.0)
    create_session(tmp_path / "s", session)
    p = session.postures[0]
    p.corner_ids = p.corner_ids[:-1]
    write_postures(tmp_path / "s", session.postures)
    with pytest.raises(SessionError, match="corner_ids has"):
        read_session(tmp_path / "s")


def test_a_posture_seeing_too_little_is_refused_naming_it():
    _, session = _partial_session(seed=5, share=0.0)
    p = session.postures[3]
    p.points_mm, p.corner_ids = p.points_mm[:4], np.arange(4)
    with pytest.raises(CalibrationError, match="posture 3: only 4 corners"):
        problem_from_session(session)


def test_a_charuco_description_without_its_square_size_is_refused_in_one_line():
    from handeye.geometry.targets import target_to_dict

    # float(None) used to raise a TypeError from deep inside; the description needs the square size
    with pytest.raises(ValueError, match="square_mm"):
        target_to_dict(CharucoBoard((13, 8)))
    assert target_to_dict(STATION_CHARUCO)["square_mm"] == 30.0
