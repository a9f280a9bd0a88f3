"""The hardware side: the robot controller link (:mod:`handeye.drivers.controller`) and the stereo
camera (:mod:`handeye.drivers.camera`), back ends chosen by name from one registry per kind
(:mod:`handeye.drivers.registry`), and the exceptions they share (:mod:`handeye.drivers.errors`).

Importing this package imports no hardware library (no OpenCV, pymodbus, pyserial or libdc1394):
the names below load on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "Setting": "registry",
    "SocketController": "controller.socket_client",
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
    "camera_settings": "camera.backends",
    "as_board": "camera.checkerboard",
    "board_pose_from_corners": "camera.checkerboard",
    "detect_board": "camera.checkerboard",
    "Coverage": "camera.coverage",
    "coverage_map": "camera.coverage",
    "tilt_class": "camera.coverage",
    "decode_xb3_frame": "camera.decode",
    "pack_rgb8": "camera.decode",
    "BoardNotFound": "camera.errors",
    "FrameError": "camera.errors",
    "NoBoardInView": "camera.errors",
    "SquareSizeMismatch": "camera.errors",
    "StereoModelError": "camera.errors",
    "Camera": "camera.interface",
    "StereoFrame": "camera.interface",
    "pnp_pose": "camera.pnp",
    "StereoModel": "camera.stereo",
    "load_stereo_model": "camera.stereo",
    "nominal_xb3_model": "camera.stereo",
    "refuse_base64_filestorage": "camera.stereo",
    "save_stereo_model": "camera.stereo",
    "ViewCorners": "camera.stereo_fit",
    "calibrate_stereo": "camera.stereo_fit",
    "decode_image": "camera.triangulate",
    "read_image_bytes": "camera.triangulate",
    "triangulate_files": "camera.triangulate",
    "triangulate_images": "camera.triangulate",
    "read_triclops_model": "camera.triclops",
    "read_robot_state": "controller",
    "ControllerLink": "controller.backends",
    "DEFAULT_PROTOCOL": "controller.backends",
    "LinkSetting": "controller.backends",
    "MockServer": "controller.backends",
    "RAPID_LINKS": "controller.backends",
    "link_settings": "controller.backends",
    "rapid_protocol_choices": "controller.backends",
    "ControllerConnectionError": "controller.errors",
    "ControllerRefused": "controller.errors",
    "ControllerTimeout": "controller.errors",
    "InvalidRequest": "controller.errors",
    "load_register_map": "controller.modbus_map",
    "SIMULATION_SYSTEM_NAME": "controller.rws_client",
    "parse_rapid_value": "controller.rws_codec",
    "FlangePose": "controller.types",
    "ToolData": "controller.types",
    "check_tooldata": "controller.types",
    "check_write_key": "controller.types",
    "chosen_with_own": "registry",
    "opencv_board": "camera.charuco",
    "detect_charuco": "camera.charuco",
    "detect_circles": "camera.charuco",
    "Controller": "controller.interface",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .camera.charuco import detect_charuco, opencv_board, detect_circles  # noqa: F401
    from .registry import Setting  # noqa: F401
    from .controller.socket_client import SocketController  # noqa: F401
    from .camera.backends import CAMERAS, CameraBackend, camera_settings  # noqa: F401
    from .camera.checkerboard import as_board, board_pose_from_corners, detect_board  # noqa: F401
    from .camera.coverage import Coverage, coverage_map, tilt_class  # noqa: F401
    from .camera.decode import decode_xb3_frame, pack_rgb8  # noqa: F401
    from .camera.errors import BoardNotFound, FrameError, NoBoardInView, SquareSizeMismatch, StereoModelError  # noqa: F401
    from .camera.interface import Camera, StereoFrame, open_camera  # noqa: F401
    from .camera.pnp import pnp_pose  # noqa: F401
    from .camera.stereo import StereoModel, load_stereo_model, nominal_xb3_model, refuse_base64_filestorage, save_stereo_model  # noqa: F401
    from .camera.stereo_fit import ViewCorners, calibrate_stereo  # noqa: F401
    from .camera.triangulate import decode_image, read_image_bytes, triangulate_files, triangulate_images  # noqa: F401
    from .camera.triclops import read_triclops_model  # noqa: F401
    from .controller import read_robot_state  # noqa: F401
    from .controller.backends import CONTROLLERS, ControllerBackend, ControllerLink, DEFAULT_PROTOCOL, LinkSetting, MockServer, RAPID_LINKS, link_settings, rapid_protocol_choices  # noqa: F401
    from .controller.errors import ControllerConnectionError, ControllerRefused, ControllerTimeout, InvalidRequest  # noqa: F401
    from .controller.interface import Controller, open_controller  # noqa: F401
    from .controller.modbus_map import load_register_map  # noqa: F401
    from .controller.rws_client import SIMULATION_SYSTEM_NAME  # noqa: F401
    from .controller.rws_codec import parse_rapid_value  # noqa: F401
    from .controller.types import FlangePose, ToolData, check_tooldata, check_write_key  # noqa: F401
    from .errors import CameraError, ConfigError, ControllerError, LinkConnectionError, LinkTimeout, ProtocolError, Refused, StationError  # noqa: F401
    from .registry import chosen_with_own  # noqa: F401
