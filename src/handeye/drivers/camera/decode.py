"""Decoding Bumblebee XB3 Format_7 frames: de-interleaving the sensors and debayering.

Byte layouts (see ``shared/reference/bumblebee-xb3.md``):

- ``rgb8``, 3-sensor stream, Format_7 mode 3 with RGB8 coding: ``h x w x 3`` bytes; per pixel
  byte 0 = right, byte 1 = centre, byte 2 = left sensor (as seen from the camera looking out).
- ``raw16``, 2-sensor stream, Format_7 mode 3 with MONO16/RAW16 coding and the camera in
  little-endian mode (register 0x1048 = 0x80000000): ``h x w x 2`` bytes; byte 0 = right,
  byte 1 = left (the wide or the narrow pair, as register 0x884 selects).

Every plane is a GBRG Bayer mosaic on colour heads (first row G B G B, second row R G R G) and a
grey image on mono heads. OpenCV names a Bayer pattern by the second row's second and third
pixels, so GBRG decodes with ``COLOR_BayerGR2*`` (checked on a synthetic mosaic in the tests).
Demosaicing keeps pixel centres where they are: no half-pixel shift is introduced.
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from .errors import FrameError
from .interface import StereoFrame

__all__ = [
    "XB3_WIDTH",
    "XB3_HEIGHT",
    "GBRG_TO_BGR",
    "GBRG_TO_GRAY",
    "LAYOUTS",
    "frame_bytes",
    "deinterleave",
    "debayer_gbrg",
    "to_gray",
    "decode_xb3_frame",
    "pack_rgb8",
    "pack_raw16",
]

XB3_WIDTH, XB3_HEIGHT = 1280, 960

#: OpenCV conversion codes of the XB3's GBRG mosaic (OpenCV names the second row: "GR").
GBRG_TO_BGR = cv2.COLOR_BayerGR2BGR
GBRG_TO_GRAY = cv2.COLOR_BayerGR2GRAY

#: Layout name -> (bytes per pixel, sensor of each byte).
LAYOUTS = {
    "rgb8": (3, ("right", "centre", "left")),
    "raw16": (2, ("right", "left")),
}


def frame_bytes(layout: str = "rgb8", width: int = XB3_WIDTH, height: int = XB3_HEIGHT) -> int:
    """Size in bytes of one frame of ``layout`` at ``width x height``."""
    return _layout(layout)[0] * int(width) * int(height)


def _layout(layout: str):
    try:
        return LAYOUTS[layout]
    except KeyError:
        raise FrameError(f"unknown XB3 frame layout {layout!r}; choose one of {', '.join(LAYOUTS)}") from None


def _as_bytes_array(buffer) -> np.ndarray:
    if isinstance(buffer, np.ndarray):
        if buffer.dtype != np.uint8:
            raise FrameError(f"an XB3 frame is a byte buffer; got an array of {buffer.dtype}")
        return buffer.reshape(-1)
    try:
        return np.frombuffer(memoryview(buffer), dtype=np.uint8)
    except TypeError:
        raise FrameError(f"an XB3 frame is a byte buffer; got {type(buffer).__name__}") from None


def deinterleave(buffer: bytes | bytearray | memoryview | np.ndarray, layout: str = "rgb8", width: int = XB3_WIDTH, height: int = XB3_HEIGHT,
                 *, allow_padding: bool = False) -> dict[str, np.ndarray]:
    """Split a packed XB3 frame into its sensor planes.

    Parameters
    ----------
    buffer : bytes-like or ndarray of uint8
        The frame as the camera sent it (any shape; only the byte order matters).
    layout : {"rgb8", "raw16"}
    width, height : int
    allow_padding : bool
        Accept (and ignore) bytes after the image, as libdc1394 buffers may carry.

    Returns
    -------
    dict of str -> ndarray, shape (height, width) uint8
        ``right``, ``centre``, ``left`` for ``rgb8``; ``right``, ``left`` for ``raw16``.
        Each plane is C-contiguous (a copy).

    Raises
    ------
    FrameError
        If the buffer is shorter (truncated) or, without ``allow_padding``, longer than one frame.
    """
    per_pixel, names = _layout(layout)
    data = _as_bytes_array(buffer)
    expected = per_pixel * int(width) * int(height)
    if data.size < expected or (data.size > expected and not allow_padding):
        what = "truncated" if data.size < expected else "too long"
        raise FrameError(
            f"XB3 frame {what}: got {data.size} bytes, a {width}x{height} {layout} frame has {expected} "
            f"({per_pixel} bytes per pixel); check the file and the frame size"
        )
    packed = data[:expected].reshape(int(height), int(width), per_pixel)
    return {name: np.ascontiguousarray(packed[..., k]) for k, name in enumerate(names)}


def debayer_gbrg(plane: np.ndarray, output: str = "bgr") -> np.ndarray:
    """Demosaic one GBRG plane (bilinear, OpenCV).

    Parameters
    ----------
    plane : ndarray, shape (h, w) uint8
    output : {"bgr", "gray"}

    Returns
    -------
    ndarray, shape (h, w, 3) for "bgr" or (h, w) for "gray", uint8
    """
    if plane.ndim != 2:
        raise FrameError(f"a Bayer plane is a 2-D image; got shape {plane.shape}")
    code = GBRG_TO_BGR if output == "bgr" else GBRG_TO_GRAY
    return cv2.cvtColor(plane, code)


def to_gray(image: np.ndarray) -> np.ndarray:
    """A grey uint8 view of an image: grey passes through, BGR is converted, BGRA too."""
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if image.ndim == 3 and image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    if image.ndim == 3 and image.shape[2] == 1:
        return image[..., 0]
    raise FrameError(f"cannot read an image of shape {image.shape} as grey")


def decode_xb3_frame(buffer: bytes | bytearray | memoryview | np.ndarray, layout: str = "rgb8", width: int = XB3_WIDTH, height: int = XB3_HEIGHT, *,
                     colour: bool = True, output: str = "bgr", centre: bool = True, timestamp: float | None = None,
                     serial: int | None = None, allow_padding: bool = False, keep_raw: bool = False) -> StereoFrame:
    """Decode a packed XB3 frame into a :class:`StereoFrame`.

    Parameters
    ----------
    buffer : bytes-like or ndarray of uint8
    layout : {"rgb8", "raw16"}
    width, height : int
    colour : bool
        The planes are GBRG mosaics (colour head); ``False``: mono head, planes pass through.
    output : {"bgr", "gray"}
        Debayered colour images or grey images (grey is what corner detection uses).
    centre : bool
        Decode the centre sensor too (``rgb8`` only); ``False`` leaves ``frame.centre = None``.
    timestamp : float, optional
        Defaults to now.
    serial : int, optional
    keep_raw : bool
        Keep the packed buffer in ``frame.raw``.

    Raises
    ------
    FrameError
    """
    planes = deinterleave(buffer, layout, width, height, allow_padding=allow_padding)
    if output not in ("bgr", "gray"):
        raise FrameError(f"output must be 'bgr' or 'gray'; got {output!r}")

    def convert(plane):
        if colour:
            return debayer_gbrg(plane, output)
        return plane if output == "gray" else cv2.cvtColor(plane, cv2.COLOR_GRAY2BGR)

    centre_image = convert(planes["centre"]) if centre and "centre" in planes else None
    raw = None
    if keep_raw:
        per_pixel = _layout(layout)[0]
        raw = _as_bytes_array(buffer)[: per_pixel * width * height].reshape(height, width, per_pixel).copy()
    return StereoFrame(
        left=convert(planes["left"]),
        right=convert(planes["right"]),
        centre=centre_image,
        timestamp=time.time() if timestamp is None else float(timestamp),
        serial=serial,
        raw=raw,
        layout=layout,
        colour=colour,
    )


def pack_rgb8(right: np.ndarray, centre: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Pack three uint8 planes into the 3-sensor RGB8 layout, ``(h, w, 3)``: byte 0 right, 1 centre, 2 left."""
    return np.ascontiguousarray(np.stack([right, centre, left], axis=-1).astype(np.uint8, copy=False))


def pack_raw16(right: np.ndarray, left: np.ndarray) -> np.ndarray:
    """Pack two uint8 planes into the little-endian 2-sensor 16-bit layout, ``(h, w, 2)``: byte 0 right, 1 left."""
    return np.ascontiguousarray(np.stack([right, left], axis=-1).astype(np.uint8, copy=False))
