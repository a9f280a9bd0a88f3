"""Extensions by name: one registry per kind (calibration methods here; controllers and cameras in
``handeye.drivers``), filled by the package in code and by other installed packages through entry
points, the way python-can finds its interfaces.

Each entry is a frozen dataclass with a ``name``. The package registers its own in code; another
installed package adds one through an entry point of the registry's group, without any change to
handeye::

    # pyproject.toml of the other package
    [project.entry-points."handeye.methods"]
    kabsch = "handeye_kabsch:METHOD"      # a handeye.calibration.methods.Method

Entry points are read from the installed packages' metadata at the first question asked of a registry
(and again after :meth:`Registry.refresh`): listing names imports no plug-in. A plug-in is imported
only when its own entry is asked for (``registry[name]``, or :meth:`Registry.names` with a condition
on the entries), under a time bound (:mod:`handeye.base.time_bound`): one that fails, or whose
import hangs, is left out with a warning saying why (:meth:`Registry.unusable`), and the command goes
on. Everything that lists entries asks the registry.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata
import logging
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import replace
from typing import Any, Generic, TypeVar, cast

__all__ = ["Choices", "Registry", "load_target", "quiet_loads", "unusable_clause"]

log = logging.getLogger(__name__)

E = TypeVar("E")

#: While above zero, a plug-in that does not load is not logged (its reason is kept: :meth:`Registry.unusable`):
#: a message or a listing that says why itself (:func:`quiet_loads`).
_QUIET = [0]


@contextlib.contextmanager
def quiet_loads() -> Iterator[None]:
    """Within it, plug-ins that fail to load are not logged as warnings (the message being written names
    them and why itself)."""
    _QUIET[0] += 1
    try:
        yield
    finally:
        _QUIET[0] -= 1


#: ``{module: thread}`` of the plug-in imports that did not finish within the time bound (shared by the
#: registries: two entry points of one module wait on the same import).
_HANGING: dict[str, threading.Thread] = {}


def load_target(target: object) -> Any:
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
        self._loaded: dict[str, E] = {}  # entry points loaded so far, by name
        self._unusable: dict[str, str] = {}  # entry points that could not be loaded: name -> why
        self._ignored: list[str] = []  # entry points left out because their name is taken: why, one line each

    # ------------------------------------------------------------------ filling
    def register(self, entry: E) -> E:
        """Add ``entry`` (or replace the one of the same name); returns it."""
        if not isinstance(entry, self.entry_type):
            raise TypeError(f"a {self.kind} is registered as a {self.entry_type.__name__}; got {type(entry).__name__}")
        entry = replace(cast(Any, entry), name=cast(Any, entry).name.lower())
        self._registered[cast(Any, entry).name] = entry
        return entry

    def unregister(self, name: str) -> None:
        """Remove an entry registered in code (entry points come back at the next refresh)."""
        self._registered.pop(name.lower(), None)

    def update(self, name: str, **changes: Any) -> E:
        """Change some fields of a registered entry (``mock=...`` from the mocks); returns it."""
        return self.register(replace(cast(Any, self[name]), **changes))

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

    def _entry_points(self) -> dict:
        """``{name: entry point}`` of this group, read from the installed packages' metadata only (no
        plug-in is imported here); names handeye (or an earlier entry point) has already are left out
        with a warning."""
        if self._discovered is None:
            found: dict = {}
            self._providers, self._loaded, self._unusable, self._ignored = {}, {}, {}, []
            for point in importlib.metadata.entry_points(group=self.group):
                name = point.name.lower()
                if name in self._registered or name in found:
                    self._ignored.append(f"the {self.kind} {name!r} of the installed package {_package(point)} "
                                         f"(entry point {point.value}) is ignored: {self._origin(name)}; rename it "
                                         "in that package")
                    log.warning("warning: %s", self._ignored[-1])
                    continue
                found[name] = point
                self._providers[name] = f"the installed package {_package(point)} (entry point {point.value})"
            self._discovered = found
        return self._discovered

    def _load(self, name: str) -> E | None:
        """The entry of the entry point ``name``, its plug-in imported now under the time bound
        (:func:`~handeye.base.time_bound.call_within`); None when it cannot be had, the reason kept
        (:meth:`unusable`) and logged once. A module whose import is still hanging is not waited for again."""
        from .time_bound import OutOfTime, call_within

        point = self._entry_points().get(name)
        if point is None or name in self._unusable:
            return None
        if name not in self._loaded:
            module = point.value.partition(":")[0].strip()
            if module in _HANGING and _HANGING[module].is_alive():
                self._unusable[name] = f"did not load: its module {module} is still loading from an earlier try (it hangs)"
            else:
                try:
                    entry = self._describe(name, call_within(point.load, f"load-{self.group}-{name}"))
                    self._loaded[name] = entry if cast(Any, entry).name == name else replace(cast(Any, entry), name=name)
                except OutOfTime as exc:
                    _HANGING[module] = exc.thread
                    self._unusable[name] = f"did not load within {exc.seconds:g} s"
                except Exception as exc:  # a broken plug-in must not break the package
                    self._unusable[name] = f"{type(exc).__name__}: {exc}"
            if name in self._unusable:
                if not _QUIET[0]:
                    log.warning("%s %r from entry point %s is unusable: %s", self.kind, name, point.value,
                                self._unusable[name])
                return None
        return self._loaded[name]

    def unusable(self) -> dict[str, str]:
        """``{name: why}`` of the entry points tried so far that gave no entry (a failed or hanging import,
        an object of the wrong type)."""
        self._entry_points()
        return dict(self._unusable)

    def ignored(self) -> tuple[str, ...]:
        """One line for each entry point left out because handeye (or an earlier entry point) has its name."""
        self._entry_points()
        return tuple(self._ignored)

    def plugin_names(self) -> tuple[str, ...]:
        """The names of this group's entry points (read from metadata, none loaded), usable or not."""
        return tuple(self._entry_points())

    def is_plugin(self, name: str) -> bool:
        """Whether ``name`` comes from an entry point (not registered in code)."""
        key = str(name).lower()
        return key not in self._registered and key in self._entry_points()

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
            return replace(cast(Any, obj), name=cast(Any, obj).name.lower())
        raise TypeError(f"an entry point of {self.group} must name a {self.entry_type.__name__}; got {type(obj).__name__}")

    # ------------------------------------------------------------------ asking
    def __getitem__(self, name: str) -> E:
        key = str(name).lower()
        entry = self._registered.get(key) or self._load(key)
        if entry is None:
            raise KeyError(name)
        return entry

    def __iter__(self) -> Iterator[str]:
        """The names in code, then those of the entry points (from metadata: nothing is loaded), less those
        that were tried and could not be loaded."""
        yield from list(self._registered)
        yield from [name for name in self._entry_points() if name not in self._registered and name not in self._unusable]

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def names(self, where: Callable[[E], bool] | None = None) -> tuple[str, ...]:
        """The names, in order; only those whose entry satisfies ``where`` when given (which loads each
        plug-in, under the time bound, and leaves out those that cannot be loaded)."""
        if where is None:
            return tuple(self)
        return tuple(name for name in self if (entry := self.get(name)) is not None and where(entry))

    def loaded_names(self) -> tuple[str, ...]:
        """The names registered in code, then the plug-ins loaded so far (those a command asked for):
        what can be described without importing another plug-in."""
        self._entry_points()
        return tuple(self._registered) + tuple(name for name in self._loaded if name not in self._registered)

    def choices(self, where: Callable[[E], bool] | None = None, extra: tuple[str, ...] = (),
                lacking: str = "") -> "Choices":
        """The names a value may take (those whose entry satisfies ``where``, then ``extra``), for a check of
        one value: asking whether a name is one loads that plug-in only (:class:`Choices`); ``lacking`` says
        what an entry ``where`` refuses is (``has no mock``)."""
        return Choices(self, where, extra, lacking)

    def names_in_code(self) -> tuple[str, ...]:
        """The names registered in code (the package's own, then :meth:`register`'s), entry points left out:
        what the package's shipped documents describe, whatever plug-ins this machine has installed."""
        return tuple(self._registered)

    def unknown(self, name: object, names: Iterable[str] | None = None) -> str:
        """The one-line message for a name that is not registered (or whose plug-in did not load: why)."""
        text = f"unknown {self.kind} {name!r}; choose one of {', '.join(self.names() if names is None else names)}"
        why = self.why_unusable(name)
        return f"{text} ({why})" if why else text

    def why_unusable(self, name: object) -> str | None:
        """Why the entry point ``name`` gives no entry (``the camera back end 'stuck' of the installed package
        ... did not load within 30 s: fix or uninstall that package``); None when it is not one that failed."""
        key = str(name).lower()
        self._entry_points()
        if key not in self._unusable:
            return None
        return (f"the {self.kind} {key!r} of {self._providers.get(key, 'an installed package')} {unusable_clause(self._unusable[key])}: "
                "fix or uninstall that package")


