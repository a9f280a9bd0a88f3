"""The controller back ends: each described once, in :data:`CONTROLLERS`.

A back end is a :class:`ControllerBackend`: its name (the ``--protocol`` and ``controller.protocol``
word), its class, the port it listens on by default, its own link settings (:class:`LinkSetting`:
key, type, default, help, flag; the station config's keys, the flags of ``handeye robot``,
:class:`ControllerLink` and the class's keywords all come from them), the RAPID link module the controller
runs for it (a ``rapid.links.RapidLink``: a template or a renderer), the mock that serves it (the
package's own are filled in by ``handeye.mocks``; the drivers never name the mocks) and one line of
help: what it talks to (its options are written from its settings, :meth:`ControllerBackend.usage`;
``handeye robot --help``, ``rapid generate --help`` and ``src/handeye/station/config/example_station.yaml`` read them all
here). Another package adds one with :func:`register_backend` or an entry point in the
``handeye.controllers`` group, bringing its own RAPID link and mock in the same entry.

Nothing here imports a hardware library: the class is imported when the back end is opened.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..registry import Backend, Registry, Setting, declared_settings, keyword_options, load_target
from .errors import InvalidRequest

if TYPE_CHECKING:
    from ...base import Choices

__all__ = ["ControllerBackend", "ControllerLink", "LinkSetting", "MockServer", "CONTROLLERS", "DEFAULT_PROTOCOL", "RAPID_LINKS",
           "link_settings", "rapid_protocol_choices", "register_backend", "setting_options", "standard_options", "tcp_options"]


#: A controller back end's setting (:class:`handeye.drivers.registry.Setting`: the station config's
#: ``controller.<key>``, a flag of ``handeye robot``, a keyword of the class).
LinkSetting = Setting


def link_settings(names: Iterable[str] | None = None) -> dict[str, tuple[LinkSetting, tuple[str, ...]]]:
    """The back ends' link settings by key, with the back ends that declare it (registry order): of
    ``names`` (default: every back end loaded so far, :func:`~handeye.drivers.registry.declared_settings`,
    so no other plug-in is imported): the keys of the config's ``controller`` section and the flags of
    ``handeye robot`` beyond ``host`` and ``port``. Two back ends sharing a key share its description
    (the first one's)."""
    return declared_settings(CONTROLLERS, "link_settings", names)


class ControllerLink:
    """Where a controller is: ``host``, ``port`` and the back ends' own settings by key
    (``serial_url``, ``modbus_map`` ...: :func:`link_settings`), from the station config's
    ``controller`` section or the command line.

    Parameters
    ----------
    host : str
    port : int or None
        None: the back end's default port.
    **settings
        Values of link settings by key (None: not set); read back as ``link.serial_url`` or
        ``link.get("serial_url")``.

    Raises
    ------
    TypeError
        A key no registered back end declares (a misspelt setting is refused, never read as unset);
        reading one raises ``AttributeError`` (``link.key``) or ``KeyError`` (``link.get``) the same way.
    """

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, **settings: Any):
        unknown = sorted(set(settings) - set(link_settings()))
        if unknown:
            raise TypeError(_unknown_setting(unknown[0]))
        self.host, self.port = host, port
        self.settings = {key: value for key, value in settings.items() if value is not None}

    def get(self, key: str, default: Any = None) -> Any:
        """The value of a link setting (``default`` when not set); a key no back end declares raises ``KeyError``."""
        if key not in self.settings and key not in link_settings():
            raise KeyError(_unknown_setting(key))
        return self.settings.get(key, default)

    def __getattr__(self, name: str) -> Any:
        """A link setting by key (None when not set); a key no back end declares raises ``AttributeError``."""
        if name.startswith("_") or name == "settings":
            raise AttributeError(name)
        if name not in link_settings():
            raise AttributeError(_unknown_setting(name))
        return self.settings.get(name)

    def __eq__(self, other) -> bool:
        return isinstance(other, ControllerLink) and (self.host, self.port, self.settings) == \
            (other.host, other.port, other.settings)

    def __repr__(self) -> str:
        shown = {key: "<set>" if key in _secret_keys() else value for key, value in self.settings.items()}
        return f"ControllerLink(host={self.host!r}, port={self.port!r}, settings={shown!r})"

    @classmethod
    def of(cls, section: object) -> "ControllerLink":
        """The link of any object with these attributes (the station config's controller section)."""
        keys = link_settings()
        return cls(getattr(section, "host", "127.0.0.1"), getattr(section, "port", None),
                   **{key: getattr(section, key, None) for key in keys})


