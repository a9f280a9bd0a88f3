"""Extensions by name: one registry per kind (calibration methods here; controllers and cameras in
``handeye.drivers``), filled by the package in code and by other installed packages through entry
points, the way python-can finds its interfaces.

Each entry is a frozen dataclass with a ``name``. The package registers its own in code; another
installed package adds one through an entry point of the registry's group, without any change to
handeye::

    # pyproject.toml of the other package
    [project.entry-points."handeye.methods"]
    kabsch = "handeye_kabsch:METHOD"      # a handeye.calibration.methods.Method

Entry points are read at the first question asked of a registry (and again after
:meth:`Registry.refresh`), so importing handeye never imports a plug-in; a plug-in that cannot be
loaded is skipped with a warning. Everything that lists entries asks the registry.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import logging
from collections.abc import Callable, Iterator, Mapping
from dataclasses import replace
from typing import Generic, TypeVar

__all__ = ["Registry", "load_target"]

log = logging.getLogger(__name__)

E = TypeVar("E")


def load_target(target):
    """The object a ``"module:attribute"`` string names (imported now), or ``target`` itself."""
    if not isinstance(target, str):
        return target
    module_name, _, attribute = target.partition(":")
    obj = importlib.import_module(module_name)
    for part in attribute.split(".") if attribute else ():
        obj = getattr(obj, part)
    return obj


class Registry(Mapping, Generic[E]):
    """Entries of one kind by name, in registration order (the package's first, then plug-ins).

    ``registry[name] = entry`` registers (the entry's own name must be ``name``) and ``del
    registry[name]`` unregisters, so a test can swap an entry with ``monkeypatch.setitem``.

    Parameters
    ----------
    kind : str
        What they are, for messages (``method``, ``controller protocol``).
    group : str
        The entry-point group other packages register theirs in (``handeye.methods``).
    entry_type : type
        The dataclass of this kind's entries; an entry point must name one (subclasses may accept
        more, see :meth:`_describe`).
    """

    def __init__(self, kind: str, group: str, entry_type: type[E]):
        self.kind, self.group, self.entry_type = kind, group, entry_type
        self._registered: dict[str, E] = {}
        self._discovered: dict[str, E] | None = None  # None: entry points not read yet
        self._providers: dict[str, str] = {}  # name -> the installed package behind an entry point's entry

    # ------------------------------------------------------------------ filling
    def register(self, entry: E) -> E:
        """Add ``entry`` (or replace the one of the same name); returns it."""
        if not isinstance(entry, self.entry_type):
            raise TypeError(f"a {self.kind} is registered as a {self.entry_type.__name__}; got {type(entry).__name__}")
        entry = replace(entry, name=entry.name.lower())
        self._registered[entry.name] = entry
        return entry

    def unregister(self, name: str) -> None:
        """Remove an entry registered in code (entry points come back at the next refresh)."""
        self._registered.pop(name.lower(), None)

    def update(self, name: str, **changes) -> E:
        """Change some fields of a registered entry (``mock=...`` from the mocks); returns it."""
        return self.register(replace(self[name], **changes))

    def refresh(self) -> None:
        """Forget the entry points read so far: the next question reads them again (new installs)."""
        self._discovered = None
        importlib.invalidate_caches()

    def __setitem__(self, name: str, entry: E) -> None:
        if getattr(entry, "name", "").lower() != str(name).lower():
            raise ValueError(f"a {self.kind} named {getattr(entry, 'name', None)!r} cannot be registered as {name!r}")
        self.register(entry)

    def __delitem__(self, name: str) -> None:
        if str(name).lower() not in self._registered:
            raise KeyError(name)
        self.unregister(name)

    def _entry_points(self) -> dict[str, E]:
        if self._discovered is None:
            found: dict[str, E] = {}
            self._providers = {}
            for point in importlib.metadata.entry_points(group=self.group):
                try:
                    entry = self._describe(point.name, point.load())
                except Exception as exc:  # a broken plug-in must not break the package
                    log.warning("%s %r from entry point %s is unusable: %s", self.kind, point.name, point.value, exc)
                    continue
                if entry.name in self._registered or entry.name in found:
                    log.warning("warning: the %s %r of the installed package %s (entry point %s) is ignored: %s; "
                                "rename it in that package", self.kind, entry.name, _package(point), point.value,
                                self._origin(entry.name))
                    continue
                found[entry.name] = entry
                self._providers[entry.name] = f"the installed package {_package(point)} (entry point {point.value})"
            self._discovered = found
        return self._discovered

    def _origin(self, name: str) -> str:
        """Who has ``name`` already, for a message: handeye (or code), or another package."""
        if name in self._registered:
            return f"handeye already has a {self.kind} of that name"
        return f"{self._providers.get(name, 'another entry point')} registers one of that name first"

    def plugin_modules(self) -> dict[str, str]:
        """``{top-level module: installed package}`` of every entry point of this registry's group (usable
        or not): whose code a traceback's frames are (``station.unexpected``)."""
        return {point.value.partition(":")[0].split(".")[0]: _package(point)
                for point in importlib.metadata.entry_points(group=self.group)}

    def provider(self, name: str) -> str | None:
        """The installed package an entry point's entry comes from, for messages (``the installed package
        handeye-kabsch (entry point handeye_kabsch:METHOD)``); None for an entry registered in code (the
        package's own)."""
        key = str(name).lower()
        if key in self._registered:
            return None
        self._entry_points()
        return self._providers.get(key)

    def _describe(self, name: str, obj) -> E:
        """The entry an entry point's object stands for (here: the object itself, of ``entry_type``)."""
        if isinstance(obj, self.entry_type):
            return replace(obj, name=obj.name.lower())
        raise TypeError(f"an entry point of {self.group} must name a {self.entry_type.__name__}; got {type(obj).__name__}")

    # ------------------------------------------------------------------ asking
    def __getitem__(self, name: str) -> E:
        key = str(name).lower()
        entry = self._registered.get(key) or self._entry_points().get(key)
        if entry is None:
            raise KeyError(name)
        return entry

    def __iter__(self) -> Iterator[str]:
        yield from list(self._registered)
        yield from [name for name in self._entry_points() if name not in self._registered]

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def names(self, where: Callable[[E], bool] | None = None) -> tuple[str, ...]:
        """The names, in order; only those whose entry satisfies ``where`` when given."""
        return tuple(name for name in self if where is None or where(self[name]))

    def names_in_code(self) -> tuple[str, ...]:
        """The names registered in code (the package's own, then :meth:`register`'s), entry points left out:
        what the package's shipped documents describe, whatever plug-ins this machine has installed."""
        return tuple(self._registered)

    def unknown(self, name, names=None) -> str:
        """The one-line message for a name that is not registered."""
        return f"unknown {self.kind} {name!r}; choose one of {', '.join(self.names() if names is None else names)}"


def _package(point) -> str:
    """The distribution an entry point belongs to (its module's top-level name when that is unknown)."""
    dist = getattr(point, "dist", None)
    name = getattr(dist, "name", None) if dist is not None else None
    return name or point.value.partition(":")[0].split(".")[0]
