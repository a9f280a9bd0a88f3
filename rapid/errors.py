"""Exceptions of the RAPID side: a station config that cannot be used, a program that fails its checks."""

from __future__ import annotations

from ..calibration.errors import HandEyeError

__all__ = ["RapidError", "StationConfigError"]


class RapidError(HandEyeError):
    """RAPID modules cannot be generated (postures outside limits, a check failed)."""


class StationConfigError(RapidError):
    """The station config file is missing, malformed or holds values that cannot be used."""
