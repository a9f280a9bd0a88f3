"""What running code holds: references to data, routine frames, and the signals of RAPID's control flow.

A :class:`Ref` names a place that holds a value (a variable's box, an array element, a record
component) with its declared type; ``INOUT``/``VAR``/``PERS`` parameters receive one. A
:class:`Frame` is one call of a routine: its local slots, its error-handler state. The control
signals (``RETURN``, ``RETRY``, ``TRYNEXT``, ``EXIT``, a task asked to stop) are BaseExceptions, so
that no error handling in a binding catches them.
"""

from __future__ import annotations

from typing import Any

from .errors import RapidRuntimeError

__all__ = ["Ref", "Frame", "ABSENT", "ReturnSignal", "RetrySignal", "TryNextSignal", "ExitSignal", "StopSignal",
           "TaskStopped", "RETRY", "TRYNEXT", "MAX_RETRIES"]

#: Consecutive RETRY of one statement before the error goes to the caller (RAPID's "No Of Retry").
MAX_RETRIES = 4
RETRY, TRYNEXT = "retry", "trynext"


class _Absent:
    """An optional parameter that was not passed."""

    def __repr__(self) -> str:
        return "ABSENT"


ABSENT = _Absent()


class Ref:
    """A place holding a value: ``holder[key]`` (a box list, an array, a record's component dict)."""

    __slots__ = ("holder", "key", "type", "dims", "name")

    def __init__(self, holder, key, type_, dims=(), name: str = ""):
        self.holder, self.key, self.type, self.dims, self.name = holder, key, type_, dims, name

    def get(self):
        return self.holder[self.key]

    def set(self, value: Any) -> None:
        self.holder[self.key] = value


class ReturnSignal(BaseException):
    def __init__(self, value: Any = None):
        self.value = value


class RetrySignal(BaseException):
    pass


class TryNextSignal(BaseException):
    pass


class ExitSignal(BaseException):
    """EXIT: the program ends (``args[0]``: where, ``Module.mod:12``, when known)."""


class StopSignal(BaseException):
    """The Stop instruction: program execution stops (the mock does not restart it)."""


class TaskStopped(BaseException):
    """The task was asked to stop (the mock shuts down or loads another program)."""


class Frame:
    """One call of a routine.

    Attributes
    ----------
    task : Task
    routine : CompiledRoutine
    slots : list
        Parameters and local data (by-reference parameters hold a :class:`Ref`).
    in_handler : bool
        The error handler runs.
    """

    __slots__ = ("task", "routine", "slots", "in_handler", "retries", "error")

    def __init__(self, task: Any, routine, size: int):  # a runtime.Task, or the program's stand-in for constants
        self.task, self.routine, self.slots = task, routine, [None] * size
        self.in_handler, self.retries, self.error = False, 0, None

    def handle(self, err: RapidRuntimeError) -> str:
        """Run this routine's error handler for ``err``: RETRY or TRYNEXT, or raise (RETURN, RAISE)."""
        routine = self.routine
        numbers = routine.error_numbers
        if numbers is not None and err.errno not in numbers:
            err.handled_in = self
            raise err
        self.task.errno = err.errno
        self.in_handler, self.error = True, err
        try:
            routine.handler(self)
        except RetrySignal:
            self.retries += 1
            if self.retries > MAX_RETRIES:
                err.handled_in = self
                raise err from None
            return RETRY
        except TryNextSignal:
            return TRYNEXT
        except RapidRuntimeError as inner:  # an error in the handler (or its RAISE) goes to the caller
            inner.handled_in = self
            raise
        finally:
            self.in_handler = False
        # The end of the handler without RETRY, TRYNEXT, RETURN or RAISE: the error goes on to the
        # caller, as RAISE would (a guess of RAPID's rule; the shipped modules always end theirs).
        err.handled_in = self
        raise err
