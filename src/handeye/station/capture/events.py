"""What a capture loop tells an observer (the live view, ``station.view``), one small event per step.

The planned capture (``station.capture.loop.capture``) and the guided capture
(``station.guided.capture.guided_capture``) take an optional ``observer``: a callable that receives these
events from the capture thread, in order. An observer must return at once (keep a reference, signal
a thread of its own): the capture does not wait for it. The arrays an event carries are not changed
by the capture afterwards.

- :class:`CaptureStarted`: the session is open (new or resumed): the postures already on disk and,
  for a planned capture, the plan.
- :class:`Prompt`: the loop now waits for the robot: it moves to a planned posture (``move``) or the
  operator jogs (``jog``), with what to do in words.
- :class:`Measured`: one grab of one attempt at a posture, the board found (``result``) or not
  (``problem``).
- :class:`Verdict`: what became of a posture or a rest: ``captured``, ``skipped`` (quality),
  ``not captured`` (guided: the board not measured), ``too close`` (guided: near a captured posture).
- :class:`CaptureEnded`: the run is over, with what the command said last (``capture`` tells the
  live view: ``LiveView.finish``); a view closed without it says the capture stopped.

Posture numbers are the files' (``postures/NNN.yaml`` -> NNN), as everywhere the operator reads them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["CAPTURED", "NOT_CAPTURED", "SKIPPED", "TOO_CLOSE", "CaptureEnded", "CaptureStarted", "Measured", "Prompt",
           "Verdict"]

#: The words of :attr:`Verdict.word`.
CAPTURED, SKIPPED, NOT_CAPTURED, TOO_CLOSE = "captured", "skipped", "not captured", "too close"


@dataclass(frozen=True)
class CaptureStarted:
    """The session is open.

    Attributes
    ----------
    mode : str
        ``planned`` or ``guided``.
    session_dir : str
    postures : list of calibration.session.Posture
        The postures on disk when the run started (a resume), by index.
    skipped : dict
        ``{posture number: reason}`` recorded in the session (planned capture).
    plan_joints : ndarray, shape (n, dof), or None
        The plan's joint angles (deg), row ``i`` posture ``i``; None for a guided capture.
    """

    mode: str
    session_dir: str
    postures: list = field(default_factory=list)
    skipped: dict = field(default_factory=dict)
    plan_joints: np.ndarray | None = None


@dataclass(frozen=True)
class Prompt:
    """The loop waits for the robot.

    Attributes
    ----------
    kind : str
        ``move`` (a planned posture: the robot moves there itself) or ``jog`` (the operator jogs).
    text : str
        What happens or what to do, in words.
    posture : int or None
        ``move``: the posture the robot moves to.
    """

    kind: str
    text: str
    posture: int | None = None


@dataclass(frozen=True)
class Measured:
    """One grab at a posture (each attempt of ``measure_with_retries``).

    Attributes
    ----------
    posture : int
        The number the posture gets on disk when captured.
    frame : drivers.camera.StereoFrame
        ``left`` and ``right`` images, shape (h, w) or (h, w, 3), uint8.
    result : drivers.camera.TriangulationResult or None
        The board measured (``left_px``, ``right_px``: corners (m, 2) in the raw images).
    problem : str or None
        Why this grab is not good enough (None: good).
    tool02base : ndarray, shape (4, 4), or None
        The flange pose at this posture (mm).
    """

    posture: int
    frame: object
    result: object = None
    problem: str | None = None
    tool02base: np.ndarray | None = None


@dataclass(frozen=True)
class Verdict:
    """What became of a posture (or of a rest, guided).

    Attributes
    ----------
    posture : int
    word : str
        :data:`CAPTURED`, :data:`SKIPPED`, :data:`NOT_CAPTURED` or :data:`TOO_CLOSE`.
    text : str
        The line the capture prints.
    quality : dict
        The measurement's quality figures (empty when nothing was measured).
    tool02base : ndarray, shape (4, 4), or None
        Captured: the flange pose written (mm).
    points_mm : ndarray, shape (m, 3), or None
        Captured: the corners in the camera frame written (mm).
    """

    posture: int
    word: str
    text: str
    quality: dict = field(default_factory=dict)
    tool02base: np.ndarray | None = None
    points_mm: np.ndarray | None = None


@dataclass(frozen=True)
class CaptureEnded:
    """The run is over: nothing follows.

    Attributes
    ----------
    text : str
        What the command said last (how many postures, what to do next).
    ok : bool
        False when the run ended without what a calibration needs (or was stopped).
    """

    text: str
    ok: bool = True
