"""Camera-side exceptions: sub-classes of :class:`~handeye.drivers.errors.CameraError`.

Each carries a one-line message that names the offending value and what to do next, so the
``handeye`` command can print it as it is and a capture loop can reject the posture and go on.
"""

from __future__ import annotations

from ...base import UsageError
from ..errors import CameraError

__all__ = ["CameraError", "FrameError", "FrameUsageError", "BoardNotFound", "NoBoardInView", "StereoModelError",
           "StereoMismatch", "SquareSizeMismatch"]


class FrameError(CameraError):
    """A frame or image cannot be used: truncated raw buffer, wrong size, unreadable file."""


class FrameUsageError(UsageError, FrameError):
    """The images asked for are given wrongly on the command line (``--left`` without ``--right``)."""


class BoardNotFound(CameraError):
    """The checkerboard was not found (completely, with the expected corner count) in an image."""


class NoBoardInView(BoardNotFound):
    """No checkerboard at all in an image (not a part of one, not another count): the board is out of
    view, covered or unlit; grabbing again from the same view does not find it."""


class StereoModelError(CameraError):
    """A stereo calibration file is missing, malformed or inconsistent."""


class StereoMismatch(CameraError):
    """Left and right detections do not agree with the stereo model (swapped or unrelated images)."""


class SquareSizeMismatch(CameraError):
    """The measured corner spacing disagrees with the given square size (wrong size, or a stereo model
    whose baseline is not in mm): a systematic error, not a bad view."""
