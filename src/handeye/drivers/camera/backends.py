"""The camera back ends: each described once, in :data:`CAMERAS`.

A back end is a :class:`CameraBackend`: its name (the ``camera.backend`` word), its class (imported
when it is opened), its own settings (:class:`~handeye.drivers.registry.Setting`: key, type, default,
help; each a ``camera.<key>`` of the station config, checked and documented from it, and a keyword of
the class), how further options are built from the config's ``camera`` section, whether it is
simulated, and one line of help. The package registers ``xb3`` here; ``handeye.mocks``
registers its simulated XB3 as ``mock`` (the drivers never name the mocks); another package adds one
with :func:`register_backend` or an entry point in the ``handeye.cameras`` group.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ..registry import Backend, Registry, Setting, declared_settings, keyword_options
from .errors import CameraError

__all__ = ["CameraBackend", "CAMERAS", "camera_settings", "register_backend", "no_options"]


def no_options(section: object) -> dict:
    """A back end that takes nothing from the station config (the constructor's defaults)."""
    return {}


@dataclass(frozen=True)
class CameraBackend(Backend):
    """A camera back end (see the module docstring).

    Attributes
    ----------
    settings : tuple of Setting
        Its own settings, described once: each is the station config's ``camera.<key>`` (checked
        and documented from it) and a keyword of the class (:meth:`camera_options`).
    options : callable
        ``options(section) -> dict``: further keyword options of the class from the station config's
        ``camera`` section (default: none).
    simulated : bool
        A simulated camera (the mock): not a choice for a real station's ``camera.backend``.
    """

    settings: tuple = ()
    options: Callable = no_options
    simulated: bool = False

    def camera_options(self, section: object) -> dict:
        """The class's keyword options for the station config's ``camera`` section: its settings that
        the section sets, then what :attr:`options` adds.

        Raises
        ------
        CameraError
            A required setting is not set.
        """
        declared = keyword_options(self.settings, lambda key: getattr(section, key, None), lambda setting: CameraError(
            f"the {self.name} camera needs {setting.required} (camera.{setting.key} in the station config)"))
        return {**declared, **self.options(section)}


#: Every camera back end by name: the package's, the mock once ``handeye.mocks`` is imported, plug-ins.
CAMERAS: Registry[CameraBackend] = Registry("camera back end", "handeye.cameras", CameraBackend)


def _guid(value, name: str) -> str:
    """A FireWire GUID as 16 hex digits (``00b09d0100aabbcc``; given with a ``0x`` or fewer digits too)."""
    digits = str(value).strip().lower().removeprefix("0x")
    if not 1 <= len(digits) <= 16 or any(c not in "0123456789abcdef" for c in digits):
        raise ValueError(f"{name} must be the camera's FireWire GUID, up to 16 hex digits (as the camera's error "
                         f"lists them: '00b09d0100aabbcc', quoted); got {value!r}")
    return f"{int(digits, 16):016x}"


CAMERAS.register(CameraBackend(
    "xb3", f"{__package__}.xb3:XB3Camera", help="Point Grey Bumblebee XB3 on IEEE-1394 (libdc1394)",
    settings=(Setting("guid", str, None, "the XB3 to open by its FireWire GUID (16 hex digits, quoted); null: the "
                      "only XB3 on the bus (several are refused, naming their GUIDs)", check=_guid, metavar="GUID"),)))


def camera_settings(names: Iterable[str] | None = None) -> dict:
    """The camera back ends' settings by key, with the back ends that declare it (registry order): of
    ``names`` (default: every back end loaded so far, so no other plug-in is imported): the keys of the
    station config's ``camera`` section beyond its own."""
    return declared_settings(CAMERAS, "settings", names)


def register_backend(backend: CameraBackend | str, target: object = None, **fields: Any) -> CameraBackend:
    """Add a camera back end (or replace the one of the same name); returns it.

    ``backend`` is a :class:`CameraBackend`, or a name with ``target`` (a Camera sub-class or a
    ``"module:Class"`` string) and the other fields as keywords.
    """
    if not isinstance(backend, CameraBackend):
        backend = CameraBackend(str(backend), target, **fields)
    return CAMERAS.register(backend)
