"""``handeye stereo calibrate`` and ``handeye stereo triclops``: files written, what is printed, one-line
refusals (exit 1), the guided live loop on the mock camera."""

from __future__ import annotations

import json
import shutil

import cv2
import numpy as np
import pytest

import stereo_scene as ss
from handeye.base.errors import HandEyeError
from handeye.drivers.camera.coverage import Coverage
from handeye.drivers.camera.stereo import load_stereo_model
from handeye.station.cli import main
from handeye.station.stereo_from_pairs import StereoCalibrationConfig, capture_live, find_pairs


def _run(capsys, *args):
    code = main(["stereo", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


def _one_line_error(code, err, message):
    assert code == (2 if message.startswith("give ") else 1)  # "give one source ...": usage errors exit 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handeye stereo: error: "), err
    assert message in lines[0], lines[0]
    assert "Traceback" not in err


@pytest.fixture(scope="module")
def scene():
    return ss.hard_scene()


def test_calibrate_a_folder_writes_the_model_the_report_and_the_map(scene, tmp_path, capsys):
    out = tmp_path / "cal" / "xb3.yaml"
    factory = tmp_path / "factory.ini"
    factory.write_text("[triclops]\nimage_width = 1280\nimage_height = 960\nfocal_length = 983.0\ncenter_row = 493.4\n"
                       "center_col = 643.6\nbaseline = 0.23998\n")
    code, text, err = _run(capsys, "calibrate", "--images", scene.folder, "--board", "9x6", "--square-mm", "30",
                           "-o", out, "--factory", factory)
    assert code == 0, err
    model = load_stereo_model(out)
    assert model.image_size == (1280, 960)
    assert model.baseline_mm == pytest.approx(240.5, abs=1.2) and model.T[0] < 0
    assert "rms_px:" in out.read_text() and "epipolar_rms_px:" in out.read_text()
    report = json.loads((tmp_path / "cal" / "xb3.json").read_text())
    assert report["pairs_given"] == len(scene.names) and report["pairs_used"] >= 12
    assert report["rms_px"] < 0.5 and report["epipolar_rms_px"] < 0.3
    assert set(report["coverage"]) >= {"left", "right", "tilts", "complete"}
    image = cv2.imread(str(tmp_path / "cal" / "xb3_coverage.png"))
    assert image is not None and image.shape[1] > 1000
    assert "RMS" in text and "epipolar" in text and "baseline" in text and "handeye triangulate" in text
    assert report["factory"]["factory"]["baseline_mm"] == pytest.approx(239.98)
    assert report["factory"]["baseline_difference_percent"] == pytest.approx(100 * (240.5 / 239.98 - 1), abs=0.5)
    assert "factory (Triclops rectified): baseline 239.98 mm" in text


def test_globs_and_swapped_images(scene, tmp_path, capsys):
    left, right = f"{scene.folder}/*_left.png", f"{scene.folder}/*_right.png"
    code, _, err = _run(capsys, "calibrate", "--left", right, "--right", left, "--board", "9x6", "-o",
                        tmp_path / "s.yaml")
    _one_line_error(code, err, "the images given as left are the RIGHT camera's")
    assert "--swap" in err and not (tmp_path / "s.yaml").exists()
    code, _, err = _run(capsys, "calibrate", "--left", right, "--right", left, "--swap", "--board", "9x6",
                        "--no-refine", "-o", tmp_path / "s.yaml")
    assert code == 0, err
    assert load_stereo_model(tmp_path / "s.yaml").T[0] < 0


def test_globs_without_left_right_names_pair_in_sorted_order(tmp_path):
    for name in ("cam0/img_2.png", "cam0/img_1.png", "cam1/img_1.png", "cam1/img_2.png"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_bytes(b"")
    pairs = find_pairs(left=f"{tmp_path}/cam0/*.png", right=f"{tmp_path}/cam1/*.png")
    assert [(n, a.name, b.name) for n, a, b in pairs] == [("img_1", "img_1.png", "img_1.png"), ("img_2", "img_2.png", "img_2.png")]
    (tmp_path / "cam1" / "img_3.png").write_bytes(b"")
    with pytest.raises(HandEyeError, match="2 left and 3 right images"):
        find_pairs(left=f"{tmp_path}/cam0/*.png", right=f"{tmp_path}/cam1/*.png")


def test_pairs_are_matched_by_name(tmp_path):
    for name in ("left/01.png", "right/01.png", "left/02.png", "right/02.png", "notes.txt"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_bytes(b"")
    pairs = find_pairs(tmp_path)
    assert [(n, a.relative_to(tmp_path).as_posix(), b.relative_to(tmp_path).as_posix()) for n, a, b in pairs] == [
        ("01", "left/01.png", "right/01.png"), ("02", "left/02.png", "right/02.png")]


@pytest.mark.parametrize("setup, args, message", [
    ("empty", ["--images", "{d}"], "no image pairs in"),
    ("unmatched", ["--images", "{d}"], "has no right image beside it"),
    ("sizes", ["--images", "{d}"], "every image of a calibration must have the same size"),
    ("empty", ["--left", "{d}/*_l.png", "--right", "{d}/*_r.png"], "no file matches"),
    ("empty", ["--images", "{d}", "--camera", "mock"], "give one source of pairs"),
    ("empty", ["--left", "{d}/*.png"], "give both --left and --right"),
    ("few", ["--images", "{d}"], "at least 5 are needed"),
])
def test_bad_input_is_one_line(scene, tmp_path, capsys, setup, args, message):
    d = tmp_path / "pairs"
    d.mkdir()
    if setup == "unmatched":
        shutil.copy(scene.folder / "000_left.png", d / "000_left.png")
    if setup == "sizes":
        shutil.copy(scene.folder / "000_left.png", d / "000_left.png")
        cv2.imwrite(str(d / "000_right.png"), np.zeros((480, 640), np.uint8))
    if setup == "few":
        for name in scene.names[:3]:
            for side in ("left", "right"):
                shutil.copy(scene.folder / f"{name}_{side}.png", d / f"{name}_{side}.png")
    code, _, err = _run(capsys, "calibrate", *[a.format(d=d) for a in args], "--board", "9x6", "-o", tmp_path / "s.yaml")
    _one_line_error(code, err, message)


def test_a_bad_factory_file_is_refused_before_any_work(scene, tmp_path, capsys):
    bad = tmp_path / "factory.yaml"
    bad.write_text("focal_length: 983\n")
    code, out, err = _run(capsys, "calibrate", "--images", scene.folder, "--board", "9x6", "--factory", bad,
                          "-o", tmp_path / "s.yaml")
    _one_line_error(code, err, "missing center_row, center_col, baseline")
    assert out == ""  # refused before the pairs were read


def test_output_into_a_folder_is_refused(scene, tmp_path, capsys):
    code, _, err = _run(capsys, "calibrate", "--images", scene.folder, "--board", "9x6", "-o", tmp_path)
    _one_line_error(code, err, "it is a folder")


def test_live_guided_loop_on_the_mock_camera(tmp_path, capsys):
    out = tmp_path / "live.yaml"
    code, text, err = _run(capsys, "calibrate", "--camera", "mock", "--seed", "3", "--pairs", "8", "--board", "13x8",
                           "--square-mm", "30", "--save-images", tmp_path / "pairs", "-o", out)
    assert code == 0, err
    lines = text.splitlines()
    assert lines[0].startswith("MOCK camera")
    assert lines[1].startswith("next: hold the board in the top-left of the left image")
    assert any("cells covered: left 9/9, right 9/9; tilts 5/5" in line for line in lines)
    model = load_stereo_model(out)
    assert model.baseline_mm == pytest.approx(239.98, rel=0.003)  # the mock's head: the nominal XB3 pair
    np.testing.assert_allclose(model.K1[0, 0], 983.0, rtol=0.003)
    saved = sorted(p.name for p in (tmp_path / "pairs").iterdir())
    assert "000_left.png" in saved and len(saved) % 2 == 0
    report = json.loads(out.with_suffix(".json").read_text())
    assert report["coverage"]["complete"] and report["pairs_used"] >= 8


def test_the_live_loop_stops_after_max_grabs_and_says_why():
    class Still:  # a camera that always shows the same board: nothing new after the first view
        def __init__(self):
            self.frames = 0
            left, right = ss.hard_scene().image("001", "left"), ss.hard_scene().image("001", "right")
            from handeye.drivers.camera.interface import StereoFrame
            self.frame = StereoFrame(left, right)

        def grab(self, timeout_s=2.0):
            self.frames += 1
            return self.frame

    said = []
    config = StereoCalibrationConfig(output="x.yaml", board=ss.GEOMETRY, camera="still", pairs=5, max_grabs=6)
    camera = Still()
    views, size, coverage = capture_live(camera, config, said.append)
    assert camera.frames == 6 and len(views) == 1 and size == (1280, 960)
    assert isinstance(coverage, Coverage)
    assert said[-1].startswith("stopped after 6 frames with 1 pair;")


def test_triclops_file_to_stereo_yaml(tmp_path, capsys):
    cal = tmp_path / "head.cal"
    cal.write_text("Version 2\nSerialNumber 7654321\nSensorResolution 1280 960\nFocalLength 0.76797 1.023958\n"
                   "ImageCenter 0.502813 0.513958\nBaseLine 0.23998\nCameraConfiguration 3\n0.1 0.2 0.3\n")
    code, text, err = _run(capsys, "triclops", cal, "-o", tmp_path / "factory.yaml")
    assert code == 0, err
    model = load_stereo_model(tmp_path / "factory.yaml")
    assert model.K1[0, 0] == pytest.approx(0.76797 * 1280)
    assert model.K1[0, 2] == pytest.approx(0.502813 * 1280) and model.K1[1, 2] == pytest.approx(0.513958 * 960)
    assert model.baseline_mm == pytest.approx(239.98) and np.all(model.D1 == 0)
    assert "baseline 239.98 mm" in text
    bad = tmp_path / "bad.yaml"
    bad.write_text("focal_length: 983\ncenter_row: 643.6\ncenter_col: 493.4\nbaseline: 0.24\nimage_width: 1280\n"
                   "image_height: 960\n")
    code, _, err = _run(capsys, "triclops", bad, "-o", tmp_path / "x.yaml")
    _one_line_error(code, err, "Triclops gives the ROW first")


def test_help_teaches(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["stereo", "calibrate", "--help"])
    assert stop.value.code == 0
    text = capsys.readouterr().out
    for words in ("--images FOLDER", "--swap", "epipolar", "STEREO_coverage.png", "Examples", "T in mm"):
        assert words in text, words
    with pytest.raises(SystemExit):
        main(["stereo", "triclops", "--help"])
    text = capsys.readouterr().out
    assert "triclopsGetImageCenter" in text and "SensorResolution" in text
