"""The package's own exceptions: each carries a one-line message meant for the operator."""

from __future__ import annotations

import reprlib

__all__ = ["HandEyeError", "SessionError", "CalibrationError", "OutputError", "brief"]

_BRIEF = reprlib.Repr()
_BRIEF.maxlevel, _BRIEF.maxlist, _BRIEF.maxtuple, _BRIEF.maxdict, _BRIEF.maxset = 3, 6, 6, 4, 6
_BRIEF.maxstring = _BRIEF.maxother = 60
_BRIEF.maxlong = 40


def brief(value) -> str:
    """A short ``repr`` of any value read from a file, for a one-line message: bounded in length and
    in the work it takes (a YAML alias bomb, a list of lists of the same list ..., is not expanded)."""
    return _BRIEF.repr(value)


class HandEyeError(Exception):
    """Base of every error the ``handeye`` command reports as one line (no traceback)."""


class SessionError(HandEyeError):
    """A session on disk is missing, malformed or holds values that cannot be used."""


class CalibrationError(HandEyeError):
    """The data cannot be solved: too few postures, degenerate motion, inconsistent points."""


class OutputError(HandEyeError):
    """A file or folder cannot be written: permission denied, a read-only file system, a file where a
    folder should be, a full disk. The message names the path, the reason and what to do."""
