"""The real Bumblebee XB3 on libdc1394 2.x through ctypes (the ``"xb3"`` camera back end).

The library is loaded inside :meth:`XB3Camera.connect` (and :func:`list_cameras`), never at import,
so the rest of the package works on machines without it. On Debian/Ubuntu it is the package
``libdc1394-25`` (``libdc1394.so.25``). FlyCapture2/PyCapture2 are discontinued, Spinnaker has no
FireWire support and OpenCV's wheels have no DC1394 back end: libdc1394 is the way on Linux.

What :meth:`XB3Camera.connect` does (facts from ``shared/reference/bumblebee-xb3.md``):

1. ``dc1394_new``, ``dc1394_camera_enumerate``; the first camera whose model names a Bumblebee XB3
   (or the one with the given GUID). No camera: :class:`CameraError` saying what was looked for.
2. Reads the serial number (register 0x1F20), the sensor info (0x1F28: low nibble 0xE colour,
   0xF mono) and the Bayer tile (0x1040: "GBRG" or "YYYY").
3. IEEE-1394b operation mode, ISO speed 800, Format_7 mode 3 (``DC1394_VIDEO_MODE_FORMAT7_3``),
   and either the 3-sensor RGB8 coding or the 2-sensor 16-bit coding (RAW16 on colour heads, MONO16
   on mono heads) after putting the camera in little-endian mode (0x1048 = 0x80000000) and choosing
   the wide (0x884 = 0x82000000) or narrow (0x82000001) pair.
4. ROI 0,0,1280x960 with the largest packet size, capture set-up with a few DMA buffers,
   transmission on.

:meth:`XB3Camera.grab` waits for a frame with ``select`` on the capture file descriptor (so the
timeout is honoured), dequeues it with the poll policy, copies the image bytes and gives the buffer
back; the bytes are decoded by :mod:`.decode`. Registers are read and written with
``dc1394_get/set_control_registers`` (the single-register helpers are static inline in the header).
"""

from __future__ import annotations

import collections
import ctypes
import ctypes.util
import select
import time

import numpy as np

from .errors import CameraError
from .interface import Camera, StereoFrame

__all__ = [
    "DEBIAN_PACKAGE",
    "LIBRARY_NAMES",
    "LIBRARY_MESSAGES",
    "Dc1394",
    "XB3Camera",
    "load_library",
    "list_cameras",
    "parse_sensor_info",
]

DEBIAN_PACKAGE = "libdc1394-25"
LIBRARY_NAMES = ("libdc1394.so.25", "libdc1394.so", "libdc1394.25.dylib", "libdc1394.dylib")
LOOKING_FOR = "a Point Grey Bumblebee XB3 (BBX3-13S2C/-13S2M) on the IEEE-1394b (FireWire 800) bus"

# libdc1394 2.2.6 enumerations (types.h, video.h, capture.h).
DC1394_SUCCESS = 0
VIDEO_MODE_FORMAT7_3 = 91
COLOR_CODING_RGB8 = 356
COLOR_CODING_MONO16 = 357
COLOR_CODING_RAW16 = 362
ISO_SPEED_800 = 3
OPERATION_MODE_1394B = 481
CAPTURE_POLICY_WAIT = 672
CAPTURE_POLICY_POLL = 673
CAPTURE_FLAGS_DEFAULT = 0x4
USE_MAX_AVAIL = -2
DC1394_OFF, DC1394_ON = 0, 1
LOG_ERROR, LOG_WARNING = 768, 769

# Point Grey registers (offsets for dc1394_get/set_control_registers).
REG_PAN = 0x884
REG_BAYER_TILE = 0x1040
REG_ENDIANNESS = 0x1048
REG_SERIAL = 0x1F20
REG_SENSOR_INFO = 0x1F28
REG_CALIBRATION_LENGTH = 0x1FFC
REG_CALIBRATION_DATA = 0x2000
LITTLE_ENDIAN = 0x80000000
PAN_WIDE = 0x82000000
PAN_NARROW = 0x82000001


class _CameraId(ctypes.Structure):
    _fields_ = [("unit", ctypes.c_uint16), ("guid", ctypes.c_uint64)]


