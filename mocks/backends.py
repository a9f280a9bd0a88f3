"""The mocks register themselves with the drivers' back-end registries (the drivers never name them).

Importing ``handeye.mocks`` (any of its modules) runs this: the simulated controller servers become
the ``mock`` of the ``socket``, ``serial`` and ``modbus`` back ends, and the simulated XB3 becomes the
camera back end ``mock``. Nothing heavy is imported here: the classes load when a mock starts.
"""

from __future__ import annotations

from ..drivers.camera.backends import CAMERAS, CameraBackend
from ..drivers.controller.backends import CONTROLLERS, MockServer

__all__ = ["MOCK_SERVERS", "MOCK_CAMERA", "mock_protocols", "mock_server"]

_HERE = __package__  # handeye.mocks

#: Controller back end -> the simulated controller that serves it (default ports are unprivileged).
MOCK_SERVERS = {
    "socket": MockServer(f"{_HERE}.controller.line_server:SocketControllerServer", 1025,
                         help="HeSocket executed: TCP line protocol (rapid/PROTOCOL.md)"),
    "serial": MockServer(f"{_HERE}.controller.line_server:SerialControllerServer", 1026,
                         help="HeSerial executed on a line behind pyserial's socket://HOST:PORT URL"),
    "modbus": MockServer(f"{_HERE}.controller.modbus_server:ModbusControllerServer", 5020, ("register_map",),
                         help="HeIo executed behind a Modbus TCP gateway (drivers/controller/modbus_map.yaml)"),
}



def _camera_options(section) -> dict:
    """``camera.mock_arm`` of a rehearsal station (the standalone mock controller's camera port)."""
    address = getattr(section, "mock_arm", None)
    return {"mock_arm": address} if address else {}


#: The simulated XB3 (renders the board, packs real XB3 frames): the embedded station's, or with
#: ``mock_arm`` the one on a standalone mock controller's arm (a rehearsal station).
MOCK_CAMERA = CameraBackend("mock", f"{_HERE}.cell:mock_camera", options=_camera_options, simulated=True,
                            help="simulated Bumblebee XB3 (the embedded mock station, or camera.mock_arm: the "
                                 "camera of `handeye mock controller --camera-port`)")

for _name, _server in MOCK_SERVERS.items():
    CONTROLLERS.update(_name, mock=_server)
CAMERAS.register(MOCK_CAMERA)


def mock_protocols() -> tuple[str, ...]:
    """The controller back ends a mock serves, in registry order (plug-ins that bring a mock included)."""
    return CONTROLLERS.names(lambda backend: backend.mock is not None)


def mock_server(protocol: str) -> MockServer:
    """The mock serving ``protocol``.

    Raises
    ------
    ValueError
        No registered back end of that name, or none that a mock serves.
    """
    names = mock_protocols()
    if str(protocol).lower() not in names:
        raise ValueError(f"unknown mock protocol {protocol!r}; choose one of {', '.join(names)}")
    return CONTROLLERS[protocol].mock
