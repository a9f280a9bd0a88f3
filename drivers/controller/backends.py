"""The controller back ends: each described once, in :data:`CONTROLLERS`.

A back end is a :class:`ControllerBackend`: its name (the ``--protocol`` and ``controller.protocol``
word), its class, the port it listens on by default, how its options are built from where the
station config (or the command line) says the controller is, the RAPID link module the controller
runs for it (a ``rapid.links.RapidLink``: a template or a renderer), the mock that serves it (the
package's own are filled in by ``handeye.mocks``; the drivers never name the mocks) and one line of
help. Another package adds one with :func:`register_backend` or an entry point in the
``handeye.controllers`` group, bringing its own RAPID link and mock in the same entry.

Nothing here imports a hardware library: the class is imported when the back end is opened.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass

from ..registry import Backend, Registry, load_target
from .errors import InvalidRequest

__all__ = ["ControllerBackend", "ControllerLink", "MockServer", "CONTROLLERS", "RAPID_LINKS", "register_backend",
           "tcp_options"]


@dataclass(frozen=True)
class ControllerLink:
    """Where a controller is: the fields of the station config's ``controller`` section that say so,
    or the same from the command line (``--host``, ``--port``, ``--url``, ``--register-map``).

    Attributes
    ----------
    host : str
    port : int or None
        None: the back end's default port.
    serial_url : str or None
        Serial device or pyserial URL.
    modbus_map : str or None
        Register map YAML (None: the built-in one).
    baudrate : int or None
        Serial baud rate (None: the back end's default).
    username, password : str or None
        Robot Web Services: the controller user (None: RobotWare's default account).
    tls_fingerprint : str or None
        Robot Web Services 2.0: SHA-256 of the controller's certificate (HTTPS, pinned).
    """

    host: str = "127.0.0.1"
    port: int | None = None
    serial_url: str | None = None
    modbus_map: str | None = None
    baudrate: int | None = None
    username: str | None = None
    password: str | None = None
    tls_fingerprint: str | None = None

    @classmethod
    def of(cls, section) -> "ControllerLink":
        """The link of any object with these attributes (the station config's controller section)."""
        return cls(**{name: getattr(section, name, None) for name in cls.__dataclass_fields__})


@dataclass(frozen=True)
class MockServer:
    """The simulated controller that serves a back end (``handeye mock controller``, the demo).

    Attributes
    ----------
    target : str or type
        The server class (``"module:Class"``), called as ``cls(program, robot, host, port, faults=...,
        idle_timeout_s=..., write_key=..., **options)`` (``program``: the RAPID modules it runs,
        ``robot``: the simulated arm); it has ``start``, ``stop`` and ``client_options()``.
    default_port : int
        Where ``handeye mock controller`` listens when no ``--port`` is given (unprivileged).
    options : tuple of str
        The extra keyword options the server takes (``allowed_client``, ``register_map`` ...).
    help : str
        One line for ``handeye mock controller --help``: what it serves.
    variants : tuple of (str, dict)
        Named settings of the server the contract tests run each (``("rws2", {"generation": 2})``);
        empty: the server as it is.
    """

    target: object
    default_port: int
    options: tuple = ()
    help: str = ""
    variants: tuple = ()

    def load(self) -> type:
        return load_target(self.target)


def tcp_options(link: ControllerLink, backend: "ControllerBackend") -> dict:
    """``host`` and ``port`` (the back end's default port when the link names none)."""
    return {"host": link.host, "port": link.port if link.port is not None else backend.default_port}


@dataclass(frozen=True)
class ControllerBackend(Backend):
    """A controller back end (see the module docstring).

    Attributes
    ----------
    default_port : int or None
        The port its controller side listens on by default (None: not a TCP back end).
    options : callable
        ``options(link, backend) -> dict``: the keyword options of the class for a
        :class:`ControllerLink` (default: :func:`tcp_options`).
    mock : MockServer or None
        The simulated controller serving it (None: no mock).
    rapid_link : str or object or None
        The RAPID link module its controller runs (a ``handeye.rapid.links.RapidLink``, or
        ``"module:attribute"`` naming one, imported when asked); None: no generated program
        (``handeye capture`` and ``rapid generate`` refuse the protocol).
    """

    default_port: int | None = None
    options: Callable = tcp_options
    mock: MockServer | None = None
    rapid_link: object = None

    def link_options(self, link) -> dict:
        """The class's keyword options for ``link`` (a :class:`ControllerLink` or a config section)."""
        return self.options(link if isinstance(link, ControllerLink) else ControllerLink.of(link), self)


def _serial_options(link: ControllerLink, backend: ControllerBackend) -> dict:
    if not link.serial_url:
        raise InvalidRequest(f"the {backend.name} link needs a device or pyserial URL (--url /dev/ttyUSB0 or "
                             "socket://HOST:PORT; controller.serial_url in a station config)")
    return {"url": link.serial_url, **({"baudrate": link.baudrate} if link.baudrate else {})}


def _modbus_options(link: ControllerLink, backend: ControllerBackend) -> dict:
    return {**tcp_options(link, backend), **({"register_map": link.modbus_map} if link.modbus_map else {})}


def _rws_options(link: ControllerLink, backend: ControllerBackend) -> dict:
    # no port named: 443 with a certificate fingerprint (RWS 2.0, HTTPS), else 80 (RWS 1.0, HTTP)
    default = backend.default_port if link.tls_fingerprint is None else 443
    options = {"host": link.host, "port": link.port if link.port is not None else default}
    for name in ("username", "password", "tls_fingerprint"):
        if getattr(link, name) is not None:
            options[name] = getattr(link, name)
    return options


#: Every controller back end by name: the package's (socket, serial, modbus, rws), then plug-ins.
CONTROLLERS: Registry[ControllerBackend] = Registry("controller protocol", "handeye.controllers", ControllerBackend)

_HERE = __package__
_LINKS = f"{__package__.rsplit('.', 2)[0]}.rapid.links"  # handeye.rapid.links: the RAPID side of each
CONTROLLERS.register(ControllerBackend(
    "socket", f"{_HERE}.socket_client:SocketController", default_port=1025, rapid_link=f"{_LINKS}:HE_SOCKET",
    help="TCP to the HeSocket RAPID module:   --host H --port P (default 1025)"))
CONTROLLERS.register(ControllerBackend(
    "serial", f"{_HERE}.serial_client:SerialController", options=_serial_options, rapid_link=f"{_LINKS}:HE_SERIAL",
    help="serial channel (HeSerial module):   --url DEVICE_OR_URL [--baudrate B]"))
CONTROLLERS.register(ControllerBackend(
    "modbus", f"{_HERE}.modbus_client:ModbusController", default_port=502, options=_modbus_options,
    rapid_link=f"{_LINKS}:HE_IO",
    help="Modbus TCP gateway (HeIo module):   --host H --port P (default 502) [--register-map MAP]"))
CONTROLLERS.register(ControllerBackend(
    "rws", f"{_HERE}.rws_client:RwsController", default_port=80, options=_rws_options, rapid_link=f"{_LINKS}:HE_RWS",
    help="Robot Web Services (RobotWare 6/7, HeRws module): --host H [--port P] [--user U --password W] "
         "[--tls-fingerprint SHA256 for RobotWare 7]"))


class _RapidLinks(Mapping):
    """Protocol -> the RAPID link module of every controller back end that carries one, in registry
    order (plug-ins included; each loaded when asked). What the station hands to ``rapid``
    (``RapidStation.links``), which never reads the registry itself."""

    def __getitem__(self, name: str):
        backend = CONTROLLERS.get(str(name).lower())
        if backend is None or backend.rapid_link is None:
            raise KeyError(name)
        return load_target(backend.rapid_link)

    def __iter__(self) -> Iterator[str]:
        return iter(CONTROLLERS.names(lambda backend: backend.rapid_link is not None))

    def __len__(self) -> int:
        return len(CONTROLLERS.names(lambda backend: backend.rapid_link is not None))


#: The RAPID link module of every controller back end that has one (read from :data:`CONTROLLERS`).
RAPID_LINKS: Mapping = _RapidLinks()


def register_backend(backend: ControllerBackend) -> ControllerBackend:
    """Add a controller back end (or replace the one of the same name); returns it."""
    return CONTROLLERS.register(backend)
