"""XB3 frame decoding on synthetic buffers: byte layouts, the GBRG debayer constant, mono pass-through."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from handeye.drivers.camera.decode import (
    GBRG_TO_BGR,
    debayer_gbrg,
    decode_xb3_frame,
    deinterleave,
    frame_bytes,
    pack_raw16,
    pack_rgb8,
    to_gray,
)
from handeye.drivers.camera.errors import CameraError, FrameError
from handeye.drivers.camera.interface import StereoFrame

H, W = 6, 8


def _planes(seed=0, n=3, h=H, w=W):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (h, w), dtype=np.uint8) for _ in range(n)]


def _interleave(*planes) -> bytes:
    """Reference packing written out byte by byte: pixel (r, c) -> bytes planes[0], planes[1], ..."""
    k = len(planes)
    out = np.empty(planes[0].size * k, np.uint8)
    for i, p in enumerate(planes):
        out[i::k] = p.ravel()
    return out.tobytes()


def test_rgb8_byte0_is_right_byte1_centre_byte2_left():
    right, centre, left = _planes()
    planes = deinterleave(_interleave(right, centre, left), "rgb8", W, H)
    assert set(planes) == {"right", "centre", "left"}
    np.testing.assert_array_equal(planes["right"], right)
    np.testing.assert_array_equal(planes["centre"], centre)
    np.testing.assert_array_equal(planes["left"], left)
    # the reference's numpy form: buf.reshape(h, w, 3)[..., 0] is the right sensor
    buf = np.frombuffer(_interleave(right, centre, left), np.uint8)
    np.testing.assert_array_equal(buf.reshape(H, W, 3)[..., 0], right)


def test_pack_rgb8_is_the_inverse_of_deinterleave():
    right, centre, left = _planes(1)
    packed = pack_rgb8(right, centre, left)
    assert packed.tobytes() == _interleave(right, centre, left)


def test_raw16_little_endian_byte0_right_byte1_left():
    right, left = _planes(2, n=2)
    data = _interleave(right, left)
    planes = deinterleave(data, "raw16", W, H)
    np.testing.assert_array_equal(planes["right"], right)
    np.testing.assert_array_equal(planes["left"], left)
    # the same bytes read as little-endian 16-bit words: low byte right, high byte left
    words = np.frombuffer(data, "<u2").reshape(H, W)
    np.testing.assert_array_equal(words & 0xFF, right)
    np.testing.assert_array_equal(words >> 8, left)
    assert pack_raw16(right, left).tobytes() == data


def test_frame_sizes():
    assert frame_bytes("rgb8") == 1280 * 960 * 3 == 3_686_400
    assert frame_bytes("raw16") == 1280 * 960 * 2


def test_truncated_buffer_is_a_frame_error_naming_the_sizes():
    right, centre, left = _planes()
    data = _interleave(right, centre, left)
    with pytest.raises(FrameError, match=rf"truncated: got {len(data) - 5} bytes.*has {len(data)}"):
        deinterleave(data[:-5], "rgb8", W, H)
    with pytest.raises(FrameError, match="too long"):
        deinterleave(data + b"\0" * 7, "rgb8", W, H)
    planes = deinterleave(data + b"\0" * 7, "rgb8", W, H, allow_padding=True)
    np.testing.assert_array_equal(planes["left"], left)
    assert issubclass(FrameError, CameraError)


def test_bad_buffers_and_layouts():
    with pytest.raises(FrameError, match="byte buffer"):
        deinterleave(np.zeros(W * H * 3, np.float32), "rgb8", W, H)
    with pytest.raises(FrameError, match="unknown XB3 frame layout"):
        deinterleave(b"\0" * (W * H * 3), "yuv", W, H)
    with pytest.raises(FrameError, match="byte buffer"):
        deinterleave(12345, "rgb8", W, H)


def _mosaic_gbrg(bgr: np.ndarray) -> np.ndarray:
    """GBRG mosaic: first row G B G B, second row R G R G."""
    b, g, r = bgr[..., 0], bgr[..., 1], bgr[..., 2]
    m = np.empty(bgr.shape[:2], np.uint8)
    m[0::2, 0::2] = g[0::2, 0::2]
    m[0::2, 1::2] = b[0::2, 1::2]
    m[1::2, 0::2] = r[1::2, 0::2]
    m[1::2, 1::2] = g[1::2, 1::2]
    return m


def test_gbrg_debayers_with_opencv_bayer_gr_constant():
    # Patches of distinct, saturated colours; the interior of each must come back with its colour.
    colours = [(30, 120, 220), (200, 40, 90), (60, 230, 20)]  # B, G, R
    bgr = np.zeros((24, 48, 3), np.uint8)
    for k, c in enumerate(colours):
        bgr[:, 16 * k: 16 * (k + 1)] = c
    out = debayer_gbrg(_mosaic_gbrg(bgr), "bgr")
    for k, c in enumerate(colours):
        interior = out[4:20, 16 * k + 4: 16 * k + 12].reshape(-1, 3)
        np.testing.assert_allclose(interior.mean(axis=0), c, atol=1.0)
    assert GBRG_TO_BGR == cv2.COLOR_BayerGR2BGR
    # Any other pattern name swaps or mixes the colours on this mosaic.
    wrong = cv2.cvtColor(_mosaic_gbrg(bgr), cv2.COLOR_BayerGB2BGR)
    assert np.abs(wrong[4:20, 4:12].reshape(-1, 3).mean(axis=0) - colours[0]).max() > 50


def test_gray_debayer_of_a_neutral_mosaic_is_the_grey_image():
    rng = np.random.default_rng(3)
    grey = cv2.GaussianBlur(rng.integers(40, 220, (32, 32)).astype(np.uint8), (0, 0), 3)
    bgr = np.repeat(grey[..., None], 3, axis=2)
    out = debayer_gbrg(_mosaic_gbrg(bgr), "gray")
    assert np.abs(out[2:-2, 2:-2].astype(int) - grey[2:-2, 2:-2]).max() <= 3


def test_decode_colour_frame_to_stereo_frame():
    colours = {"right": (10, 200, 30), "centre": (120, 120, 120), "left": (220, 40, 90)}
    planes = {k: _mosaic_gbrg(np.full((16, 16, 3), c, np.uint8)) for k, c in colours.items()}
    data = _interleave(planes["right"], planes["centre"], planes["left"])
    frame = decode_xb3_frame(data, "rgb8", 16, 16, colour=True, output="bgr", timestamp=12.5, serial=42, keep_raw=True)
    assert isinstance(frame, StereoFrame)
    assert frame.size == (16, 16) and frame.serial == 42 and frame.timestamp == 12.5 and frame.colour
    for name in ("left", "right", "centre"):
        img = getattr(frame, name)
        assert img.shape == (16, 16, 3)
        np.testing.assert_allclose(img[4:12, 4:12].reshape(-1, 3).mean(axis=0), colours[name], atol=1.0)
    assert frame.raw.shape == (16, 16, 3)
    np.testing.assert_array_equal(frame.raw[..., 2], planes["left"])
    no_centre = decode_xb3_frame(data, "rgb8", 16, 16, output="gray", centre=False)
    assert no_centre.centre is None and no_centre.left.shape == (16, 16)


def test_mono_planes_pass_through():
    right, centre, left = _planes(4)
    frame = decode_xb3_frame(_interleave(right, centre, left), "rgb8", W, H, colour=False, output="gray")
    np.testing.assert_array_equal(frame.left, left)
    np.testing.assert_array_equal(frame.right, right)
    np.testing.assert_array_equal(frame.centre, centre)
    bgr = decode_xb3_frame(_interleave(right, centre, left), "rgb8", W, H, colour=False, output="bgr")
    np.testing.assert_array_equal(bgr.left[..., 1], left)
    two = decode_xb3_frame(_interleave(right, left), "raw16", W, H, colour=False, output="gray")
    np.testing.assert_array_equal(two.left, left)
    assert two.centre is None


def test_to_gray():
    img = np.zeros((4, 4, 3), np.uint8)
    img[..., 1] = 100
    assert to_gray(img).shape == (4, 4)
    g = np.ones((4, 4), np.uint8)
    assert to_gray(g) is g
    with pytest.raises(FrameError):
        to_gray(np.zeros((4, 4, 5), np.uint8))
