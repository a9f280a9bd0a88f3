"""The camera back ends: each described once, in :data:`CAMERAS`.

A back end is a :class:`CameraBackend`: its name (the ``camera.backend`` word), its class (imported
when it is opened), how its options are built from the station config's ``camera`` section, whether
it is simulated, and one line of help. The package registers ``xb3`` here; ``handeye.mocks``
registers its simulated XB3 as ``mock`` (the drivers never name the mocks); another package adds one
with :func:`register_backend` or an entry point in the ``handeye.cameras`` group.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..registry import Backend, Registry

__all__ = ["CameraBackend", "CAMERAS", "register_backend", "no_options"]


def no_options(section) -> dict:
    """A back end that takes nothing from the station config (the constructor's defaults)."""
    return {}


@dataclass(frozen=True)
class CameraBackend(Backend):
    """A camera back end (see the module docstring).

    Attributes
    ----------
    options : callable
        ``options(section) -> dict``: the class's keyword options from the station config's
        ``camera`` section (default: none).
    simulated : bool
        A simulated camera (the mock): not a choice for a real station's ``camera.backend``.
    """

    options: Callable = no_options
    simulated: bool = False


#: Every camera back end by name: the package's, the mock once ``handeye.mocks`` is imported, plug-ins.
CAMERAS: Registry[CameraBackend] = Registry("camera back end", "handeye.cameras", CameraBackend)

CAMERAS.register(CameraBackend("xb3", f"{__package__}.xb3:XB3Camera",
                               help="Point Grey Bumblebee XB3 on IEEE-1394 (libdc1394)"))


def register_backend(backend, target=None, **fields) -> CameraBackend:
    """Add a camera back end (or replace the one of the same name); returns it.

    ``backend`` is a :class:`CameraBackend`, or a name with ``target`` (a Camera sub-class or a
    ``"module:Class"`` string) and the other fields as keywords.
    """
    if not isinstance(backend, CameraBackend):
        backend = CameraBackend(str(backend), target, **fields)
    return CAMERAS.register(backend)