class _CameraList(ctypes.Structure):
    _fields_ = [("num", ctypes.c_uint32), ("ids", ctypes.POINTER(_CameraId))]


class _Camera(ctypes.Structure):
    """``dc1394camera_t`` (camera.h of 2.2.x), read for the vendor and model strings."""

    _fields_ = [
        ("guid", ctypes.c_uint64), ("unit", ctypes.c_int), ("unit_spec_ID", ctypes.c_uint32),
        ("unit_sw_version", ctypes.c_uint32), ("unit_sub_sw_version", ctypes.c_uint32),
        ("command_registers_base", ctypes.c_uint32), ("unit_directory", ctypes.c_uint32),
        ("unit_dependent_directory", ctypes.c_uint32), ("advanced_features_csr", ctypes.c_uint64),
        ("PIO_control_csr", ctypes.c_uint64), ("SIO_control_csr", ctypes.c_uint64),
        ("strobe_control_csr", ctypes.c_uint64), ("format7_csr", ctypes.c_uint64 * 8),
        ("iidc_version", ctypes.c_int), ("vendor", ctypes.c_char_p), ("model", ctypes.c_char_p),
        ("vendor_id", ctypes.c_uint32), ("model_id", ctypes.c_uint32), ("bmode_capable", ctypes.c_int),
        ("one_shot_capable", ctypes.c_int), ("multi_shot_capable", ctypes.c_int),
        ("can_switch_on_off", ctypes.c_int), ("has_vmode_error_status", ctypes.c_int),
        ("has_feature_error_status", ctypes.c_int), ("max_mem_channel", ctypes.c_int), ("flags", ctypes.c_uint32),
    ]


class _VideoFrame(ctypes.Structure):
    """``dc1394video_frame_t`` (video.h of 2.2.x)."""

    _fields_ = [
        ("image", ctypes.POINTER(ctypes.c_ubyte)), ("size", ctypes.c_uint32 * 2), ("position", ctypes.c_uint32 * 2),
        ("color_coding", ctypes.c_int), ("color_filter", ctypes.c_int), ("yuv_byte_order", ctypes.c_uint32),
        ("data_depth", ctypes.c_uint32), ("stride", ctypes.c_uint32), ("video_mode", ctypes.c_int),
        ("total_bytes", ctypes.c_uint64), ("image_bytes", ctypes.c_uint32), ("padding_bytes", ctypes.c_uint32),
        ("packet_size", ctypes.c_uint32), ("packets_per_frame", ctypes.c_uint32), ("timestamp", ctypes.c_uint64),
        ("frames_behind", ctypes.c_uint32), ("camera", ctypes.c_void_p), ("id", ctypes.c_uint32),
        ("allocated_image_bytes", ctypes.c_uint64), ("little_endian", ctypes.c_int),
        ("data_in_padding", ctypes.c_int),
    ]


_LOG_HANDLER = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p)

#: The last messages libdc1394 logged (errors and warnings), instead of its own printing to stderr.
LIBRARY_MESSAGES: collections.deque = collections.deque(maxlen=50)


def _collect(_kind, message, _user):
    LIBRARY_MESSAGES.append((message or b"").decode("ascii", "replace").strip())


# One module-level callback: libdc1394 keeps the pointer for the life of the process.
_HANDLER = _LOG_HANDLER(_collect)


def _not_installed(tried) -> CameraError:
    return CameraError(
        f"libdc1394 is not installed (tried {', '.join(tried)}); install the Debian package {DEBIAN_PACKAGE} "
        f"(apt-get install {DEBIAN_PACKAGE}) to use {LOOKING_FOR}, or use the mock camera"
    )


def load_library(path: str | None = None) -> ctypes.CDLL:
    """Load libdc1394 (``path`` or the usual names); :class:`CameraError` naming the package when absent."""
    names: list[str] = [path] if path else list(LIBRARY_NAMES)
    if not path:
        found = ctypes.util.find_library("dc1394")
        if found and found not in names:
            names.append(found)
    for name in names:
        try:
            return ctypes.CDLL(name)
        except OSError:
            continue
    raise _not_installed(names)


