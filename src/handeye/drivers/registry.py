"""Back ends by name: one registry per kind (controllers, cameras), the way python-can finds its
interfaces.

Each back end is described once, by a :class:`Backend` (its name, its class as ``"module:Class"``,
imported only when it is opened, a one-line help, and what its kind adds: default port, options from
the station config, the mock that serves it). The package registers its own back ends in code;
another installed package adds one through an entry point of the kind's group, without any change
to handeye::

    # pyproject.toml of the other package
    [project.entry-points."handeye.controllers"]
    profinet = "handeye_profinet:BACKEND"      # a ControllerBackend (or the Controller class itself)

Entry points are read at the first question asked of a registry (and again after :meth:`Registry.refresh`),
so importing handeye never imports a plug-in. Everything that lists back ends (config validation,
command-line choices, the runtime, the mocks, test parameters) asks the registry. The machinery is
:class:`handeye.base.registry.Registry`, shared with the calibration methods.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TypeVar

from ..base import Registry as _Registry
from ..base import load_target

__all__ = ["Backend", "Registry", "Setting", "chosen_with_own", "declared_settings", "keyword_options", "load_target"]


@dataclass(frozen=True)
class Backend:
    """What every back end declares.

    Attributes
    ----------
    name : str
        The name it is chosen by (``--protocol socket``, ``camera.backend: xb3``); lower case.
    target : str or type
        Its class, as ``"module:Class"`` (imported only when the back end is opened) or the class.
    help : str
        One line for ``--help`` texts: what it talks to and the options it needs.
    """

    name: str
    target: object
    help: str = ""

    def load(self) -> type:
        """The back end's class (imports its module, and so its hardware libraries, now)."""
        return load_target(self.target)


@dataclass(frozen=True)
class Setting:
    """One setting of a back end, described once: the station config's key (``controller.<key>`` of a
    controller back end, ``camera.<key>`` of a camera back end; checked and documented from this), the
    command-line flag (``handeye robot``'s, or ``handeye mock controller``'s for a mock's option) and
    the keyword of the back end's class. The controller back ends call it ``LinkSetting``.

    Attributes
    ----------
    key : str
        The key in its config section (``serial_url``; for a controller also on ``ControllerLink``).
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
        ``check(value, name) -> value``: a check of its own, raising ``ValueError`` (the controllers'
        ``InvalidRequest`` is one) naming ``name``.
    required : str
        Not empty: the back end cannot open without it; what it is, for the message (``a device or pyserial URL``).
    note : str
        More about it for the documented example (``src/handeye/station/config/example_station.yaml``), beyond ``help``.
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
    note: str = ""

    @property
    def option(self) -> str:
        """The command-line flag."""
        return self.flag or "--" + self.key.replace("_", "-")

    @property
    def usage(self) -> str:
        """The flag with its value (``--url DEVICE_OR_URL``), in brackets when it may be left out."""
        text = f"{self.option} {self.metavar or self.key.upper()}"
        return text if self.required else f"[{text}]"


def declared_settings(registry: _Registry, attribute: str, names: Iterable[str] | None = None) -> dict:
    """``{key: (Setting, names of the back ends declaring it)}`` over the back ends ``names`` of
    ``registry`` (registry order; default: those loaded, :meth:`~handeye.base.registry.Registry.loaded_names`:
    handeye's own and the plug-ins asked for so far, so describing settings imports no other plug-in),
    from each one's ``attribute`` (a tuple of :class:`Setting`): the keys of one station config section.
    Two back ends sharing a key share its description (the first one's)."""
    out: dict = {}
    for name in registry.loaded_names() if names is None else names:
        backend = registry.get(name)
        if backend is None:
            continue
        for setting in getattr(backend, attribute):
            first, declaring = out.get(setting.key, (setting, ()))
            out[setting.key] = (first, declaring + (name,))
    return out


def chosen_with_own(registry: _Registry, chosen: object) -> tuple[str, ...]:
    """The names of ``registry``'s own back ends (registered in code), and ``chosen`` when it is a plug-in's
    that loads: the back ends whose settings a station config section using ``chosen`` may hold."""
    own = registry.names_in_code()
    if isinstance(chosen, str) and chosen not in own and registry.get(chosen) is not None:
        return own + (chosen,)
    return own


def keyword_options(settings: Iterable[Setting], value_of: Callable, missing: Callable) -> dict:
    """The class's keyword options of ``settings`` (:class:`Setting` s) whose value ``value_of(key)`` is
    set (not None); ``missing(setting)`` makes the exception raised for a required one that is not."""
    out = {}
    for setting in settings:
        value = value_of(setting.key)
        if value is None and setting.required:
            raise missing(setting)
        if value is not None:
            out[setting.keyword or setting.key] = value
    return out


B = TypeVar("B", bound=Backend)


class Registry(_Registry[B]):
    """Back ends of one kind by name, in registration order (the package's first, then plug-ins):
    :class:`handeye.base.registry.Registry` whose entry points may also name a class.

    Parameters
    ----------
    kind : str
        What they are, for messages (``controller protocol``, ``camera back end``).
    group : str
        The entry-point group other packages register theirs in (``handeye.controllers``).
    entry_type : type
        The :class:`Backend` subclass of this kind; an entry point may also name a class, which is
        then described with the defaults of ``entry_type``.
    """

    def _describe(self, name: str, obj) -> B:
        if isinstance(obj, self.entry_type):
            return obj
        if isinstance(obj, type):
            return self.entry_type(name=name.lower(), target=obj, help=f"{name} ({obj.__module__}.{obj.__qualname__})")
        raise TypeError(f"an entry point of {self.group} must name a {self.entry_type.__name__} or a class; "
                        f"got {type(obj).__name__}")
