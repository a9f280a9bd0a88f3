"""Simulated station hardware: an IRB 1400 controller (a server per controller back end that brings
a mock, on 127.0.0.1, executing the generated RAPID in handeye's interpreter) and a Bumblebee XB3, built on the same
kinematics and frame layout as the real paths; ``mocks.cell`` serves the XB3 on a standalone mock
controller's arm to a rehearsal station.

Importing this package registers the mocks with the drivers' back-end registries
(:mod:`handeye.mocks.backends`): the controller servers as the ``mock`` of their back ends, the
simulated XB3 as the camera back end ``mock``. The other names load on first use::

    from handeye.mocks import MockStation
    with MockStation() as station:          # a simulated arm behind a real server, a camera on its flange
        print(station.controller_options())
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports
from . import backends as _backends  # noqa: F401  (registers the mocks)

_EXPORTS = {
    "SocketControllerServer": "controller.line_server",
    "mock_protocols": "backends",
    "mock_server": "backends",
    "start_mock_controller": "controller",
    "MockStation": "station",
    "MockStationSpec": "station",
    "MockCamera": "camera",
    "RenderOptions": "camera",
    "SimulatedRobot": "robot",
    "PrintedBoard": "world",
    "mock_protocol_choices": "backends",
    "mock_settings": "backends",
    "cell_info": "cell",
    "MockControllerOptions": "controller.service",
    "run_mock_controller": "controller.service",
    "parse_signal": "controller.signals",
    "StationFaults": "drift",
    "BoardOperator": "world",
    "Occlusion": "printed_targets",
    "LINK_NAMES": "arm_truth",
    "ArmDeviations": "arm_truth",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .printed_targets import Occlusion  # noqa: F401
    from .arm_truth import LINK_NAMES, ArmDeviations  # noqa: F401
    from .controller.line_server import SocketControllerServer  # noqa: F401
    from .backends import mock_protocol_choices, mock_protocols, mock_server, mock_settings  # noqa: F401
    from .camera import MockCamera, RenderOptions  # noqa: F401
    from .cell import cell_info  # noqa: F401
    from .controller import start_mock_controller  # noqa: F401
    from .controller.service import MockControllerOptions, run_mock_controller  # noqa: F401
    from .controller.signals import parse_signal  # noqa: F401
    from .drift import StationFaults  # noqa: F401
    from .robot import SimulatedRobot  # noqa: F401
    from .station import MockStation, MockStationSpec  # noqa: F401
    from .world import BoardOperator, PrintedBoard  # noqa: F401
