"""The controller back ends: each described once, in :data:`CONTROLLERS`.

A back end is a :class:`ControllerBackend`: its name (the ``--protocol`` and ``controller.protocol``
word), its class, the port it listens on by default, its own link settings (:class:`LinkSetting`:
key, type, default, help, flag; the station config's keys, the flags of ``handeye robot``,
:class:`ControllerLink` and the class's keywords all come from them), the RAPID link module the controller
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

__all__ = ["ControllerBackend", "ControllerLink", "LinkSetting", "MockServer", "CONTROLLERS", "DEFAULT_PROTOCOL", "RAPID_LINKS",
           "link_settings", "register_backend", "setting_options", "standard_options", "tcp_options"]


@dataclass(frozen=True)
class LinkSetting:
    """One setting of a back end's link, described once: the station config's key
    (``controller.<key>``, checked and documented from this), the command-line flag of ``handeye
    robot`` and the keyword of the back end's class.

    Attributes
    ----------
    key : str
        The key in the config's ``controller`` section and on :class:`ControllerLink` (``serial_url``).
    type : type
        ``str``, ``int`` or ``float``: what a value is (the config checks it, the command line parses it).
    default : object
        The config's value when the file names none (None: unset, the class's own default).
    help : str
        What it is, one line (the config's doc and the flag's help; the back ends' names go in front).
    flag : str or None
        The command-line flag (default ``--key`` with ``-`` for ``_``).
    keyword : str or None
        The class's keyword argument (default: ``key``).
    metavar : str or None
        The flag's value in ``--help``.
    low, high : float
        Range of a number.
    secret : bool
        Never printed (masked in the config's record).
    check : callable or None
        ``check(value, name) -> value``: a check of its own, raising :class:`InvalidRequest` naming ``name``.
    required : str
        Not empty: the link cannot open without it; what it is, for the message (``a device or pyserial URL``).
    """

    key: str
    type: type = str
    default: object = None
    help: str = ""
    flag: str | None = None
    keyword: str | None = None
    metavar: str | None = None
    low: float = float("-inf")
    high: float = float("inf")
    secret: bool = False
    check: Callable | None = None
    required: str = ""

    @property
    def option(self) -> str:
        """The command-line flag."""
        return self.flag or "--" + self.key.replace("_", "-")


def link_settings() -> dict[str, tuple[LinkSetting, tuple[str, ...]]]:
    """Every back end's link settings by key, with the back ends that declare it (registry order):
    the keys of the config's ``controller`` section and the flags of ``handeye robot`` beyond
    ``host`` and ``port``. Two back ends sharing a key share its description (the first one's)."""
    out: dict[str, tuple[LinkSetting, tuple[str, ...]]] = {}
    for name in CONTROLLERS:
        for setting in CONTROLLERS[name].link_settings:
            first, names = out.get(setting.key, (setting, ()))
            out[setting.key] = (first, names + (name,))
    return out


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
        Values of link settings by key (None: not set). A key no back end declares reads as None.
    """

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, **settings):
        self.host, self.port = host, port
        self.settings = {key: value for key, value in settings.items() if value is not None}

    def get(self, key: str, default=None):
        """The value of a link setting (``default`` when not set)."""
        return self.settings.get(key, default)

    def __getattr__(self, name: str):
        if name.startswith("_") or name == "settings":
            raise AttributeError(name)
        return self.settings.get(name)

    def __eq__(self, other) -> bool:
        return isinstance(other, ControllerLink) and (self.host, self.port, self.settings) == \
            (other.host, other.port, other.settings)

    def __repr__(self) -> str:
        shown = {key: "<set>" if key in _secret_keys() else value for key, value in self.settings.items()}
        return f"ControllerLink(host={self.host!r}, port={self.port!r}, settings={shown!r})"

    @classmethod
    def of(cls, section) -> "ControllerLink":
        """The link of any object with these attributes (the station config's controller section)."""
        keys = link_settings()
        return cls(getattr(section, "host", "127.0.0.1"), getattr(section, "port", None),
                   **{key: getattr(section, key, None) for key in keys})


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
    options = {}
    for setting in backend.link_settings:
        value = link.get(setting.key)
        if value is None and setting.required:
            raise InvalidRequest(f"the {backend.name} link needs {setting.required} ({setting.option} "
                                 f"{setting.metavar or setting.key.upper()}; controller.{setting.key} in a station config)")
        if value is not None:
            options[setting.keyword or setting.key] = value
    return options


def standard_options(link: ControllerLink, backend: "ControllerBackend") -> dict:
    """``host``, ``port`` (:func:`tcp_options`) and the back end's link settings (:func:`setting_options`)."""
    return {**tcp_options(link, backend), **setting_options(link, backend)}


@dataclass(frozen=True)
class ControllerBackend(Backend):
    """A controller back end (see the module docstring).

    Attributes
    ----------
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

    def link_options(self, link) -> dict:
        """The class's keyword options for ``link`` (a :class:`ControllerLink` or a config section)."""
        return self.options(link if isinstance(link, ControllerLink) else ControllerLink.of(link), self)


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
    LinkSetting("username", str, "Default User", "the controller user (give the station its own)", flag="--user"),
    LinkSetting("password", str, None, "that user's password (default: RobotWare's default account's)", secret=True),
    LinkSetting("tls_fingerprint", str, None, "RobotWare 7: SHA-256 of the controller's certificate (HTTPS, pinned; "
                "port 443); none: RobotWare 6 over HTTP", metavar="SHA256", check=_fingerprint),
)


#: The protocol a command or a mock uses when none is named (``--protocol``, ``mock.protocol``).
DEFAULT_PROTOCOL = "socket"

#: Every controller back end by name: the package's (socket, serial, modbus, rws), then plug-ins.
CONTROLLERS: Registry[ControllerBackend] = Registry("controller protocol", "handeye.controllers", ControllerBackend)

_HERE = __package__
_LINKS = f"{__package__.rsplit('.', 2)[0]}.rapid.links"  # handeye.rapid.links: the RAPID side of each
CONTROLLERS.register(ControllerBackend(
    "socket", f"{_HERE}.socket_client:SocketController", default_port=1025, rapid_link=f"{_LINKS}:HE_SOCKET",
    help="TCP to the HeSocket RAPID module:   --host H --port P (default 1025)"))
CONTROLLERS.register(ControllerBackend(
    "serial", f"{_HERE}.serial_client:SerialController", link_settings=_SERIAL, options=setting_options,
    rapid_link=f"{_LINKS}:HE_SERIAL",
    help="serial channel (HeSerial module):   --url DEVICE_OR_URL [--baudrate B]"))
CONTROLLERS.register(ControllerBackend(
    "modbus", f"{_HERE}.modbus_client:ModbusController", default_port=502, link_settings=_MODBUS,
    rapid_link=f"{_LINKS}:HE_IO",
    help="Modbus TCP gateway (HeIo module):   --host H --port P (default 502) [--register-map MAP]"))
CONTROLLERS.register(ControllerBackend(
    "rws", f"{_HERE}.rws_client:RwsController", default_port=80, link_settings=_RWS, options=_rws_options,
    rapid_link=f"{_LINKS}:HE_RWS",
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