def _unknown_setting(name: str) -> str:
    """The one line for a link setting no registered back end declares, naming those they do."""
    known = ", ".join(["host", "port", *link_settings()])
    return f"no controller link setting {name!r}; the registered back ends declare: {known}"


def _secret_keys() -> set:
    return {key for key, (setting, _) in link_settings().items() if setting.secret}


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
    options : tuple of LinkSetting (or str)
        The extra keyword options the server takes, described once (key, type, default, help, flag):
        the flags of ``handeye mock controller`` come from them. A bare name is an option without a flag.
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

    def settings(self) -> tuple:
        """:attr:`options` as :class:`LinkSetting` s (a bare name: a text option without a flag of its own)."""
        return tuple(o if isinstance(o, LinkSetting) else LinkSetting(str(o)) for o in self.options)


def tcp_options(link: ControllerLink, backend: "ControllerBackend") -> dict:
    """``host`` and ``port`` (the back end's default port when the link names none)."""
    return {"host": link.host, "port": link.port if link.port is not None else backend.default_port}


def setting_options(link: ControllerLink, backend: "ControllerBackend") -> dict:
    """The class's keywords of the back end's :class:`LinkSetting` s that ``link`` sets.

    Raises
    ------
    InvalidRequest
        A required setting is not set.
    """
    return keyword_options(backend.link_settings, link.get, lambda setting: InvalidRequest(
        f"the {backend.name} link needs {setting.required} ({setting.option} {setting.metavar or setting.key.upper()}; "
        f"controller.{setting.key} in a station config)"))


def standard_options(link: ControllerLink, backend: "ControllerBackend") -> dict:
    """``host``, ``port`` (:func:`tcp_options`) and the back end's link settings (:func:`setting_options`)."""
    return {**tcp_options(link, backend), **setting_options(link, backend)}


@dataclass(frozen=True)
class ControllerBackend(Backend):
    """A controller back end (see the module docstring).

    Attributes
    ----------
    help : str
        What it talks to, one line without its options (``TCP to the RAPID program's server``): the
        help texts add the RAPID module and :meth:`usage`.
    default_port : int or None
        The port its controller side listens on by default (None: not a TCP back end).
    link_settings : tuple of LinkSetting
        Its own settings beyond ``host`` and ``port``, described once: the station config's keys,
        the flags of ``handeye robot`` and the class's keywords come from them.
    options : callable
        ``options(link, backend) -> dict``: the keyword options of the class for a
        :class:`ControllerLink` (default: :func:`standard_options`: host, port and ``link_settings``).
    mock : MockServer or None
        The simulated controller serving it (None: no mock).
    rapid_link : str or object or None
        The RAPID link module its controller runs (a ``handeye.rapid.links.RapidLink``, or
        ``"module:attribute"`` naming one, imported when asked); None: no generated program
        (``handeye capture`` and ``rapid generate`` refuse the protocol).
    """

    default_port: int | None = None
    link_settings: tuple = ()
    options: Callable = standard_options
    mock: MockServer | None = None
    rapid_link: object = None

    def link_options(self, link: object) -> dict:
        """The class's keyword options for ``link`` (a :class:`ControllerLink` or a config section)."""
        return self.options(link if isinstance(link, ControllerLink) else ControllerLink.of(link), self)

    def usage(self) -> str:
        """Its command-line link options, from its declarations: ``--host H [--port P, default 502]`` for a
        TCP back end (one with a default port), then each link setting's :attr:`LinkSetting.usage`."""
        words = [] if self.default_port is None else ["--host H", f"[--port P, default {self.default_port}]"]
        return " ".join(words + [setting.usage for setting in self.link_settings]) or "no options"


