"""The package's own exceptions: each carries a one-line message meant for the operator."""

from __future__ import annotations

import reprlib

__all__ = ["HandEyeError", "UsageError", "SessionError", "SessionUsageError", "CalibrationError", "ConfigError", "OutputError",
           "brief", "exception_line", "with_backend"]


class _Brief(reprlib.Repr):
    def repr_int(self, x, level):
        if x.bit_length() > 4000:  # repr() itself refuses integers of more than 4300 digits
            return f"<an integer of {x.bit_length() * 0.30103:.0f} digits>"
        return super().repr_int(x, level)


_BRIEF = _Brief()
_BRIEF.maxlevel, _BRIEF.maxlist, _BRIEF.maxtuple, _BRIEF.maxdict, _BRIEF.maxset = 3, 6, 6, 4, 6
_BRIEF.maxstring = _BRIEF.maxother = 60
_BRIEF.maxlong = 40


def brief(value: object) -> str:
    """A short ``repr`` of any value read from a file, for a one-line message: bounded in length and
    in the work it takes (a YAML alias bomb, a list of lists of the same list ..., is not expanded;
    an integer of thousands of digits is described, not printed)."""
    return _BRIEF.repr(value)


def exception_line(exc: BaseException) -> str:
    """``Type: the first line of its message`` (at most 200 characters), for a one-line message about an
    exception that is not the package's own (a plug-in's, a library's)."""
    text = (str(exc).splitlines() or [""])[0].strip()
    text = text if len(text) <= 200 else text[:197] + "..."
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class HandEyeError(Exception):
    """Base of every error the ``handeye`` command reports as one line (no traceback)."""


def with_backend(message: str, backend: str | None) -> str:
    """``message`` prefixed with the back end's name (``socket: ...``), unless it already starts with it."""
    message = str(message)
    if not backend or message.startswith(f"{backend}:"):
        return message
    return f"{backend}: {message}"


class ConfigError(HandEyeError):
    """A configuration is missing, malformed or holds a bad value: the station file, the RAPID station,
    a register map, a back end's options. The one exception of every configuration problem.

    Parameters
    ----------
    message : str
        One line naming the key at fault and what it must be.
    backend : str, optional
        The back end whose configuration it is (``modbus`` for its register map); put in front of
        the message and kept as :attr:`backend`.
    """

    def __init__(self, message: str = "", *, backend: str | None = None):
        self.backend = backend
        super().__init__(with_backend(message, backend))


class UsageError(HandEyeError):
    """The command line asks for what cannot be done: a flag missing, flags that exclude each other, a
    flag value out of range, a flag that does not apply. ``handeye`` exits 2 on it, as on argparse's
    own usage errors (every other error exits 1). A library error that is a usage error when a flag
    carries the value derives from both (:class:`SessionUsageError`), so callers catching the
    library's kind still catch it."""


class SessionError(HandEyeError):
    """A session on disk is missing, malformed or holds values that cannot be used."""


class SessionUsageError(UsageError, SessionError):
    """An option of a session reader or importer given wrongly (``--square-mm`` without ``--board``, a
    flag that does not apply to the format)."""


class CalibrationError(HandEyeError):
    """The data cannot be solved: too few postures, degenerate motion, inconsistent points."""


class OutputError(HandEyeError):
    """A file or folder cannot be written: permission denied, a read-only file system, a file where a
    folder should be, a full disk. The message names the path, the reason and what to do."""