class Dc1394:
    """Thin, typed wrapper of the libdc1394 calls the XB3 back end needs (one library context).

    Every call checks the ``dc1394error_t`` and raises :class:`CameraError` with the library's
    own error string and the step that failed.
    """

    def __init__(self, library: ctypes.CDLL | str | None = None):
        lib = library if isinstance(library, ctypes.CDLL) else load_library(library)
        self.lib = lib
        self._declare()
        self._quiet_logs()
        self.context = lib.dc1394_new()
        if not self.context:
            raise CameraError(
                "libdc1394 could not start (dc1394_new failed): no FireWire (IEEE 1394) subsystem; load the "
                "firewire-ohci kernel module and check that /dev/fw* exist and are readable"
            )

    def _declare(self) -> None:
        lib, vp, i32, u32, u64 = self.lib, ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32, ctypes.c_uint64
        sig = {
            "dc1394_new": (vp, []),
            "dc1394_free": (None, [vp]),
            "dc1394_camera_enumerate": (i32, [vp, ctypes.POINTER(ctypes.POINTER(_CameraList))]),
            "dc1394_camera_free_list": (None, [ctypes.POINTER(_CameraList)]),
            "dc1394_camera_new_unit": (ctypes.POINTER(_Camera), [vp, u64, i32]),
            "dc1394_camera_free": (None, [ctypes.POINTER(_Camera)]),
            "dc1394_get_control_registers": (i32, [ctypes.POINTER(_Camera), u64, ctypes.POINTER(u32), u32]),
            "dc1394_set_control_registers": (i32, [ctypes.POINTER(_Camera), u64, ctypes.POINTER(u32), u32]),
            "dc1394_video_set_operation_mode": (i32, [ctypes.POINTER(_Camera), i32]),
            "dc1394_video_set_iso_speed": (i32, [ctypes.POINTER(_Camera), i32]),
            "dc1394_video_set_mode": (i32, [ctypes.POINTER(_Camera), i32]),
            "dc1394_format7_set_roi": (i32, [ctypes.POINTER(_Camera), i32, i32, ctypes.c_int32, ctypes.c_int32,
                                             ctypes.c_int32, ctypes.c_int32, ctypes.c_int32]),
            "dc1394_capture_setup": (i32, [ctypes.POINTER(_Camera), u32, u32]),
            "dc1394_capture_stop": (i32, [ctypes.POINTER(_Camera)]),
            "dc1394_capture_get_fileno": (i32, [ctypes.POINTER(_Camera)]),
            "dc1394_capture_dequeue": (i32, [ctypes.POINTER(_Camera), i32, ctypes.POINTER(ctypes.POINTER(_VideoFrame))]),
            "dc1394_capture_enqueue": (i32, [ctypes.POINTER(_Camera), ctypes.POINTER(_VideoFrame)]),
            "dc1394_video_set_transmission": (i32, [ctypes.POINTER(_Camera), i32]),
            "dc1394_error_get_string": (ctypes.c_char_p, [i32]),
            "dc1394_log_register_handler": (i32, [i32, _LOG_HANDLER, vp]),
        }
        for name, (restype, argtypes) in sig.items():
            try:
                fn = getattr(lib, name)
            except AttributeError:
                raise CameraError(f"the loaded libdc1394 has no {name}: install libdc1394 2.x ({DEBIAN_PACKAGE})") from None
            fn.restype = restype
            fn.argtypes = argtypes

    def _quiet_logs(self) -> None:
        """Collect the library's error/warning messages in :data:`LIBRARY_MESSAGES` instead of printing them."""
        for kind in (LOG_ERROR, LOG_WARNING):
            self.lib.dc1394_log_register_handler(kind, _HANDLER, None)

    def check(self, err: int, step: str) -> None:
        if err != DC1394_SUCCESS:
            text = self.lib.dc1394_error_get_string(err)
            reason = text.decode("ascii", "replace") if text else f"error {err}"
            raise CameraError(f"libdc1394 failed to {step}: {reason}")

    def enumerate(self) -> list[tuple[int, int]]:
        """``(guid, unit)`` of every IIDC camera on the bus; an empty list when there is none."""
        listing = ctypes.POINTER(_CameraList)()
        self.check(self.lib.dc1394_camera_enumerate(self.context, ctypes.byref(listing)), "list the cameras")
        if not listing:
            return []
        try:
            return [(int(listing.contents.ids[i].guid), int(listing.contents.ids[i].unit))
                    for i in range(listing.contents.num)]
        finally:
            self.lib.dc1394_camera_free_list(listing)

    def camera_new(self, guid: int, unit: int = 0):
        cam = self.lib.dc1394_camera_new_unit(self.context, guid, unit)
        if not cam:
            raise CameraError(f"libdc1394 could not open the camera with GUID {guid:016x}: unplugged, or in use by another program?")
        return cam

    @staticmethod
    def describe(cam) -> dict:
        c = cam.contents
        return {"guid": int(c.guid), "unit": int(c.unit),
                "vendor": (c.vendor or b"").decode("ascii", "replace"), "model": (c.model or b"").decode("ascii", "replace")}

    def camera_free(self, cam) -> None:
        self.lib.dc1394_camera_free(cam)

    def get_registers(self, cam, offset: int, count: int = 1) -> list[int]:
        values = (ctypes.c_uint32 * count)()
        self.check(self.lib.dc1394_get_control_registers(cam, offset, values, count), f"read register 0x{offset:X}")
        return [int(v) for v in values]

    def set_register(self, cam, offset: int, value: int) -> None:
        data = (ctypes.c_uint32 * 1)(value)
        self.check(self.lib.dc1394_set_control_registers(cam, offset, data, 1), f"write 0x{value:08X} to register 0x{offset:X}")

    def configure(self, cam, coding: int, width: int, height: int, dma_buffers: int) -> None:
        lib = self.lib
        self.check(lib.dc1394_video_set_operation_mode(cam, OPERATION_MODE_1394B), "switch to IEEE-1394b operation")
        self.check(lib.dc1394_video_set_iso_speed(cam, ISO_SPEED_800), "set ISO speed 800")
        self.check(lib.dc1394_video_set_mode(cam, VIDEO_MODE_FORMAT7_3), "select Format_7 mode 3")
        self.check(lib.dc1394_format7_set_roi(cam, VIDEO_MODE_FORMAT7_3, coding, USE_MAX_AVAIL, 0, 0, width, height),
                   f"set the Format_7 region 0,0,{width}x{height}")
        self.check(lib.dc1394_capture_setup(cam, dma_buffers, CAPTURE_FLAGS_DEFAULT), "set up capture (DMA buffers, ISO channel, bandwidth)")
        self.check(lib.dc1394_video_set_transmission(cam, DC1394_ON), "start transmission")

    def stop(self, cam) -> None:
        """Transmission off and capture stopped; errors ignored (used while closing)."""
        self.lib.dc1394_video_set_transmission(cam, DC1394_OFF)
        self.lib.dc1394_capture_stop(cam)

    def dequeue(self, cam, timeout_s: float) -> tuple[bytes, float, int]:
        """``(image bytes, timestamp s, frames behind)`` of the next frame, waiting at most ``timeout_s``."""
        fd = self.lib.dc1394_capture_get_fileno(cam)
        if fd >= 0:
            ready, _, _ = select.select([fd], [], [], max(0.0, timeout_s))
            if not ready:
                raise CameraError(f"no frame from the XB3 within {timeout_s:g} s: check the cable and the trigger settings")
        frame = ctypes.POINTER(_VideoFrame)()
        policy = CAPTURE_POLICY_POLL if fd >= 0 else CAPTURE_POLICY_WAIT
        self.check(self.lib.dc1394_capture_dequeue(cam, policy, ctypes.byref(frame)), "dequeue a frame")
        if not frame:
            raise CameraError(f"no frame from the XB3 within {timeout_s:g} s")
        try:
            f = frame.contents
            data = ctypes.string_at(f.image, f.image_bytes)
            return data, f.timestamp * 1e-6, int(f.frames_behind)
        finally:
            self.lib.dc1394_capture_enqueue(cam, frame)

    def free(self) -> None:
        if self.context:
            self.lib.dc1394_free(self.context)
            self.context = None


