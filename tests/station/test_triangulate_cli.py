"""``handeye triangulate``: PNG pairs and raw XB3 frames in, points_mm in target order out; bad input
gives one line on stderr and exit status 1."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from handeye.geometry.board import board_corners
from handeye.drivers.camera.stereo import nominal_xb3_model, save_stereo_model
from handeye.mocks.camera import StereoRenderer
from handeye.mocks.world import PrintedBoard, board_view
from handeye.station.cli import main

MODEL = nominal_xb3_model()
BOARD = PrintedBoard()


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("triangulate")
    pose = board_view(950, 22, 40, 160, BOARD, (120, 10))
    renderer = StereoRenderer(MODEL, BOARD, seed=8)
    left, right = renderer.gray_pair(pose)
    cv2.imwrite(str(folder / "left.png"), left)
    cv2.imwrite(str(folder / "right.png"), right)
    frame = renderer.xb3_frame(pose)
    frame.tofile(folder / "frame.raw")
    (folder / "truncated.raw").write_bytes(frame.tobytes()[:2_000_000])
    cv2.imwrite(str(folder / "blank.png"), np.full_like(left, 110))
    half = left.copy()
    half[:, 640:] = 110
    cv2.imwrite(str(folder / "half.png"), half)
    cv2.imwrite(str(folder / "small.png"), left[:480, :640])
    save_stereo_model(folder / "stereo.yaml", MODEL)
    truth = board_corners(BOARD.corners, BOARD.square_mm) @ pose[:3, :3].T + pose[:3, 3]
    return folder, truth


def _run(capsys, *args):
    code = main(["triangulate", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


def _rms(points, truth):
    return float(np.sqrt(np.mean(np.sum((np.asarray(points) - truth) ** 2, axis=1))))


def test_png_pair(scene, capsys):
    folder, truth = scene
    out_file = folder / "pair.json"
    code, out, err = _run(capsys, "--left", folder / "left.png", "--right", folder / "right.png",
                          "--stereo", folder / "stereo.yaml", "--board", "13x8", "--square-mm", "30",
                          "--json", out_file)
    assert code == 0, err
    data = json.loads(out_file.read_text())
    assert len(data["points_mm"]) == 104 and all(len(p) == 3 for p in data["points_mm"])
    assert _rms(data["points_mm"], truth) < 0.35
    assert 0 < data["runtime_s"] < 5
    assert data["quality"]["corners"] == 104 and data["quality"]["row_disagreement_rms_px"] < 0.1
    assert abs(data["quality"]["square_error_mm"]) < 0.1
    assert data["board"] == {"corners": [13, 8], "square_mm": 30.0}
    assert "104 corners" in out and "pair.json" in out


def test_raw_xb3_frame_with_the_default_stereo_model(scene, capsys):
    folder, truth = scene
    code, out, err = _run(capsys, "--xb3-raw", folder / "frame.raw", "--json", "-")
    assert code == 0, err
    data = json.loads(out)
    assert data["source"] == "xb3-raw" and data["stereo"].startswith("nominal XB3")
    assert _rms(data["points_mm"], truth) < 0.5


@pytest.mark.parametrize(
    "args, message",
    [
        (["--left", "blank.png", "--right", "right.png"], "no checkerboard in the left image"),
        (["--left", "half.png", "--right", "right.png"], "checkerboard"),  # either message: a hint only
        (["--left", "left.png", "--right", "right.png", "--board", "12x8"], "has 13x8 inner corners, not 12x8: give --board 13x8"),
        (["--left", "left.png", "--right", "right.png", "--board", "9x6"], "has 13x8 inner corners, not 9x6: give --board 13x8"),
        (["--xb3-raw", "truncated.raw"], "2000000 bytes, but a 1280x960 3-sensor RGB8 XB3 frame has 3686400"),
        (["--left", "small.png", "--right", "right.png"], "left image is 640x480 but right image is 1280x960"),
        (["--left", "right.png", "--right", "left.png"], "swapped"),
        (["--left", "nothere.png", "--right", "right.png"], "file not found"),
        (["--left", "left.png"], "give both --left and --right"),
        (["--left", "left.png", "--right", "right.png", "--xb3-raw", "frame.raw"], "either"),
        (["--left", "left.png", "--right", "right.png", "--stereo", "left.png"], "left.png is a binary file, not text"),
        (["--left", "left.png", "--right", "right.png", "--square-mm", "3"],
         "corners measure 30 mm apart but the square size given is 3 mm"),
        (["--left", "left.png", "--right", "right.png", "--square-mm", "33"], "more than 5 % off"),
        (["--left", "stereo.yaml", "--right", "right.png"], "not an image"),
    ],
)
def test_bad_input_is_one_line_and_exit_1(scene, capsys, monkeypatch, args, message):
    folder, _ = scene
    monkeypatch.chdir(folder)
    code, out, err = _run(capsys, *args)
    assert code == (2 if message in ("give both --left and --right", "either") else 1)  # usage errors exit 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handeye triangulate: error: "), err
    assert message in lines[0]
    assert "Traceback" not in err


@pytest.mark.parametrize("board, message", [
    ("13", "corners must look like 13x8"),
    ("8x13", "give the long side first: 13x8, not 8x13"),
    ("1x8", "at least 2x2"),
])
def test_a_board_written_another_way_is_a_usage_error(scene, capsys, monkeypatch, board, message):
    folder, _ = scene
    monkeypatch.chdir(folder)
    with pytest.raises(SystemExit) as stop:
        _run(capsys, "--left", "left.png", "--right", "right.png", "--board", board)
    assert stop.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handeye triangulate: error: ") and message in lines[0]


def test_help_lists_the_command(capsys):
    with pytest.raises(SystemExit) as info:
        main(["triangulate", "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "--xb3-raw" in text and "nominal XB3 wide pair" in text and "Example" in text
