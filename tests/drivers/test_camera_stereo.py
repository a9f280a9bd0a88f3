"""Stereo model: files, the nominal XB3 default, rectification once per model, exact triangulation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.drivers.camera.errors import StereoMismatch, StereoModelError
from handeye.drivers.camera.stereo import (
    NOMINAL_XB3,
    StereoModel,
    load_stereo_model,
    nominal_xb3_model,
    save_stereo_model,
)


def distorted_model() -> StereoModel:
    """A head that is not rectified: different intrinsics, lens distortion, a small rotation."""
    k1 = np.array([[990.0, 0.0, 650.0], [0.0, 985.0, 480.0], [0.0, 0.0, 1.0]])
    k2 = np.array([[975.0, 0.0, 630.0], [0.0, 978.0, 500.0], [0.0, 0.0, 1.0]])
    r = Rotation.from_euler("xyz", [0.4, -1.2, 0.3], degrees=True).as_matrix()
    return StereoModel((1280, 960), k1, [-0.08, 0.05, 0.0005, -0.0003, 0.0], k2, [-0.07, 0.04, -0.0002, 0.0004, 0.0],
                       r, [-240.5, 1.2, -0.8])


def random_points(n=200, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.uniform(500, 2000, n)
    x = rng.uniform(-0.3, 0.3, n) * z
    y = rng.uniform(-0.25, 0.25, n) * z
    return np.column_stack([x + 120, y, z])


def test_nominal_xb3_values():
    m = nominal_xb3_model()
    assert m.image_size == (1280, 960)
    assert m.K1[0, 0] == m.K1[1, 1] == 983.0
    assert (m.K1[0, 2], m.K1[1, 2]) == (643.6, 493.4)
    assert m.baseline_mm == pytest.approx(239.98)
    np.testing.assert_allclose(m.T, [-239.98, 0, 0])  # right camera at +x in the left camera's frame
    np.testing.assert_allclose(m.view("centre")[3], [-119.99, 0, 0])
    assert NOMINAL_XB3["f_px"] == 983.0
    half = nominal_xb3_model(640, 480)
    assert half.K1[0, 0] == pytest.approx(491.5)
    assert half.K1[0, 2] == pytest.approx((643.6 + 0.5) / 2 - 0.5)


@pytest.mark.parametrize("make", [nominal_xb3_model, distorted_model])
def test_triangulation_of_exact_projections_is_exact(make):
    m = make()
    pts = random_points()
    left, right = m.project(pts, "left"), m.project(pts, "right")
    tri = m.triangulate(left, right)
    np.testing.assert_allclose(tri.points_mm, pts, atol=1e-4)
    assert np.abs(tri.row_disagreement_px).max() < 1e-6
    assert np.all(tri.disparity_px > 0)


def test_row_disagreement_measures_vertical_offsets():
    m = nominal_xb3_model()
    pts = random_points(50, 1)
    left, right = m.project(pts, "left"), m.project(pts, "right")
    tri = m.triangulate(left, right + [0.0, 0.7])
    np.testing.assert_allclose(tri.row_disagreement_px, -0.7, atol=1e-9)
    # the mean row is used: a half-pixel change of the vertical position, not of the depth
    np.testing.assert_allclose(tri.points_mm[:, 2], pts[:, 2], rtol=1e-9)


def test_swapped_images_are_refused():
    m = nominal_xb3_model()
    pts = random_points(20, 2)
    with pytest.raises(StereoMismatch, match="swapped"):
        m.triangulate(m.project(pts, "right"), m.project(pts, "left"))
    with pytest.raises(StereoMismatch):
        m.triangulate(np.zeros((3, 2)), np.zeros((4, 2)))


def test_rectification_is_computed_once_and_maps_agree_with_points():
    m = distorted_model()
    assert m.rectification is m.rectification
    maps = m.rectification_maps()
    assert all(a is b for a, b in zip(maps, m.rectification_maps()))
    # The rectified image pixel (xr, yr) takes its value from the raw pixel map[yr, xr]; rectifying
    # that raw position must give (xr, yr) back.
    raw = np.array([[100.0, 120.0], [640.0, 480.0], [1100.0, 850.0]])
    rect_left, _ = m.rectify_points(raw, raw + [-200.0, 0.0])
    xr, yr = np.rint(rect_left).astype(int).T
    back = np.column_stack([maps[0][yr, xr], maps[1][yr, xr]])
    again, _ = m.rectify_points(back, back + [-200.0, 0.0])
    np.testing.assert_allclose(again, np.column_stack([xr, yr]), atol=0.02)


def test_file_round_trip(tmp_path):
    m = distorted_model()
    path = save_stereo_model(tmp_path / "stereo.yaml", m)
    assert path.read_text().startswith("%YAML:1.0")
    back = load_stereo_model(path)
    assert back.image_size == m.image_size
    for key in ("K1", "D1", "K2", "D2", "R", "T"):
        np.testing.assert_allclose(getattr(back, key), getattr(m, key), atol=1e-12)
    nominal = load_stereo_model(save_stereo_model(tmp_path / "nominal.yaml", nominal_xb3_model()))
    np.testing.assert_allclose(nominal.T3, [-119.99, 0, 0])


def test_plain_yaml_lists_are_accepted(tmp_path):
    path = tmp_path / "plain.yaml"
    path.write_text(
        "image_width: 1280\nimage_height: 960\n"
        "K1: [[983, 0, 643.6], [0, 983, 493.4], [0, 0, 1]]\nD1: [0, 0, 0, 0, 0]\n"
        "K2: [[983, 0, 643.6], [0, 983, 493.4], [0, 0, 1]]\nD2: [0, 0, 0, 0, 0]\n"
        "R: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nT: [-239.98, 0, 0]\n"
    )
    m = load_stereo_model(path)
    np.testing.assert_allclose(m.T, [-239.98, 0, 0])


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.replace("T: [-239.98, 0, 0]", "T: [-239.98, 0]"), "T must have 3 values"),
        (lambda t: t.replace("T: [-239.98, 0, 0]", "T: [239.98, 0, 0]"), "RIGHT camera"),
        (lambda t: t.replace("T: [-239.98, 0, 0]", "T: [0, -239.98, 0]"), "vertical pair"),
        (lambda t: t.replace("R: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]", "R: [[1, 0, 0], [0, 2, 0], [0, 0, 1]]"), "not a rotation"),
        (lambda t: t.replace("D2: [0, 0, 0, 0, 0]\n", ""), "missing D2"),
        (lambda t: t.replace("K1: [[983, 0, 643.6]", "K1: [[-983, 0, 643.6]"), "K1 is not a camera matrix"),
        # ragged lists: numpy refuses them with ValueError, which escaped as a traceback for the distortions
        (lambda t: t.replace("D1: [0, 0, 0, 0, 0]", "D1: [0, [0, 0], 0, 0]"), "D1 is not a matrix of numbers"),
        (lambda t: t.replace("D2: [0, 0, 0, 0, 0]", "D2: [0, 0, 0, [0, 0]]"), "D2 is not a matrix of numbers"),
    ],
)
def test_bad_files_are_refused_with_the_reason(tmp_path, edit, message):
    text = (
        "image_width: 1280\nimage_height: 960\n"
        "K1: [[983, 0, 643.6], [0, 983, 493.4], [0, 0, 1]]\nD1: [0, 0, 0, 0, 0]\n"
        "K2: [[983, 0, 643.6], [0, 983, 493.4], [0, 0, 1]]\nD2: [0, 0, 0, 0, 0]\n"
        "R: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nT: [-239.98, 0, 0]\n"
    )
    path = tmp_path / "bad.yaml"
    path.write_text(edit(text))
    with pytest.raises(StereoModelError, match=message):
        load_stereo_model(path)


def test_missing_and_foreign_files(tmp_path):
    with pytest.raises(StereoModelError, match="not found"):
        load_stereo_model(tmp_path / "nothere.yaml")
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    with pytest.raises(StereoModelError, match="junk.png is a binary file, not text"):
        load_stereo_model(junk)