class Choices:
    """The names of a :class:`Registry` a value may take, checked one value at a time: ``name in choices``
    loads that name's plug-in only (a plug-in a command does not use is never imported); listing them
    (iterating, for a message) loads each, under the time bound.

    Parameters
    ----------
    registry : Registry
    where : callable, optional
        ``where(entry) -> bool``: the entries that may be chosen (``not backend.simulated``).
    extra : tuple of str
        More names, not in the registry (``mock``).
    """

    def __init__(self, registry: Registry, where: Callable | None = None, extra: tuple[str, ...] = (),
                 lacking: str = ""):
        self.registry, self.where, self.extra, self.lacking = registry, where, tuple(extra), lacking

    def refusal(self, value: object) -> str | None:
        """Why ``value``, a name of the registry, is not a choice (its plug-in did not load, or it lacks
        what ``where`` asks: ``lacking``, a clause: ``has no mock``); None for a name the registry does not have."""
        why = self.registry.why_unusable(value)
        if why is not None or not isinstance(value, str):
            return why
        entry = self.registry.get(value.lower())
        if entry is None or self.where is None or self.where(entry):
            return None
        owner = self.registry.provider(value) or "handeye"
        return f"the {self.registry.kind} {value.lower()!r} of {owner} {self.lacking or 'cannot serve here'}"

    def __contains__(self, value) -> bool:
        if value in self.extra:
            return True
        if not isinstance(value, str) or value != value.lower():
            return False
        entry = self.registry.get(value)
        return entry is not None and (self.where is None or self.where(entry))

    def left_out(self) -> dict[str, str]:
        """``{name: why}`` of the installed plug-ins that are not choices here (each is loaded, under the time
        bound, to know): what a command's help says it left out."""
        out = {}
        with quiet_loads():
            for name in self.registry.plugin_names():
                if name not in self:
                    why = self.refusal(name)
                    if why is not None:
                        out[name] = why
        return out

    def listed(self) -> str:
        """The choices, comma-separated, for a message (plug-ins that do not load left out without a warning:
        :meth:`left_out` says why)."""
        with quiet_loads():
            return ", ".join(self)

    def __iter__(self) -> Iterator[str]:
        yield from self.registry.names(self.where)
        yield from self.extra

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def __getitem__(self, index):
        return tuple(self)[index]

    def __bool__(self) -> bool:
        return True


def unusable_clause(reason: str) -> str:
    """A load failure as a clause after the plug-in's name (``did not load within 30 s``, ``failed to load
    (ImportError: ...)``)."""
    return reason if reason.startswith("did not load") else f"failed to load ({reason})"


def _package(point) -> str:
    """The distribution an entry point belongs to (its module's top-level name when that is unknown)."""
    dist = getattr(point, "dist", None)
    name = getattr(dist, "name", None) if dist is not None else None
    return name or point.value.partition(":")[0].split(".")[0]
