"""The hardware side: the robot controller link (:mod:`handeye.drivers.controller`) and the stereo
camera (:mod:`handeye.drivers.camera`), back ends chosen by name from one registry per kind
(:mod:`handeye.drivers.registry`), and the exceptions they share (:mod:`handeye.drivers.errors`).

Importing this package imports no hardware library (no OpenCV, pymodbus, pyserial or libdc1394):
the names below load on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base.lazy import lazy_exports

_EXPORTS = {
    "CONTROLLERS": "controller.backends",
    "ControllerBackend": "controller.backends",
    "CAMERAS": "camera.backends",
    "CameraBackend": "camera.backends",
    "open_controller": "controller.interface",
    "open_camera": "camera.interface",
    "StationError": "errors",
    "ConfigError": "errors",
    "LinkConnectionError": "errors",
    "LinkTimeout": "errors",
    "ProtocolError": "errors",
    "Refused": "errors",
    "ControllerError": "errors",
    "CameraError": "errors",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .camera.backends import CAMERAS, CameraBackend  # noqa: F401
    from .camera.interface import open_camera  # noqa: F401
    from .controller.backends import CONTROLLERS, ControllerBackend  # noqa: F401
    from .controller.interface import open_controller  # noqa: F401
    from .errors import CameraError, ConfigError, ControllerError, LinkConnectionError, LinkTimeout, ProtocolError, Refused, StationError  # noqa: F401
