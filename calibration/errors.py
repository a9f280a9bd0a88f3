"""The package's own exceptions: each carries a one-line message meant for the operator."""

from __future__ import annotations

__all__ = ["HandEyeError", "SessionError", "CalibrationError", "OutputError"]


class HandEyeError(Exception):
    """Base of every error the ``handeye`` command reports as one line (no traceback)."""


class SessionError(HandEyeError):
    """A session on disk is missing, malformed or holds values that cannot be used."""


class CalibrationError(HandEyeError):
    """The data cannot be solved: too few postures, degenerate motion, inconsistent points."""


class OutputError(HandEyeError):
    """A file or folder cannot be written: permission denied, a read-only file system, a file where a
    folder should be, a full disk. The message names the path, the reason and what to do."""