def _rws_options(link: ControllerLink, backend: ControllerBackend) -> dict:
    # no port named: 443 with a certificate fingerprint (RWS 2.0, HTTPS), else 80 (RWS 1.0, HTTP)
    default = backend.default_port if link.get("tls_fingerprint") is None else 443
    return {"host": link.host, "port": link.port if link.port is not None else default,
            **setting_options(link, backend)}


def _fingerprint(value, name: str) -> str:
    from .types import check_fingerprint  # noqa: PLC0415 (the types module is light, but only needed here)

    return check_fingerprint(value, name)


_SERIAL = (
    LinkSetting("serial_url", str, "socket://127.0.0.1:1026", "device or pyserial URL", flag="--url", keyword="url",
                metavar="DEVICE_OR_URL", required="a device or pyserial URL"),
    LinkSetting("baudrate", int, None, "baud rate (default 9600)", low=1, high=10_000_000, metavar="B"),
)
_MODBUS = (LinkSetting("modbus_map", str, None, "register map YAML (default: the built-in one)", flag="--register-map",
                       keyword="register_map", metavar="MAP.yaml"),)
_RWS = (
    LinkSetting("username", str, "Default User", "the controller user (give the station its own)", flag="--user",
                note="Robot Web Services authorises tool writes by the controller's own users, not by "
                "write_key: create one for the station with only the rights it needs"),
    LinkSetting("password", str, None, "that user's password (default: RobotWare's default account's)", secret=True,
                note="SECRET: never printed"),
    LinkSetting("tls_fingerprint", str, None, "RobotWare 7: SHA-256 of the controller's certificate (HTTPS, pinned; "
                "port 443); none: RobotWare 6 over HTTP", metavar="SHA256", check=_fingerprint,
                note="64 hex digits (colons allowed); RobotWare 6 uses Digest authentication. Read it from the "
                     "FlexPendant, or: openssl s_client -connect HOST:443 </dev/null | openssl x509 -noout "
                     "-fingerprint -sha256"),
)


#: The protocol a command or a mock uses when none is named (``--protocol``, ``mock.protocol``).
DEFAULT_PROTOCOL = "socket"

#: Every controller back end by name: the package's (socket, serial, modbus, rws), then plug-ins.
CONTROLLERS: Registry[ControllerBackend] = Registry("controller protocol", "handeye.controllers", ControllerBackend)

_HERE = __name__.rpartition(".")[0]  # this package (what __package__ holds; the type checker sees str | None)
_LINKS = f"{_HERE.rsplit('.', 2)[0]}.rapid.links"  # handeye.rapid.links: the RAPID side of each
CONTROLLERS.register(ControllerBackend(
    "socket", f"{_HERE}.socket_client:SocketController", default_port=1025, rapid_link=f"{_LINKS}:HE_SOCKET",
    help="TCP to the RAPID program's server (PC Interface option)"))
CONTROLLERS.register(ControllerBackend(
    "serial", f"{_HERE}.serial_client:SerialController", link_settings=_SERIAL, options=setting_options,
    rapid_link=f"{_LINKS}:HE_SERIAL",
    help="a serial channel, the same line protocol"))
CONTROLLERS.register(ControllerBackend(
    "modbus", f"{_HERE}.modbus_client:ModbusController", default_port=502, link_settings=_MODBUS,
    rapid_link=f"{_LINKS}:HE_IO",
    help="a Modbus TCP gateway to the controller's I/O"))
CONTROLLERS.register(ControllerBackend(
    "rws", f"{_HERE}.rws_client:RwsController", default_port=80, link_settings=_RWS, options=_rws_options,
    rapid_link=f"{_LINKS}:HE_RWS",
    help="Robot Web Services, RobotWare 6 (HTTP) or 7 (HTTPS, port 443 with a tls_fingerprint)"))


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


def rapid_protocol_choices() -> Choices:
    """The protocols ``rapid generate`` can write a link module for, checked one at a time (asking about one
    imports that plug-in only); one left out says it has no RAPID link module."""
    return CONTROLLERS.choices(lambda backend: backend.rapid_link is not None,
                               lacking="has no RAPID link module (its ControllerBackend.rapid_link is None)")


def register_backend(backend: ControllerBackend) -> ControllerBackend:
    """Add a controller back end (or replace the one of the same name); returns it."""
    return CONTROLLERS.register(backend)
