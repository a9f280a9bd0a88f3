"""Another package's code run under a time bound: loading a plug-in, solving with a plug-in's method.

A plug-in may hang (an import that waits for hardware, a solver that never returns). Its code runs in
a daemon thread named after it (``handeye-plugin-...``); when the bound passes first, the caller gets
:class:`OutOfTime` and goes on, and the thread is abandoned (Python cannot stop a thread: it ends with
the process, or whenever the plug-in returns, its result then discarded).

The bound is ``HANDEYE_PLUGIN_TIME_S`` seconds (:data:`TIME_VARIABLE`), default
:data:`DEFAULT_TIME_S`.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from .errors import HandEyeError

__all__ = ["DEFAULT_TIME_S", "TIME_VARIABLE", "OutOfTime", "plugin_time_s", "call_within"]

#: The environment variable holding the bound, in seconds.
TIME_VARIABLE = "HANDEYE_PLUGIN_TIME_S"
#: The bound when the variable is unset or not a positive number, s.
DEFAULT_TIME_S = 30.0

T = TypeVar("T")


class OutOfTime(HandEyeError):
    """The plug-in's code did not return within ``seconds``; its thread is left running as a daemon."""

    def __init__(self, seconds: float, thread: threading.Thread):
        super().__init__(f"took longer than {seconds:g} s")
        self.seconds, self.thread = seconds, thread


def plugin_time_s() -> float:
    """The time bound of a plug-in's load or solve, s (:data:`TIME_VARIABLE`, else :data:`DEFAULT_TIME_S`)."""
    try:
        seconds = float(os.environ.get(TIME_VARIABLE, ""))
    except ValueError:
        return DEFAULT_TIME_S
    return seconds if 0 < seconds < float("inf") else DEFAULT_TIME_S


def call_within(function: Callable[[], T], name: str, seconds: float | None = None) -> T:
    """``function()``, run in a daemon thread ``handeye-plugin-<name>`` for at most ``seconds``.

    Parameters
    ----------
    function : callable
        Called without arguments.
    name : str
        What runs (``load handeye.cameras stuck``), for the thread's name.
    seconds : float, optional
        The bound; default :func:`plugin_time_s`.

    Returns
    -------
    object
        What ``function`` returned; what it raised is raised here.

    Raises
    ------
    OutOfTime
        ``function`` was still running after ``seconds``.
    """
    seconds = plugin_time_s() if seconds is None else seconds
    outcome: dict[str, Any] = {}

    def run():
        try:
            outcome["value"] = function()
        except BaseException as exc:  # noqa: BLE001 - handed to the caller below
            outcome["error"] = exc

    thread = threading.Thread(target=run, name=f"handeye-plugin-{name}", daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        raise OutOfTime(seconds, thread)
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]  # set: the thread ended without raising
