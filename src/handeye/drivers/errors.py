"""Exceptions of the hardware side: a handful of kinds shared by every back end, each carrying the
back end's name (``.backend``, and in front of the message: ``socket: PING: no reply ...``).

The tree::

    HandEyeError (src/handeye/base/errors.py)
     +-- ConfigError (src/handeye/base/errors.py)   configuration: a bad option, register map, back-end name
     +-- StationError                          base of every driver error (``.backend``)
          +-- LinkConnectionError              connection: cannot connect, or reconnecting failed
          +-- LinkTimeout                      timeout: no answer within the time budget
          +-- ProtocolError                    protocol: a reply that cannot be understood
          +-- Refused                          refused: the device answered with an error (``.code``)
          +-- ControllerError                  the controller, otherwise (a read-back that differs)
          |    +-- InvalidRequest (ValueError) refused on the PC before anything was sent
          +-- CameraError                      the camera: frames, boards, stereo models

A back end raises the shared kinds with its name (``LinkTimeout("...", backend="modbus")``): there
is no copy of the tree per back end. The controller-flavoured names of the kinds
(``ControllerTimeout``, ``ControllerConnectionError``, ``ControllerRefused``) are the same classes.
"""

from __future__ import annotations

from ..base import ConfigError, HandEyeError, with_backend

__all__ = [
    "StationError",
    "LinkConnectionError",
    "LinkTimeout",
    "ProtocolError",
    "Refused",
    "ConfigError",
    "ControllerError",
    "CameraError",
    "ControllerConnectionError",
    "ControllerTimeout",
    "ControllerRefused",
    "KINDS",
]


class StationError(HandEyeError):
    """Base of every driver error.

    Parameters
    ----------
    message : str
        One line naming the offending value.
    backend : str, optional
        Name of the back end that raised it (a registered back end's name: ``socket``, ``xb3`` ...): kept as
        :attr:`backend` and put in front of the message.

    Attributes
    ----------
    backend : str or None
    detail : str
        The message without the back end's name (for wrapping it into another message).
    """

    def __init__(self, message: str = "", *, backend: str | None = None):
        self.backend = backend
        self.detail = str(message)
        super().__init__(with_backend(message, backend))


class LinkConnectionError(StationError):
    """The device cannot be reached, or the link dropped and could not be re-established."""


class LinkTimeout(StationError):
    """The device did not answer within the time budget."""


class ProtocolError(StationError):
    """A message from the device could not be understood (garbage, wrong id, malformed reply)."""


class Refused(StationError):
    """The device understood the request and refused it.

    Attributes
    ----------
    code : int
        The error code of the reply (for a controller: ``protocol.ERROR_CODES``).
    reason : str
        The device's own words, where its reply has them (the line back ends set it; absent otherwise).
    """

    reason: str

    def __init__(self, message: str = "", code: int = 0, *, backend: str | None = None):
        super().__init__(message, backend=backend)
        self.code = int(code)


class ControllerError(StationError):
    """The robot controller failed in a way none of the shared kinds names (a read-back that differs)."""


class CameraError(StationError):
    """The camera cannot be opened, grabbed from, or its frame cannot be decoded."""


#: The names the controller side has always used for the shared kinds.
ControllerConnectionError = LinkConnectionError
ControllerTimeout = LinkTimeout
ControllerRefused = Refused

#: The five kinds every back end raises, by the word used for them.
KINDS = {"connection": LinkConnectionError, "timeout": LinkTimeout, "protocol": ProtocolError, "refused": Refused,
         "configuration": ConfigError}
