"""The package's own exceptions: each carries a one-line message meant for the operator."""

from __future__ import annotations

__all__ = ["HandEyeError", "SessionError", "CalibrationError"]


class HandEyeError(Exception):
    """Base of every error the ``handeye`` command reports as one line (no traceback)."""


class SessionError(HandEyeError):
    """A session on disk is missing, malformed or holds values that cannot be used."""


class CalibrationError(HandEyeError):
    """The data cannot be solved: too few postures, degenerate motion, inconsistent points."""
