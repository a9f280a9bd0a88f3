"""The package's own exceptions: each carries a one-line message meant for the operator."""

from __future__ import annotations

import reprlib

__all__ = ["HandEyeError", "SessionError", "CalibrationError", "OutputError", "brief"]

class _Brief(reprlib.Repr):
    def repr_int(self, x, level):
        if x.bit_length() > 4000:  # repr() itself refuses integers of more than 4300 digits
            return f"<an integer of {x.bit_length() * 0.30103:.0f} digits>"
        return super().repr_int(x, level)


_BRIEF = _Brief()
_BRIEF.maxlevel, _BRIEF.maxlist, _BRIEF.maxtuple, _BRIEF.maxdict, _BRIEF.maxset = 3, 6, 6, 4, 6
_BRIEF.maxstring = _BRIEF.maxother = 60
_BRIEF.maxlong = 40


def brief(value) -> str:
    """A short ``repr`` of any value read from a file, for a one-line message: bounded in length and
    in the work it takes (a YAML alias bomb, a list of lists of the same list ..., is not expanded;
    an integer of thousands of digits is described, not printed)."""
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
