"""Exceptions of the RAPID side: a program that cannot be generated or fails its checks.

A station config that cannot be used raises the package's one :class:`ConfigError`
(``StationConfigError`` is its old name here).
"""

from __future__ import annotations

from ..base import ConfigError, HandEyeError

__all__ = ["RapidError", "ConfigError", "StationConfigError"]


class RapidError(HandEyeError):
    """RAPID modules cannot be generated (postures outside limits, a check failed)."""


#: The name this module used for :class:`ConfigError` (kept for code that imports it).
StationConfigError = ConfigError
