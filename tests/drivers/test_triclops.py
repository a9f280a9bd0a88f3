"""The factory (Triclops) calibration read as a rectified stereo model: .cal headers, API values in
YAML or INI, normalised values, units, and refusals that say what to write."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.drivers.camera.errors import StereoModelError
from handeye.drivers.camera.triclops import parse_triclops_text, read_triclops_model, rectified_model

CAL = """Version 2
SerialNumber 5061234
SensorResolution 1024 768
FocalLength 0.800247 1.067
ImageCenter 0.5031 0.5112
BaseLine 0.120031
CameraConfiguration 2
Camera 0 0.0 0.0 0.0
-0.001 0.002 0.003 0.004 0.005
"""


def test_cal_header():
    v = parse_triclops_text(CAL)
    assert (v["width"], v["height"]) == (1024, 768)
    assert v["f_px"] == pytest.approx(819.45, abs=0.01)   # f/W * W; f/H * H gives the same 819.5
    assert (v["cx"], v["cy"]) == (pytest.approx(0.5031 * 1024), pytest.approx(0.5112 * 768))
    assert v["baseline_mm"] == pytest.approx(120.031)
    m = rectified_model(v)
    assert m.T[0] == pytest.approx(-120.031) and np.all(m.R == np.eye(3)) and np.all(m.D2 == 0)
    assert "Triclops" in m.name


@pytest.mark.parametrize("text", [
    "image_width: 1280\nimage_height: 960\nfocal_length: 983.0\ncenter_row: 493.4\ncenter_col: 643.6\nbaseline: 0.23998\n",
    "[triclops]\nimage_width = 1280\nimage_height = 960\nfocal_length = 983.0\ncenter_row = 493.4\ncenter_col = 643.6\n"
    "baseline_mm = 239.98\n",
    "width = 1280\nheight = 960\nfocal_length_px = 983\ncy = 493.4\ncx = 643.6\nbaseline_m = 0.23998\n",
    "triclops:\n  image_width: 1280\n  image_height: 960\n  focal_length: 0.76796875\n  center_row: 0.513958\n"
    "  center_col: 0.502813\n  baseline: 0.23998\n",
])
def test_api_values_in_yaml_or_ini(text):
    m = rectified_model(parse_triclops_text(text))
    assert m.image_size == (1280, 960)
    assert m.K1[0, 0] == pytest.approx(983.0, abs=0.01)
    assert m.K1[0, 2] == pytest.approx(643.6, abs=0.01) and m.K1[1, 2] == pytest.approx(493.4, abs=0.01)
    assert m.baseline_mm == pytest.approx(239.98)


def test_scaling_keeps_pixel_centres(tmp_path):
    path = tmp_path / "f.yaml"
    path.write_text("image_width: 1280\nimage_height: 960\nfocal_length: 983.0\ncenter_row: 493.4\n"
                    "center_col: 643.6\nbaseline: 0.23998\n")
    half = read_triclops_model(path, size=(640, 480))
    assert half.K1[0, 0] == pytest.approx(491.5)
    assert half.K1[0, 2] == pytest.approx((643.6 + 0.5) / 2 - 0.5)


@pytest.mark.parametrize("text, message", [
    ("focal_length: 983\ncenter_row: 493\ncenter_col: 643\nbaseline: 0.24\n", "give image_width and image_height"),
    ("image_width: 1280\nimage_height: 960\nfocal_length: 983\ncenter_row: 493\nbaseline: 0.24\n", "missing center_col"),
    ("image_width: 1280\nimage_height: 960\nfocal_length: 983\ncenter_row: 493\ncenter_col: 643\nbaseline: 240\n",
     "write baseline_mm: 240"),
    ("image_width: 1280\nimage_height: 960\nfocal_length: 983\ncenter_row: 643.6\ncenter_col: 493.4\nbaseline: 0.24\n",
     "ROW first"),
    ("FocalLength 0.8 1.06\nImageCenter 0.5 0.5\nBaseLine 0.12\n", "no SensorResolution line"),
    ("just some words\n", "neither a Triclops .cal file"),
    ("image_width: 1280\nimage_height: 960\nfocal_length: 40000\ncenter_row: 480\ncenter_col: 640\nbaseline: 0.24\n",
     "focal length 40000.0 px is not plausible"),
])
def test_refusals_say_what_to_write(text, message):
    with pytest.raises(StereoModelError, match=message):
        parse_triclops_text(text)


def test_files(tmp_path):
    with pytest.raises(StereoModelError, match="Triclops file not found"):
        read_triclops_model(tmp_path / "none.cal")
    binary = tmp_path / "b.cal"
    binary.write_bytes(b"\x00\x01\x02" * 100)
    with pytest.raises(StereoModelError, match="binary file"):
        read_triclops_model(binary)
    latin = tmp_path / "l.cal"
    latin.write_bytes(CAL.encode() + b"\xe9\xff warp grid\n")
    assert read_triclops_model(latin).baseline_mm == pytest.approx(120.031)
