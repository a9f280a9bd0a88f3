"""Exceptions of the controller link: the shared kinds of ``src/handeye/drivers/errors.py``, under the names the
controller side uses. Every back end raises these same classes with its name (``.backend``)::

    StationError (src/handeye/drivers/errors.py)
     +-- ProtocolError                 a reply that cannot be understood (garbage, wrong id)
     +-- ControllerTimeout             no answer within the timeout            (= LinkTimeout)
     +-- ControllerConnectionError     cannot connect, or reconnecting failed  (= LinkConnectionError)
     +-- ControllerRefused             the controller answered with an error (``code``)  (= Refused)
     +-- ControllerError               anything else on the controller's side
          +-- InvalidRequest (ValueError)   refused on the PC side before anything was sent
    ConfigError                        a bad option, back-end name or register map
"""

from __future__ import annotations

from ..errors import (
    ConfigError,
    ControllerConnectionError,
    ControllerError,
    ControllerRefused,
    ControllerTimeout,
    ProtocolError,
    StationError,
)

__all__ = [
    "StationError",
    "ControllerError",
    "ProtocolError",
    "ControllerTimeout",
    "ControllerConnectionError",
    "ControllerRefused",
    "ConfigError",
    "InvalidRequest",
]


class InvalidRequest(ControllerError, ValueError):
    """A request refused on the PC before anything was sent (NaN, posture outside limits, bad tool)."""
