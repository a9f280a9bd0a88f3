"""The robot controller link: one interface, back ends by name (the package's
``socket``, ``serial``, ``modbus`` and ``rws``, or one a plug-in registers: :data:`CONTROLLERS`).

>>> from handeye.drivers.controller import open_controller           # doctest: +SKIP
>>> with open_controller("socket", host="192.168.125.1", port=1025) as robot:
...     robot.goto_posture(1); print(robot.read_joints()); robot.acknowledge(1)

``backends`` holds the registry of back ends (:data:`CONTROLLERS`), ``protocol`` the line-protocol
codec shared with the mock controller, ``modbus_map`` the register map. Importing this package is
cheap: names load on first use, serial and Modbus libraries only when their back end is opened.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...base import lazy_exports

_EXPORTS = {
    "CONTROLLERS": "backends",
    "ControllerBackend": "backends",
    "ControllerLink": "backends",
    "MockServer": "backends",
    "register_backend": "backends",
    "Controller": "interface",
    "open_controller": "interface",
    "read_robot_state": "interface",
    "ControllerInfo": "types",
    "ControllerStatus": "types",
    "FlangePose": "types",
    "ToolData": "types",
    "check_tooldata": "types",
    "StationError": "errors",
    "ConfigError": "errors",
    "ControllerError": "errors",
    "ControllerConnectionError": "errors",
    "ControllerRefused": "errors",
    "ControllerTimeout": "errors",
    "InvalidRequest": "errors",
    "ProtocolError": "errors",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .backends import CONTROLLERS, ControllerBackend, ControllerLink, MockServer, register_backend  # noqa: F401
    from .errors import ConfigError, ControllerConnectionError, ControllerError, ControllerRefused, ControllerTimeout, InvalidRequest, ProtocolError, StationError  # noqa: F401
    from .interface import Controller, open_controller, read_robot_state  # noqa: F401
    from .types import ControllerInfo, ControllerStatus, FlangePose, ToolData, check_tooldata  # noqa: F401
