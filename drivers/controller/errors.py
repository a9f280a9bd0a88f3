"""Exceptions of the controller link, shared by every back end.

The tree (each back end adds its own leaves, e.g. ``SocketTimeout``)::

    ControllerError (drivers/errors.py)
     +-- ProtocolError                 a reply that cannot be understood (garbage, wrong id)
     +-- ControllerTimeout             no answer within the timeout
     +-- ControllerConnectionError     cannot connect, or the link dropped and reconnecting failed
     +-- ControllerRefused             the controller answered with an error (``code``)
     +-- InvalidRequest (ValueError)   refused on the PC side before anything was sent
"""

from __future__ import annotations

from ..errors import ControllerError, ControllerTimeout, ProtocolError

__all__ = [
    "ControllerError",
    "ProtocolError",
    "ControllerTimeout",
    "ControllerConnectionError",
    "ControllerRefused",
    "InvalidRequest",
]


class ControllerConnectionError(ControllerError):
    """The controller cannot be reached, or the link dropped and could not be re-established."""


class ControllerRefused(ControllerError):
    """The controller understood the request and refused it.

    Attributes
    ----------
    code : int
        The error code of the reply (see ``protocol.ERROR_CODES``).
    """

    def __init__(self, message: str, code: int = 0):
        super().__init__(message)
        self.code = int(code)


class InvalidRequest(ControllerError, ValueError):
    """A request refused on the PC before anything was sent (NaN, posture outside limits, bad tool)."""
