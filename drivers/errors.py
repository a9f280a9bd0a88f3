"""Exceptions of the hardware side (controller and camera), each with the offending value in its message."""

from __future__ import annotations

from ..calibration.errors import HandEyeError

__all__ = ["StationError", "ControllerError", "ProtocolError", "ControllerTimeout", "CameraError"]


class StationError(HandEyeError):
    """Base of every driver error."""


class ControllerError(StationError):
    """The robot controller refused, failed or cannot be reached."""


class ProtocolError(ControllerError):
    """A message from the controller could not be understood (garbage, wrong id, malformed reply)."""


class ControllerTimeout(ControllerError):
    """The controller did not answer within the timeout."""


class CameraError(StationError):
    """The camera cannot be opened, grabbed from, or its frame cannot be decoded."""
