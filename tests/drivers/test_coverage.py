"""Coverage of the images and board tilts, the hints of the guided loop, the map, and the mock operator
who follows the hints."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.drivers.camera.coverage import TILT_CLASSES, Coverage, Hint, coverage_map, tilt_class
from handeye.drivers.camera.stereo import nominal_xb3_model
from handeye.mocks.world import BoardOperator, PrintedBoard, board_view


def _board_at(x, y, size=(1280, 960), n=6, step=20.0):
    """A small grid of corners centred at (x, y) px."""
    g = np.stack(np.meshgrid(np.arange(n) * step, np.arange(n) * step), -1).reshape(-1, 2)
    return g - g.mean(axis=0) + [x, y]


@pytest.mark.parametrize("tilt, expected", [(0, "facing"), (10, "facing"), (17, None)])
def test_facing_and_in_between(tilt, expected):
    kind, angle = tilt_class(board_view(1000, tilt, 40.0, 0.0))
    assert kind == expected and angle == pytest.approx(tilt, abs=0.5)


def test_tilt_classes_name_the_nearer_edge():
    kinds = set()
    for azimuth in (0, 90, 180, 270):
        pose = board_view(1000, 30, azimuth, 0.0)
        kind, angle = tilt_class(pose)
        assert kind in TILT_CLASSES[1:] and angle == pytest.approx(30, abs=0.5)
        kinds.add(kind)
        # the named edge of the sheet is nearer the camera than the opposite one (camera x right, y down)
        corners = PrintedBoard().outline(8) @ pose[:3, :3].T + pose[:3, 3]
        x, y = corners[:, 0], corners[:, 1]
        side = {"left": x < np.median(x), "right": x > np.median(x), "top": y < np.median(y), "bottom": y > np.median(y)}
        edge = side[kind.split()[0]]
        assert corners[edge, 2].mean() < corners[~edge, 2].mean() - 50, kind
    assert kinds == set(TILT_CLASSES[1:])


def test_hints_walk_the_empty_cells_then_the_tilts():
    cov = Coverage((1280, 960))
    hint = cov.next_hint()
    assert (hint.side, hint.cell, hint.tilt) == ("left", (0, 0), "facing")
    assert hint.text == "hold the board in the top-left of the left image, facing the cameras squarely"
    for r in range(3):
        for c in range(3):
            cov.add(left=_board_at(213 + 427 * c, 160 + 320 * r), target2cam=board_view(1000, 0, 0, 0))
    hint = cov.next_hint()
    assert hint.side == "right" and hint.cell == (0, 0) and hint.tilt == "right edge nearer"
    assert "its right edge nearer the cameras" in hint.text
    for r in range(3):
        for c in range(3):
            cov.add(right=_board_at(213 + 427 * c, 160 + 320 * r))
    for azimuth in (0, 90, 180, 270):
        assert not cov.complete
        cov.add(target2cam=board_view(1000, 30, azimuth, 0))
    assert cov.complete and cov.next_hint() is None
    assert cov.summary() == "cells covered: left 9/9, right 9/9; tilts 5/5"
    assert cov.to_json()["complete"]


def test_a_view_covers_only_cells_with_enough_corners_and_left_out_views_do_not_count():
    cov = Coverage((1280, 960))
    corners = _board_at(420, 300)  # straddles four cells
    cells = cov.cells_of(corners)
    assert cells.sum() >= 1 and cells[0, 0]
    cov.add(left=corners, used=False)
    assert cov.left.sum() == 0 and len(cov.outlines) == 1


def test_coverage_map_picture():
    cov = Coverage((1280, 960))
    cov.add(left=_board_at(300, 300), right=_board_at(200, 300), target2cam=board_view(900, 0, 0, 0))
    image = coverage_map(cov, "title")
    assert image.dtype == np.uint8 and image.shape == (28 + 480 + 40, 1290, 3)
    # empty cells are drawn red (BGR: more red than green), covered ones green
    assert image[28 + 400, 600, 2] > image[28 + 400, 600, 1]
    assert image[28 + 150, 150, 1] > image[28 + 150, 150, 2]


@pytest.mark.parametrize("side, cell, tilt", [("left", (0, 0), "facing"), ("right", (2, 2), "top edge nearer"),
                                              ("left", (1, 2), "right edge nearer"), (None, None, "bottom edge nearer")])
def test_the_mock_operator_holds_the_board_where_asked(side, cell, tilt):
    model = nominal_xb3_model()
    board = PrintedBoard()
    operator = BoardOperator(model, board, seed=4)
    pose = operator.pose_for(Hint(side, cell, tilt, ""))
    assert tilt_class(pose)[0] == tilt
    if cell is not None:
        x, y = model.project(pose[:3, :3] @ board.centre() + pose[:3, 3], side)[0]
        assert (int(3 * y / 960), int(3 * x / 1280)) == cell
