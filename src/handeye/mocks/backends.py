"""The mocks register themselves with the drivers' back-end registries (the drivers never name them).

Importing ``handeye.mocks`` (any of its modules) runs this: the simulated controller servers become
the ``mock`` of the package's controller back ends (:data:`MOCK_SERVERS`; a plug-in's back end brings
its own in its registry entry), and the simulated XB3 becomes the
camera back end ``mock``. Nothing heavy is imported here: the classes load when a mock starts.
"""

from __future__ import annotations

from ..drivers import CAMERAS, CameraBackend
from ..drivers import CONTROLLERS, LinkSetting, MockServer

__all__ = ["MOCK_SERVERS", "MOCK_CAMERA", "MockVariant", "mock_protocol_choices", "mock_protocols", "mock_server",
           "mock_settings", "mock_variants"]

_HERE = __package__  # handeye.mocks

#: Controller back end -> the simulated controller that serves it (default ports are unprivileged).
MOCK_SERVERS = {
    "socket": MockServer(f"{_HERE}.controller.line_server:SocketControllerServer", 1025,
                         help="HeSocket executed: TCP line protocol (src/handeye/rapid/PROTOCOL.md)"),
    "serial": MockServer(f"{_HERE}.controller.line_server:SerialControllerServer", 1026,
                         help="HeSerial executed on a line behind pyserial's socket://HOST:PORT URL"),
    "modbus": MockServer(f"{_HERE}.controller.modbus_server:ModbusControllerServer", 5020,
                         (LinkSetting("register_map", str, None, "register map YAML (default: the built-in one)",
                                      metavar="MAP.yaml"),),
                         help="HeIo executed behind a Modbus TCP gateway (src/handeye/drivers/controller/modbus_map.yaml)"),
    "rws": MockServer(f"{_HERE}.controller.rws_server:RwsControllerServer", 8080,
                      (LinkSetting("generation", int, 1, "1 = RobotWare 6 (HTTP, Digest; default), 2 = RobotWare 7 "
                                   "(HTTPS with a self-signed certificate, Basic; the banner prints its fingerprint, "
                                   "which is new at every start: a certificate is made for each run)",
                                   flag="--rws-generation", low=1, high=2, metavar="{1,2}"),),
                      help="HeRws executed behind Robot Web Services (--rws-generation 1: RobotWare 6 HTTP/Digest; "
                           "2: RobotWare 7 HTTPS/Basic)",
                      variants=(("rws1", {"generation": 1}), ("rws2", {"generation": 2}))),
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


def _has_mock(backend) -> bool:
    return backend.mock is not None


def _mock_of(name: str) -> MockServer:
    """The mock of a protocol :func:`mock_protocols` names (those have one)."""
    mock = CONTROLLERS[name].mock
    if mock is None:
        raise ValueError(f"the controller back end {name!r} has no mock")
    return mock


def mock_protocols(loaded: bool = False) -> tuple[str, ...]:
    """The controller back ends a mock serves, in registry order (plug-ins that bring a mock included;
    each plug-in is loaded, under the time bound, to know); with ``loaded``, of those loaded so far only
    (handeye's own and the plug-ins a command asked for: no other plug-in is imported)."""
    if loaded:
        return tuple(name for name in CONTROLLERS.loaded_names() if _has_mock(CONTROLLERS[name]))
    return CONTROLLERS.names(_has_mock)


def mock_protocol_choices():
    """The protocols a mock serves, checked one at a time (asking about one imports that plug-in only: the
    demo's ``--protocol``, ``mock.protocol``); one left out says it has no mock."""
    return CONTROLLERS.choices(_has_mock, lacking="has no mock (its ControllerBackend.mock is None), so nothing can "
                                                  "simulate its controller")


def mock_settings(loaded: bool = False) -> dict:
    """Every mock server's own options by key, with the protocols whose mock takes it (registry order):
    the flags of ``handeye mock controller`` beyond the common ones; with ``loaded``, of the protocols
    loaded so far only (:func:`mock_protocols`)."""
    out: dict = {}
    for name in mock_protocols(loaded):
        for setting in _mock_of(name).settings():
            first, names = out.get(setting.key, (setting, ()))
            out[setting.key] = (first, names + (name,))
    return out


def mock_server(protocol: str) -> MockServer:
    """The mock serving ``protocol``.

    Raises
    ------
    ValueError
        No registered back end of that name, or none that a mock serves.
    """
    backend = CONTROLLERS.get(str(protocol).lower())  # that back end only: no other plug-in is imported
    if backend is None or backend.mock is None:
        raise ValueError(f"unknown mock protocol {protocol!r}; choose one of {', '.join(mock_protocols())}")
    return backend.mock


class MockVariant(str):
    """A mock protocol name carrying server settings: equal to the protocol's name (``"rws"``), so it
    opens the same client back end, with ``label`` (``rws2``) and ``options`` (``{"generation": 2}``)
    that :func:`~handeye.mocks.controller.start_mock_controller` passes to the server."""

    label: str
    options: dict

    def __new__(cls, protocol: str, label: str, options: dict) -> MockVariant:
        obj = super().__new__(cls, protocol)
        obj.label, obj.options = label, dict(options)
        return obj

    def __repr__(self) -> str:
        return self.label


def mock_variants() -> tuple[str, ...]:
    """Every mock protocol, and each variant of a mock that has them (RWS 1.0 and 2.0): what the
    contract tests run on. Plain names for mocks without variants, :class:`MockVariant` otherwise."""
    out = []
    for name in mock_protocols():
        variants = _mock_of(name).variants
        out += [MockVariant(name, label, options) for label, options in variants] if variants else [name]
    return tuple(out)
