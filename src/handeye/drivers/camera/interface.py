"""The camera interface: one abstract stereo camera, back ends chosen by name.

A back end connects, grabs :class:`StereoFrame` objects and closes; it is a context manager::

    with open_camera("xb3") as camera:          # the real Bumblebee XB3 (libdc1394)
        frame = camera.grab(timeout_s=2.0)
    with open_camera("mock", seed=1) as camera: # the simulated XB3 (registered by handeye.mocks)
        frame = camera.grab()

Back ends are found by name in :data:`~handeye.drivers.camera.backends.CAMERAS` (their classes are
imported only when opened), the way pyvisa finds ``pyvisa-sim``: the drivers do not import the
mocks; the mocks register their camera under the name ``mock`` when ``handeye.mocks`` is imported.
:func:`~handeye.drivers.camera.backends.register_backend` and the ``handeye.cameras`` entry points
add more.
"""

from __future__ import annotations

from typing import Any

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from .errors import CameraError

__all__ = ["StereoFrame", "Camera", "open_camera"]


@dataclass
class StereoFrame:
    """One synchronised grab of the stereo head.

    Attributes
    ----------
    left, right : ndarray, shape (h, w) uint8 or (h, w, 3) uint8 (BGR)
        Camera 1 (left, the reference ``camera`` frame) and camera 2 (right), as seen from the
        camera looking out. Grey for mono heads or when grey output was asked for.
    centre : ndarray or None
        The centre sensor of a 3-sensor head (``None`` for 2-sensor streams).
    timestamp : float
        Capture time, seconds since the epoch.
    serial : int or None
        Camera serial number.
    raw : ndarray or None
        The packed frame as delivered (e.g. ``(h, w, 3)`` uint8 for the XB3 3-sensor RGB8 layout),
        kept so a session can store exactly what the camera sent.
    layout : str
        ``"rgb8"`` (3-sensor), ``"raw16"`` (2-sensor 16-bit) or ``"images"`` (separate images).
    colour : bool
        Whether the sensors are Bayer colour sensors.
    info : dict
        Back-end details (sensor info, model, ...).
    """

    left: np.ndarray
    right: np.ndarray
    centre: np.ndarray | None = None
    timestamp: float = 0.0
    serial: int | None = None
    raw: np.ndarray | None = None
    layout: str = "images"
    colour: bool = False
    info: dict = field(default_factory=dict)

    @property
    def size(self) -> tuple[int, int]:
        """Image size ``(width, height)``."""
        return int(self.left.shape[1]), int(self.left.shape[0])


class Camera(ABC):
    """Abstract stereo camera: ``connect`` / ``grab`` / ``close``, usable as a context manager."""

    #: Back-end name, e.g. ``"xb3"``.
    name = "camera"
    #: True for a camera that renders a simulation (the mocks): a session it captures is never a real one
    #: (``station.config.station_kind``).
    simulated = False

    @abstractmethod
    def connect(self) -> None:
        """Open the device. Raises :class:`CameraError` with what to install or plug in."""

    @abstractmethod
    def close(self) -> None:
        """Release the device; safe to call twice."""

    @abstractmethod
    def grab(self, timeout_s: float = 2.0) -> StereoFrame:
        """Grab one frame; raises :class:`CameraError` when none arrives within ``timeout_s``."""

    @property
    @abstractmethod
    def is_connected(self) -> bool:
        """Whether :meth:`connect` succeeded and :meth:`close` was not called since."""

    @property
    def serial(self) -> int | None:
        """Serial number of the connected camera, if known."""
        return None

    def __enter__(self):
        if not self.is_connected:
            self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_camera(backend_name: str = "xb3", *, connect: bool = True, **options: Any) -> Camera:
    """Create (and by default connect) the camera back end ``backend_name``.

    Parameters
    ----------
    backend_name : str
        ``"xb3"`` (Bumblebee XB3 on libdc1394), ``"mock"`` (simulated XB3, once ``handeye.mocks`` is
        imported), or another registered name.
    connect : bool
        Connect before returning (a failure raises and leaves nothing open).
    **options
        Keyword options of the back end's constructor.

    Raises
    ------
    CameraError
    """
    from .backends import CAMERAS

    try:
        backend = CAMERAS[backend_name]
    except KeyError:
        raise CameraError(CAMERAS.unknown(backend_name)) from None
    camera = backend.load()(**options)
    if connect:
        camera.connect()
    return camera
