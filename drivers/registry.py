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
command-line choices, the runtime, the mocks, test parameters) asks the registry.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import logging
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from typing import Generic, TypeVar

__all__ = ["Backend", "Registry", "load_target"]

log = logging.getLogger(__name__)


def load_target(target):
    """The object a ``"module:attribute"`` string names (imported now), or ``target`` itself."""
    if not isinstance(target, str):
        return target
    module_name, _, attribute = target.partition(":")
    obj = importlib.import_module(module_name)
    for part in attribute.split(".") if attribute else ():
        obj = getattr(obj, part)
    return obj


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


B = TypeVar("B", bound=Backend)


class Registry(Mapping, Generic[B]):
    """Back ends of one kind by name, in registration order (the package's first, then plug-ins).

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

    def __init__(self, kind: str, group: str, entry_type: type[B]):
        self.kind, self.group, self.entry_type = kind, group, entry_type
        self._registered: dict[str, B] = {}
        self._discovered: dict[str, B] | None = None  # None: entry points not read yet

    # ------------------------------------------------------------------ filling
    def register(self, backend: B) -> B:
        """Add ``backend`` (or replace the one of the same name); returns it."""
        if not isinstance(backend, self.entry_type):
            raise TypeError(f"a {self.kind} is registered as a {self.entry_type.__name__}; got {type(backend).__name__}")
        backend = replace(backend, name=backend.name.lower())
        self._registered[backend.name] = backend
        return backend

    def unregister(self, name: str) -> None:
        """Remove a back end registered in code (entry points come back at the next refresh)."""
        self._registered.pop(name.lower(), None)

    def update(self, name: str, **changes) -> B:
        """Change some fields of a registered back end (``mock=...`` from the mocks); returns it."""
        return self.register(replace(self[name], **changes))

    def refresh(self) -> None:
        """Forget the entry points read so far: the next question reads them again (new installs)."""
        self._discovered = None
        importlib.invalidate_caches()

    def _entry_points(self) -> dict[str, B]:
        if self._discovered is None:
            found: dict[str, B] = {}
            for point in importlib.metadata.entry_points(group=self.group):
                try:
                    backend = self._describe(point.name, point.load())
                except Exception as exc:  # a broken plug-in must not break the package
                    log.warning("%s %r from entry point %s is unusable: %s", self.kind, point.name, point.value, exc)
                    continue
                if backend.name not in self._registered:
                    found.setdefault(backend.name, backend)
            self._discovered = found
        return self._discovered

    def _describe(self, name: str, obj) -> B:
        if isinstance(obj, self.entry_type):
            return obj
        if isinstance(obj, type):
            return self.entry_type(name=name.lower(), target=obj, help=f"{name} ({obj.__module__}.{obj.__qualname__})")
        raise TypeError(f"an entry point of {self.group} must name a {self.entry_type.__name__} or a class; "
                        f"got {type(obj).__name__}")

    # ------------------------------------------------------------------ asking
    def __getitem__(self, name: str) -> B:
        key = str(name).lower()
        backend = self._registered.get(key) or self._entry_points().get(key)
        if backend is None:
            raise KeyError(name)
        return backend

    def __iter__(self) -> Iterator[str]:
        yield from list(self._registered)
        yield from [name for name in self._entry_points() if name not in self._registered]

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def names(self, where: Callable[[B], bool] | None = None) -> tuple[str, ...]:
        """The names, in order; only those whose back end satisfies ``where`` when given."""
        return tuple(name for name in self if where is None or where(self[name]))

    def unknown(self, name, names=None) -> str:
        """The one-line message for a name that is not registered."""
        return f"unknown {self.kind} {name!r}; choose one of {', '.join(self.names() if names is None else names)}"
