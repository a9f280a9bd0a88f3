"""The XB3 back end: libdc1394 loading and enumeration, ctypes layouts, and the connect/grab sequence
checked against a fake library (the real camera is not on the test machine)."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from handeye.drivers.camera import open_camera
from handeye.drivers.camera import xb3
from handeye.drivers.camera.errors import CameraError
from handeye.drivers.camera.xb3 import Dc1394, XB3Camera, list_cameras, load_library, parse_sensor_info


def _system_library():
    try:
        return load_library()
    except CameraError as exc:
        pytest.skip(f"libdc1394 is not installed here ({xb3.DEBIAN_PACKAGE}): {exc}")


# ------------------------------------------------------------------------- real library
def test_missing_library_names_the_debian_package_and_the_camera():
    with pytest.raises(CameraError) as info:
        XB3Camera(library="libdc1394-not-here.so.99").connect()
    message = str(info.value)
    assert "libdc1394-25" in message and "Bumblebee XB3" in message and "\n" not in message


def test_system_library_loads_and_reports_zero_cameras_cleanly():
    lib = _system_library()
    assert hasattr(lib, "dc1394_camera_enumerate")
    try:
        dc = Dc1394(lib)
    except CameraError as exc:  # the library loads but the machine has no FireWire subsystem
        assert "FireWire" in str(exc)
        return
    try:
        found = dc.enumerate()
    finally:
        dc.free()
    if found:
        pytest.skip(f"{len(found)} IEEE-1394 camera(s) attached: the zero-camera path cannot be checked here")
    assert list_cameras() == []
    with pytest.raises(CameraError, match=r"libdc1394 sees 0 cameras, looked for a Point Grey Bumblebee XB3"):
        XB3Camera().connect()
    with pytest.raises(CameraError, match="0 cameras"):
        open_camera("xb3")


def test_ctypes_structures_match_libdc1394_2_2_headers():
    # sizeof/offsetof measured with gcc against the libdc1394-dev 2.2.6 headers (x86-64).
    if ctypes.sizeof(ctypes.c_void_p) != 8:
        pytest.skip("layouts measured on a 64-bit build")
    assert ctypes.sizeof(xb3._VideoFrame) == 120
    assert xb3._VideoFrame.image_bytes.offset == 56
    assert xb3._VideoFrame.timestamp.offset == 72
    assert xb3._VideoFrame.little_endian.offset == 112
    assert ctypes.sizeof(xb3._Camera) == 200
    assert (xb3._Camera.vendor.offset, xb3._Camera.model.offset) == (144, 152)
    assert ctypes.sizeof(xb3._CameraId) == 16


def test_enumeration_values_of_libdc1394_2_2_6():
    assert xb3.VIDEO_MODE_FORMAT7_3 == 91
    assert (xb3.COLOR_CODING_RGB8, xb3.COLOR_CODING_MONO16, xb3.COLOR_CODING_RAW16) == (356, 357, 362)
    assert (xb3.ISO_SPEED_800, xb3.OPERATION_MODE_1394B, xb3.CAPTURE_POLICY_WAIT) == (3, 481, 672)


def test_sensor_info_register():
    assert parse_sensor_info(0x0000000E) is True
    assert parse_sensor_info(0x1234567F) is False
    with pytest.raises(CameraError, match="0x1F28"):
        parse_sensor_info(0x00000003)


# ----------------------------------------------------------------------------- fake library
class FakeDc1394(Dc1394):
    """Records what the driver asks of libdc1394 and answers like an XB3 would."""

    def __init__(self, cameras=((0x00B09D0100AABBCC, 0, "Point Grey Research", "Bumblebee XB3 BBX3-13S2C"),),
                 colour=True, tile="GBRG", frame=None):
        self.cameras = list(cameras)
        self.registers = {xb3.REG_SERIAL: 7_123_456, xb3.REG_SENSOR_INFO: 0xE if colour else 0xF,
                          xb3.REG_BAYER_TILE: int.from_bytes(tile.encode(), "big")}
        self.writes, self.configured, self.freed, self.stopped = [], None, [], 0
        self.frame = frame
        self.context = object()

    def enumerate(self):
        return [(g, u) for g, u, _, _ in self.cameras]

    def camera_new(self, guid, unit=0):
        return next(c for c in self.cameras if c[0] == guid)

    @staticmethod
    def describe(cam):
        return {"guid": cam[0], "unit": cam[1], "vendor": cam[2], "model": cam[3]}

    def camera_free(self, cam):
        self.freed.append(cam[0])

    def get_registers(self, cam, offset, count=1):
        return [self.registers.get(offset + 4 * i, 0) for i in range(count)]

    def set_register(self, cam, offset, value):
        self.writes.append((offset, value))

    def configure(self, cam, coding, width, height, dma_buffers):
        self.configured = (coding, width, height, dma_buffers)

    def stop(self, cam):
        self.stopped += 1

    def dequeue(self, cam, timeout_s):
        if self.frame is None:
            raise CameraError(f"no frame from the XB3 within {timeout_s:g} s")
        return self.frame, 1_700_000_000.25, 0

    def free(self):
        self.context = None


def test_connect_rgb8_colour_head():
    fake = FakeDc1394()
    with XB3Camera(library=fake) as cam:
        assert cam.is_connected and cam.serial == 7_123_456 and cam.colour
        assert fake.configured == (xb3.COLOR_CODING_RGB8, 1280, 960, 4)
        assert fake.writes == []  # the 3-sensor stream needs no endianness or pair registers
        assert cam.info["bayer_tile"] == "GBRG" and cam.info["model"].startswith("Bumblebee XB3")
    assert not cam.is_connected and fake.stopped == 1 and fake.freed


@pytest.mark.parametrize("pair, pan", [("wide", 0x82000000), ("narrow", 0x82000001)])
@pytest.mark.parametrize("colour, coding", [(True, 362), (False, 357)])
def test_connect_two_sensor_16_bit(pair, pan, colour, coding):
    fake = FakeDc1394(colour=colour, tile="GBRG" if colour else "YYYY")
    with XB3Camera(library=fake, layout="raw16", pair=pair):
        assert (0x1048, 0x80000000) in fake.writes      # little-endian: byte 0 = right, byte 1 = left
        assert (0x884, pan) in fake.writes
        assert fake.writes.index((0x1048, 0x80000000)) == 0
        assert fake.configured[0] == coding


def test_grab_decodes_the_frame_bytes():
    rng = np.random.default_rng(0)
    right, centre, left = (rng.integers(0, 255, (960, 1280), dtype=np.uint8) for _ in range(3))
    data = np.stack([right, centre, left], axis=-1).tobytes()
    fake = FakeDc1394(colour=False, tile="YYYY", frame=data)
    with open_camera("xb3", library=fake, output="gray") as cam:
        frame = cam.grab(timeout_s=0.5)
    np.testing.assert_array_equal(frame.left, left)
    np.testing.assert_array_equal(frame.right, right)
    np.testing.assert_array_equal(frame.centre, centre)
    assert frame.serial == 7_123_456 and frame.timestamp == pytest.approx(1_700_000_000.25)
    assert frame.raw.shape == (960, 1280, 3)


def test_camera_problems_are_one_line_camera_errors():
    with pytest.raises(CameraError, match="no frame from the XB3 within 0.2 s"):
        with XB3Camera(library=FakeDc1394()) as cam:
            cam.grab(timeout_s=0.2)
    other = FakeDc1394(cameras=[(0x1234, 0, "Basler", "scA640-70fc")])
    with pytest.raises(CameraError, match="no Bumblebee XB3 among the cameras on the bus: Basler scA640-70fc"):
        XB3Camera(library=other).connect()
    assert other.freed == [0x1234]
    with pytest.raises(CameraError, match="Bayer tile 'RGGB'"):
        XB3Camera(library=FakeDc1394(tile="RGGB")).connect()
    with pytest.raises(CameraError, match="0 cameras"):
        XB3Camera(library=FakeDc1394(cameras=[])).connect()
    with pytest.raises(CameraError, match="not connected"):
        XB3Camera(library=FakeDc1394()).grab()
    with pytest.raises(CameraError, match="layout"):
        XB3Camera(layout="yuv")


def test_camera_chosen_by_guid_and_calibration_file_read():
    cams = [(0x1111, 0, "Point Grey Research", "Bumblebee XB3"), (0x2222, 0, "Point Grey Research", "Bumblebee XB3")]
    fake = FakeDc1394(cameras=cams)
    text = b"Triclops calibration\x00\x01\x02"
    words = np.frombuffer(text + b"\0" * (-len(text) % 4), ">u4")
    fake.registers[xb3.REG_CALIBRATION_LENGTH] = len(text)
    for i, w in enumerate(words):
        fake.registers[xb3.REG_CALIBRATION_DATA + 4 * i] = int(w)
    with pytest.raises(CameraError, match="no camera with GUID 0000000000003333"):
        XB3Camera(0x3333, library=fake).connect()
    with XB3Camera(0x2222, library=fake) as cam:
        assert cam.info["guid"] == 0x2222
        assert cam.calibration_file() == text
    with XB3Camera("0000000000001111", library=fake) as cam:  # camera.guid of a station config
        assert cam.info["guid"] == 0x1111


def test_two_xb3_and_no_guid_is_refused_naming_both():
    cams = [(0x1111, 0, "Point Grey Research", "Bumblebee XB3"), (0x4444, 0, "Basler", "scA640"),
            (0x2222, 0, "Point Grey Research", "Bumblebee XB3")]
    fake = FakeDc1394(cameras=cams)
    with pytest.raises(CameraError, match=r"2 Bumblebee XB3 on the bus \(Point Grey Research Bumblebee XB3 \(GUID "
                                          r"0000000000001111\); .*GUID 0000000000002222\)\): set camera.guid"):
        XB3Camera(library=fake).connect()
    assert sorted(fake.freed) == [0x1111, 0x2222, 0x4444]  # none left open
    with pytest.raises(CameraError, match="guid must be the camera's FireWire GUID"):
        XB3Camera("not hex")