def parse_sensor_info(value: int) -> bool:
    """True for a colour head (low nibble 0xE), False for mono (0xF); :class:`CameraError` otherwise."""
    nibble = value & 0xF
    if nibble == 0xE:
        return True
    if nibble == 0xF:
        return False
    raise CameraError(f"sensor info register 0x1F28 reads 0x{value:08X}: not a Bumblebee XB3 (expected low nibble E or F)")


def _ascii(value: int) -> str:
    return bytes([(value >> s) & 0xFF for s in (24, 16, 8, 0)]).decode("ascii", "replace")


def _is_xb3(description: dict) -> bool:
    model = description.get("model", "").lower()
    return "bumblebee" in model or "xb3" in model or "bbx3" in model


def list_cameras(library=None) -> list[dict]:
    """Cameras libdc1394 sees: ``[{guid, unit, vendor, model}, ...]``; ``[]`` when there are none.

    Raises
    ------
    CameraError
        When libdc1394 is missing or cannot start (no FireWire subsystem).
    """
    dc = library if isinstance(library, Dc1394) else Dc1394(library)
    try:
        out = []
        for guid, unit in dc.enumerate():
            cam = dc.camera_new(guid, unit)
            try:
                out.append(dc.describe(cam))
            finally:
                dc.camera_free(cam)
        return out
    finally:
        if not isinstance(library, Dc1394):
            dc.free()


