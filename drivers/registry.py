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
:class:`handeye.calibration.registry.Registry`, shared with the calibration methods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

from ..calibration.registry import Registry as _Registry
from ..calibration.registry import load_target

__all__ = ["Backend", "Registry", "load_target"]


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


class Registry(_Registry[B]):
    """Back ends of one kind by name, in registration order (the package's first, then plug-ins):
    :class:`handeye.calibration.registry.Registry` whose entry points may also name a class.

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
