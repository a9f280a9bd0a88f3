"""The FlexPendant as a program sees it: lines written, a prompt waiting for the operator's key, Start.

:class:`FlexPendant` is a binding (``Bindings.flexpendant``): ``TPWrite`` lines land in it, ``TPReadFK``
and ``UIMessageBox`` wait in :meth:`FlexPendant.ask` until the operator answers (:meth:`answer`), and
``Stop \\NoRegain`` waits in :meth:`stop_here` until the operator presses Start (:meth:`start`): the
program pointer stays, execution continues after the ``Stop``. Whoever plays the operator (a test, the
mock controller's pendant port ``src/handeye/mocks/controller/pendant.py``) calls the operator's side from another
thread. Without a FlexPendant binding, ``TPReadFK`` and ``UIMessageBox`` stop the program with an error
(nobody could answer) and ``Stop`` ends it as before.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import threading
from collections import deque
from dataclasses import dataclass

if TYPE_CHECKING:
    from .runtime import Task

__all__ = ["FlexPendant", "Prompt"]


@dataclass(frozen=True)
class Prompt:
    """A question on the pendant: its text and the answers offered (key number -> label)."""

    text: str
    keys: dict


class FlexPendant:
    """The operator's pendant (see the module docstring).

    Attributes
    ----------
    lines : collections.deque
        The last lines written (``TPWrite``, the prompts' texts), newest last.
    """

    def __init__(self, history: int = 50):
        self.lines: deque = deque(maxlen=history)
        self._cond = threading.Condition()
        self._prompt: Prompt | None = None
        self._answer: int | None = None
        self._resumed: threading.Event | None = None

    # ------------------------------------------------------------------ the program's side
    def write(self, text: str) -> None:
        with self._cond:
            self.lines.append(str(text))
            self._cond.notify_all()

    def ask(self, task: Task, text: str, keys: dict, timeout: float | None = None) -> int | None:
        """Show ``text`` with the answers ``keys`` and wait (serving the task) for the operator's key (None
        after ``timeout`` s)."""
        end = None if timeout is None else task.clock() + timeout
        with self._cond:
            self._prompt, self._answer = Prompt(str(text), dict(keys)), None
            self.lines.append(str(text))
            self._cond.notify_all()
        try:
            while True:
                with self._cond:
                    if self._answer is not None:
                        return self._answer
                if end is not None and task.clock() >= end:
                    return None
                task.idle(0.02)
        finally:
            with self._cond:
                self._prompt = None
                self._cond.notify_all()

    def stop_here(self, task: Task) -> None:
        """``Stop \\NoRegain``: wait until the operator presses Start."""
        resumed = threading.Event()
        with self._cond:
            self._resumed = resumed
            self._cond.notify_all()
        try:
            task.halt(resumed)
        finally:
            with self._cond:
                self._resumed = None
                self._cond.notify_all()

    # ------------------------------------------------------------------ the operator's side
    @property
    def prompt(self) -> Prompt | None:
        """The question waiting for a key (None: none)."""
        return self._prompt

    @property
    def stopped(self) -> bool:
        """Execution stopped by ``Stop \\NoRegain``, waiting for Start."""
        return self._resumed is not None

    def answer(self, key: int) -> str | None:
        """Press key ``key`` of the waiting prompt; why not (no prompt, a key it does not offer), or None."""
        with self._cond:
            if self._prompt is None:
                return "no prompt on the pendant"
            if key not in self._prompt.keys:
                offered = ", ".join(f"{k} {label}" for k, label in sorted(self._prompt.keys.items()))
                return f"key {key} is not offered (offered: {offered})"
            self._answer = int(key)
            self._cond.notify_all()
        return None

    def start(self) -> str | None:
        """Press Start: execution continues after the ``Stop``; why not (not stopped), or None."""
        with self._cond:
            if self._resumed is None:
                return "the program is not stopped (Start continues a Stop \\NoRegain)"
            self._resumed.set()
            self._resumed = None
            self._cond.notify_all()
        return None

    def wait(self, condition, timeout: float) -> bool:
        """Wait until ``condition(self)`` holds (True) or ``timeout`` s passed (False)."""
        with self._cond:
            return self._cond.wait_for(lambda: condition(self), timeout)

    @property
    def last_line(self) -> str:
        return self.lines[-1] if self.lines else ""