class XB3Camera(Camera):
    """Bumblebee XB3 on libdc1394 (``open_camera("xb3", ...)``).

    Parameters
    ----------
    guid : int or str, optional
        Camera GUID (a number, or its hex digits: ``camera.guid`` of the station config); default: the
        Bumblebee XB3 on the bus, refused when there are several.
    layout : {"rgb8", "raw16"}
        3-sensor RGB8 stream (left, centre and right) or 2-sensor 16-bit stream.
    pair : {"wide", "narrow"}
        For ``raw16``: right-left (24 cm) or right-centre (12 cm).
    output : {"bgr", "gray"}
        Decoded images in the frames.
    library : str or ctypes.CDLL or Dc1394, optional
        Library path or object (tests inject a fake here); default: the system's libdc1394.
    width, height : int
    dma_buffers : int
    """

    name = "xb3"

    def __init__(self, guid: int | str | None = None, *, layout: str = "rgb8", pair: str = "wide", output: str = "bgr",
                 library=None, width: int = 1280, height: int = 960, dma_buffers: int = 4):
        if layout not in ("rgb8", "raw16"):
            raise CameraError(f"layout must be rgb8 (3 sensors) or raw16 (2 sensors); got {layout!r}")
        if pair not in ("wide", "narrow"):
            raise CameraError(f"pair must be wide or narrow; got {pair!r}")
        try:
            self.guid = int(guid, 16) if isinstance(guid, str) else guid
        except ValueError:
            raise CameraError(f"guid must be the camera's FireWire GUID in hex digits; got {guid!r}") from None
        self.layout, self.pair, self.output = layout, pair, output
        self.width, self.height, self.dma_buffers = int(width), int(height), int(dma_buffers)
        self._library = library
        self._dc: Dc1394 | None = None
        self._cam = None
        self._serial: int | None = None
        self.colour: bool | None = None
        self.info: dict = {}

    @property
    def is_connected(self) -> bool:
        return self._cam is not None

    @property
    def serial(self) -> int | None:
        return self._serial

    def connect(self) -> None:
        if self._cam is not None:
            return
        dc = self._library if isinstance(self._library, Dc1394) else Dc1394(self._library)
        self._dc = dc
        try:
            found = dc.enumerate()
            if not found:
                raise CameraError(
                    f"no camera found: libdc1394 sees 0 cameras, looked for {LOOKING_FOR}; check the cable and "
                    f"power (FireWire 800 powers the head) and read access to /dev/fw*"
                )
            cam, desc = self._choose(dc, found)
            self._cam = cam
            self._setup(dc, cam, desc)
        except BaseException:
            self.close()
            raise

    def _choose(self, dc: Dc1394, found: list) -> tuple:
        """The camera to open among ``found`` (``(guid, unit)`` pairs): the one of :attr:`guid`, else the only
        Bumblebee XB3; the others are freed.

        Raises
        ------
        CameraError
            No such camera, or several XB3 and no GUID to choose (a station must not calibrate the wrong
            head): the message lists what is on the bus with the GUIDs.
        """
        chosen, seen = [], []
        for guid, unit in found:
            cam = dc.camera_new(guid, unit)
            desc = dc.describe(cam)
            seen.append(f"{desc['vendor']} {desc['model']} (GUID {guid:016x})".strip())
            if (self.guid is not None and guid == self.guid) or (self.guid is None and _is_xb3(desc)):
                chosen.append((cam, desc))
                if self.guid is not None:
                    break
            else:
                dc.camera_free(cam)
        if not chosen:
            wanted = f"no camera with GUID {self.guid:016x}" if self.guid is not None else "no Bumblebee XB3"
            raise CameraError(f"{wanted} among the cameras on the bus: {'; '.join(seen)}")
        if len(chosen) > 1:
            for cam, _ in chosen:
                dc.camera_free(cam)
            raise CameraError(f"{len(chosen)} Bumblebee XB3 on the bus ({'; '.join(seen)}): set camera.guid in the "
                              "station config to the GUID of the one to calibrate")
        return chosen[0]

    def _setup(self, dc: Dc1394, cam, desc: dict) -> None:
        self._serial = dc.get_registers(cam, REG_SERIAL)[0]
        sensor = dc.get_registers(cam, REG_SENSOR_INFO)[0]
        self.colour = parse_sensor_info(sensor)
        tile = _ascii(dc.get_registers(cam, REG_BAYER_TILE)[0])
        if self.colour and tile != "GBRG":
            raise CameraError(f"the colour XB3 reports Bayer tile {tile!r} (register 0x1040); this driver decodes GBRG")
        if self.layout == "raw16":
            dc.set_register(cam, REG_ENDIANNESS, LITTLE_ENDIAN)
            dc.set_register(cam, REG_PAN, PAN_WIDE if self.pair == "wide" else PAN_NARROW)
            coding = COLOR_CODING_RAW16 if self.colour else COLOR_CODING_MONO16
        else:
            coding = COLOR_CODING_RGB8
        dc.configure(cam, coding, self.width, self.height, self.dma_buffers)
        self.info = {**desc, "serial": self._serial, "sensor_info": sensor, "bayer_tile": tile,
                     "colour": self.colour, "layout": self.layout, "pair": self.pair if self.layout == "raw16" else "all"}

    def calibration_file(self) -> bytes:
        """The factory calibration file (Triclops .cal) stored in the head (registers 0x1FFC, 0x2000..)."""
        if self._cam is None or self._dc is None:  # (connect sets _dc before _cam)
            raise CameraError("the XB3 is not connected")
        length = self._dc.get_registers(self._cam, REG_CALIBRATION_LENGTH)[0]
        if not 0 < length < 1 << 20:
            raise CameraError(f"the XB3 reports a calibration file of {length} bytes (register 0x1FFC)")
        quads = (length + 3) // 4
        words = []
        for start in range(0, quads, 64):
            count = min(64, quads - start)
            words += self._dc.get_registers(self._cam, REG_CALIBRATION_DATA + 4 * start, count)
        return np.array(words, dtype=">u4").tobytes()[:length]  # quadlets, MSB first

    def grab(self, timeout_s: float = 2.0) -> StereoFrame:
        from .decode import decode_xb3_frame

        if self._cam is None or self._dc is None:  # (connect sets _dc before _cam)
            raise CameraError("the XB3 is not connected: call connect() or use it in a with-block")
        data, stamp, behind = self._dc.dequeue(self._cam, timeout_s)
        frame = decode_xb3_frame(data, self.layout, self.width, self.height, colour=bool(self.colour),
                                 output=self.output, timestamp=stamp or time.time(), serial=self._serial,
                                 allow_padding=True, keep_raw=True)
        frame.info = {**self.info, "frames_behind": behind}
        return frame

    def close(self) -> None:
        dc, cam = self._dc, self._cam
        self._cam = None
        if dc is not None and cam is not None:
            try:
                dc.stop(cam)
            finally:
                dc.camera_free(cam)
        if dc is not None and not isinstance(self._library, Dc1394):
            dc.free()
        self._dc = None
