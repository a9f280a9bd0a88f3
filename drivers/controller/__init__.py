"""The robot controller link: one interface, back ends by name (``socket``, ``serial``, ``modbus``).

>>> from handeye.drivers.controller import open_controller           # doctest: +SKIP
>>> with open_controller("socket", host="192.168.125.1", port=1025) as robot:
...     robot.goto_posture(1); print(robot.read_joints()); robot.acknowledge(1)

``protocol`` holds the line-protocol codec shared with the mock controller; ``modbus_map`` the
register map. Serial and Modbus libraries are imported only when their back end is used.
"""

from .errors import (
    ControllerConnectionError,
    ControllerError,
    ControllerRefused,
    ControllerTimeout,
    InvalidRequest,
    ProtocolError,
)
from .interface import BACKENDS, Controller, open_controller, read_robot_state
from .types import ControllerInfo, ControllerStatus, FlangePose, ToolData, check_tooldata

__all__ = [
    "BACKENDS",
    "Controller",
    "open_controller",
    "read_robot_state",
    "ControllerInfo",
    "ControllerStatus",
    "FlangePose",
    "ToolData",
    "check_tooldata",
    "ControllerError",
    "ControllerConnectionError",
    "ControllerRefused",
    "ControllerTimeout",
    "InvalidRequest",
    "ProtocolError",
]
