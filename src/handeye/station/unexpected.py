"""One line for an exception no part of handeye expected: whose code raised it and what to do.

The commands report what goes wrong as :class:`~handeye.base.errors.HandEyeError`, one line
each. What escapes them is a fault in code: an installed plug-in's (a controller, camera or method
registered through a ``handeye.*`` entry point) or handeye's own. :func:`unexpected_error_line` names
which, from the traceback's frames (the innermost frame of a plug-in's modules blames that plug-in's
package), saves the traceback to a file for the report, and says so in one line; the session and
every file written so far are kept, since each is written whole. ``HANDEYE_DEBUG=1`` lets the
traceback through instead (``station.cli``).
"""

from __future__ import annotations

import os
import tempfile
import time
import traceback
from pathlib import Path

from ..base import HandEyeError, exception_line
from ..base import write_text_atomic

__all__ = ["DEBUG_VARIABLE", "plugin_packages", "unexpected_error_line"]

#: Set (to anything but empty or 0) to see the traceback of an unexpected error instead of one line.
DEBUG_VARIABLE = "HANDEYE_DEBUG"


def plugin_packages() -> dict[str, str]:
    """``{top-level module: installed package}`` of every plug-in of every handeye registry (methods,
    controllers, cameras), read from the entry points whether or not they load."""
    from ..calibration import METHODS
    from ..drivers import CAMERAS
    from ..drivers import CONTROLLERS

    owners: dict[str, str] = {}
    for registry in (METHODS, CONTROLLERS, CAMERAS):
        owners.update(registry.plugin_modules())
    owners.pop("handeye", None)  # an entry point into handeye itself is handeye's code
    return owners


def unexpected_error_line(exc: BaseException, command: str) -> str:
    """What ``handeye COMMAND: error: ...`` says of ``exc``: the exception, where, whose fault, the
    saved traceback and what to do next."""
    frames = list(traceback.walk_tb(exc.__traceback__))
    owners = _owners()
    blamed = None
    for frame, line in frames:
        top = str(frame.f_globals.get("__name__", "")).split(".")[0]
        if top in owners:
            blamed = (owners[top], frame.f_code.co_filename, line)
    where = blamed[1:] if blamed else ((frames[-1][0].f_code.co_filename, frames[-1][1]) if frames else None)
    place = f" at {_short(where[0])}:{where[1]}" if where else ""
    saved = _save_traceback(exc, command)
    kept = (f"its traceback is in {saved}" if saved
            else f"its traceback could not be saved (run again with {DEBUG_VARIABLE}=1 to see it)")
    if blamed:
        return (f"the installed plug-in package {blamed[0]} failed ({exception_line(exc)}{place}); {kept}: report it to "
                f"its authors, or uninstall it (pip uninstall {blamed[0]}) to work without it; what was written so far "
                f"is kept")
    return (f"unexpected {exception_line(exc)}{place}: a fault in handeye, not in your data or set-up; {kept}: report "
            f"it with the traceback; what was written so far is kept")


def _owners() -> dict[str, str]:
    try:
        return plugin_packages()
    except Exception:  # noqa: BLE001 - naming the culprit must never hide the error itself
        return {}


def _short(filename: str) -> str:
    """The file name relative to the working folder when it lies below it, else as it is."""
    try:
        return str(Path(filename).resolve().relative_to(Path.cwd()))
    except (ValueError, OSError):
        return filename


def _save_traceback(exc: BaseException, command: str) -> str | None:
    """Writes the whole traceback to a file in the temporary folder (as every file is written:
    ``base.files.write_text_atomic``); its path, or None when it cannot be written."""
    text = f"handeye {command}\n" + "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    path = Path(tempfile.gettempdir()) / f"handeye-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.traceback.txt"
    try:
        return str(write_text_atomic(path, text))
    except HandEyeError:
        return None
