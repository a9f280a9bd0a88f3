"""A wrong ``--board`` in ``stereo calibrate`` is refused after the first pairs, naming the board size the
images show, instead of after every image with "capture more pairs" (issue 25, finding 7g)."""

from __future__ import annotations

import pytest

import stereo_scene as ss
from handeye.geometry.board import BoardGeometry
from handeye.station import stereo_from_pairs as sc
from handeye.station.cli import main


@pytest.fixture(scope="module")
def scene():
    return ss.hard_scene()


@pytest.fixture
def images_searched(monkeypatch):
    """Counts the images the board is searched in."""
    seen = []
    real = sc._detect

    def counting(image, board, what):
        seen.append(what)
        return real(image, board, what)

    monkeypatch.setattr(sc, "_detect", counting)
    return seen


def test_wrong_board_is_refused_after_the_first_pairs_naming_the_right_one(scene, images_searched):
    pairs = sc.find_pairs(scene.folder)
    assert len(pairs) > sc.EARLY_PAIRS
    with pytest.raises(sc.StereoInputError) as info:
        sc.detect_pairs(pairs, BoardGeometry((8, 6), 30.0))
    message = str(info.value)
    assert message.startswith(f"no checkerboard of 8x6 inner corners found in the first {sc.EARLY_PAIRS} pairs: "
                              "check --board")
    assert "give --board 9x6" in message and "\n" not in message
    assert len(images_searched) == 2 * sc.EARLY_PAIRS  # not every image of the set


def test_cli_wrong_board_is_one_line_without_capture_more_pairs(scene, tmp_path, capsys, images_searched):
    code = main(["stereo", "calibrate", "--images", str(scene.folder), "--board", "7x5", "--square-mm", "30",
                 "-o", str(tmp_path / "s.yaml")])
    err = capsys.readouterr().err
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "no checkerboard of 7x5 inner corners found in the first" in lines[0], err
    assert "capture more pairs" not in err
    assert len(images_searched) == 2 * sc.EARLY_PAIRS


def test_the_right_board_goes_on_past_the_first_pairs(scene, images_searched):
    pairs = sc.find_pairs(scene.folder)[:sc.EARLY_PAIRS + 1]
    views, size = sc.detect_pairs(pairs, BoardGeometry((9, 6), 30.0))
    assert len(views) == sc.EARLY_PAIRS + 1 and size == (1280, 960)
