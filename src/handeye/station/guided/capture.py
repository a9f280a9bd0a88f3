"""Operator-guided capture (``capture --guided``): the operator jogs, the PC captures whenever the arm rests.

For cells that cannot run an automatic program: the operator moves the robot with the pendant; the
PC reads the joints every ``guided.poll_s`` and, once they have not changed by more than
``guided.still_tolerance_deg`` for ``guided.still_s`` (:class:`StillWatch`), and the flange stands
somewhere new (at least ``guided.min_step_deg`` of rotation or ``guided.min_step_mm`` from every
posture already captured), captures there exactly as the planned capture does (warning when the arm
rests within ``cell.margin_mm`` of a keep-out volume: the PC does not move it, the operator does): the flange pose
checked against the kinematics, the board grabbed, triangulated and judged (retried), the posture
file written atomically. After every posture it says what is still missing (:func:`what_is_missing`)
in the quality words of ``calibration.quality_words`` and what to do next, and says when the set is
good enough for the verdict's thresholds (``station.report.quality.QualityThresholds``) and the guided
targets; the operator may go on or stop (Ctrl-C; the session is whole at any moment).

The session is the planned capture's format (``capture.mode: guided`` in its record, no plan);
the same resume rules hold: run the same command again and the postures on disk stay, new ones are
numbered after them; a session of the other station (mock / real) or of the planned capture is
refused. The controller needs only to answer joints and pose reads: the PC never asks it to move.
This loop watches the joints (Robot Web Services, the embedded mock); over a line or Modbus, where the
controller does not jog beside a running program, :mod:`handeye.station.guided.pendant` runs the guided
RAPID program instead, with the same session, words and events (``station.capture.events``).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...base import remove_stale_temporaries
from ...robot import load_robot
from ...calibration import IMAGE_CELL_NAMES, MEDIAN_ANGLE_NAME, board_distances_mm, distance_spread_mm, hand_axis_coverage, image_cells
from ...calibration import Session, create_session, read_session
from ...geometry import rotation_error_deg
from ..capture.loop import (
    _STATION_NAMES,
    CaptureError,
    PostureReport,
    grab_observer,
    measure_with_retries,
    measurement_line,
    read_flange,
    stereo_views,
    store_posture,
)
from ..capture.events import CAPTURED, NOT_CAPTURED, TOO_CLOSE, CaptureStarted, Prompt, Verdict
from ..cell.plan import cell_check
from ..config.station import StationConfig
from ..origin import MOCK, REAL, session_origin
from ..config.station_kind import station_kind
from ..report.quality import QualityThresholds, config_thresholds, direction_name, motion_shortfalls
from ..runtime import StationLink

__all__ = ["GuidedSummary", "Missing", "StillWatch", "guided_capture", "postures_needed",
           "what_is_missing"]


@dataclass(frozen=True)
class Missing:
    """One thing the posture set still lacks.

    Attributes
    ----------
    word : str
        The quality word (``rotation-axis spread``).
    now, target : str
        Its value and what it must reach (``6.2 deg``, ``>= 10 deg``).
    advice : str
        What to do next at the pendant.
    """

    word: str
    now: str
    target: str
    advice: str

    def shortfall(self) -> str:
        """The word, its value and its target, without the advice (``postures 12 (needs >= 15)``)."""
        return f"{self.word} {self.now} (needs {self.target})"

    def line(self) -> str:
        return f"{self.shortfall()}: {self.advice}"


def postures_needed(thresholds: QualityThresholds) -> int:
    """Postures to capture so the verdict keeps ``min_inlier_postures`` even with the largest share of
    outliers it allows (``max_outlier_fraction``)."""
    return math.ceil(thresholds.min_inlier_postures / (1.0 - min(thresholds.max_outlier_fraction, 0.9)) - 1e-9)


def _cell_names(cells: set) -> list[str]:
    return [IMAGE_CELL_NAMES[r][c] for r in range(3) for c in range(3) if (r, c) not in cells]


def what_is_missing(tool02base, distances_mm, cells: set, thresholds: QualityThresholds, guided) -> list[Missing]:
    """What the captured postures lack, first the verdict's words, then the guided targets.

    Parameters
    ----------
    tool02base : ndarray, shape (n, 4, 4)
        The flange poses captured.
    distances_mm : ndarray, shape (n,)
        Camera-to-board-centre distances (``quality_words.board_distances_mm``).
    cells : set of (row, col)
        Cells of the 3 x 3 image grid the board's corners have been seen in (``quality_words.image_cells``).
    thresholds : QualityThresholds
    guided : GuidedSettings
        ``min_distance_spread_mm``, ``min_image_cells``.

    Returns
    -------
    list of Missing
        Empty when the set is good enough.
    """
    n, needed = len(tool02base), postures_needed(thresholds)
    out = []
    if n < needed:
        first = " (the first: the board whole in view, about 0.9 m away)" if n == 0 else ""
        out.append(Missing("postures", str(n), f">= {needed}", f"capture {needed - n} more{first}"))
    if n == 0:
        return out
    out += _rotation_missing(np.asarray(tool02base, float).reshape(-1, 4, 4), thresholds)
    spread = distance_spread_mm(distances_mm)
    if spread < guided.min_distance_spread_mm:
        near, far = float(np.min(distances_mm)), float(np.max(distances_mm))
        out.append(Missing("distance spread", f"{spread:.0f} mm", f">= {guided.min_distance_spread_mm:g} mm",
                           f"move the camera nearer than {near:.0f} mm or farther than {far:.0f} mm from the board"))
    if len(cells) < guided.min_image_cells:
        out.append(Missing("board position in the image", f"{len(cells)} of 9 cells", f">= {guided.min_image_cells}",
                           f"show the board in the {', '.join(_cell_names(cells))} of the image"))
    return out


def _rotation_missing(tool02base: np.ndarray, thresholds: QualityThresholds) -> list:
    """The rotation words of the flange poses against the thresholds (a single posture: turn at all)."""
    if len(tool02base) < 2:
        return [Missing(MEDIAN_ANGLE_NAME, "none yet", f">= {thresholds.min_median_rotation_deg:g} deg",
                        "turn the flange 20-45 deg from this posture, keeping the board in view")]
    coverage = hand_axis_coverage(tool02base, "tool0")
    direction = direction_name(coverage.weakest_direction, "tool0")
    hint = " (axis 6 alone does that)" if direction == "tool0 z" else ""
    advice = {"min_rotation_axis_spread_deg": f"turn the flange about {direction}{hint} next, keeping the board in view",
              "min_median_rotation_deg": "turn the flange further between postures (20-45 deg)"}
    return [Missing(s.word, f"{s.value:.1f} deg", f">= {s.required:g} deg", advice[s.key])
            for s in motion_shortfalls(coverage, thresholds)]


class StillWatch:
    """Says once per rest when the joints have held still for ``still_s`` (changes of at most
    ``tolerance_deg`` on every axis count as still)."""

    def __init__(self, still_s: float, tolerance_deg: float):
        self.still_s = still_s
        self.tolerance_deg = tolerance_deg
        self._anchor = None
        self._since = 0.0
        self._fired = False

    def update(self, joints, now: float) -> bool:
        """Feed a reading; True the first time the arm has been still for ``still_s`` at this rest."""
        joints = np.asarray(joints, float)
        if self._anchor is None or np.max(np.abs(joints - self._anchor)) > self.tolerance_deg:
            self._anchor, self._since, self._fired = joints, now, False
            return False
        if not self._fired and now - self._since >= self.still_s:
            self._fired = True
            return True
        return False


@dataclass
class _Captured:
    """What the postures on disk say about coverage: flange poses, distances, image cells."""

    tool02base: list = field(default_factory=list)
    distances: list = field(default_factory=list)
    cells: set = field(default_factory=set)
    next_index: int = 0

    def add(self, index: int, tool02base, points_mm, view) -> None:
        self.tool02base.append(np.asarray(tool02base, float))
        self.distances.append(float(board_distances_mm(np.asarray(points_mm, float)[None])[0]))
        self.cells |= image_cells(view.project(np.asarray(points_mm, float)), view.width, view.height)
        self.next_index = max(self.next_index, index + 1)

    def nearest(self, tool02base) -> tuple[float, float, int]:
        """Rotation (deg) and distance (mm) to the nearest captured flange pose, and its index in the list."""
        if not self.tool02base:
            return math.inf, math.inf, -1
        poses = np.array(self.tool02base)
        rot = np.atleast_1d(rotation_error_deg(poses, np.asarray(tool02base, float)[None]))
        dist = np.linalg.norm(poses[:, :3, 3] - np.asarray(tool02base, float)[:3, 3], axis=1)
        k = int(np.argmin(np.maximum(rot / 5.0, dist / 50.0)))
        return float(rot[k]), float(dist[k]), k


@dataclass
class GuidedSummary:
    """Outcome of :func:`guided_capture`.

    Attributes
    ----------
    session : Path
    captured : list of int
        Session indices (0-based) written in this run.
    already : int
        Postures on disk when the run started.
    missing : list of Missing
        What the set still lacks (empty: good enough).
    duration_s : float
    """

    session: Path
    captured: list
    already: int
    missing: list
    duration_s: float

    @property
    def good_enough(self) -> bool:
        return not self.missing


def _open_guided(config: StationConfig, session_dir: Path, progress, how: str, link: StationLink | None = None) -> Session:
    """The guided session: created, or read back (refused when planned, or from the other station:
    :func:`~handeye.station.config.station_kind.station_kind` of ``config`` and ``link``); ``how``: the running
    loop's words for how a posture is captured, said in both cases."""
    station = station_kind(config, link)
    if not (session_dir / "session.yaml").exists():
        session = Session(setup="eye_in_hand", robot=config.robot, target=config.target, extra={"capture": {
            "station": station, "mode": "guided", "skipped": {}, "config": config.to_dict()}})
        create_session(session_dir, session)
        progress(f"guided capture into {session_dir}: {how}")
        return session
    session = read_session(session_dir)
    record = session.extra.get("capture")
    if record is None or record.get("mode") != "guided":
        raise CaptureError(f"{session_dir} holds a {'planned capture' if record else 'session not made by capture'}: "
                           "resume it without --guided, or choose a new folder")
    recorded = session_origin(session)
    if recorded in (MOCK, REAL) and recorded != station:
        raise CaptureError(f"{session_dir} was captured on the {_STATION_NAMES[recorded]}; resume it on the same station "
                           "or start a new session folder")
    remove_stale_temporaries(session_dir)
    progress(f"resuming the guided capture {session_dir}: {len(session.postures)} postures on disk; {how}")
    return session


class _GuidedRun:
    """One run of the guided loop on a connected station."""

    def __init__(self, config: StationConfig, session_dir: Path, link: StationLink, progress, on_posture,
                 observer: Callable | None = None):
        self.config, self.session_dir, self.link = config, session_dir, link
        self.progress, self.on_posture = progress, on_posture
        self.observer = observer or (lambda event: None)
        self.robot = load_robot(config.robot)
        self.thresholds = config_thresholds(config)
        if link.stereo_model is None:  # every capturing link is opened with its stereo model
            raise CaptureError("the station link has no stereo model to judge the views with")
        self.view = stereo_views(link.stereo_model)[0]
        self.session = _open_guided(config, session_dir, progress, self.how_to_capture(), link)
        self.state = _Captured()
        for posture in self.session.postures:
            self.state.add(posture.index, posture.tool0_in_base, posture.points_mm, self.view)
        self.captured: list = []
        self._told = None
        self.guard = cell_check(config).guard(self.robot)  # the configured volumes (the stand needs a board pose)
        self.observer(CaptureStarted("guided", str(session_dir), list(self.session.postures),
                                     dict(self.session.extra["capture"].get("skipped", {}))))

    def how_to_capture(self) -> str:
        """What the operator does for a posture to be captured, in this loop (the PC watches the joints)."""
        who = "the simulated operator jogs the arm" if self.link.is_mock else "jog the robot with the pendant"
        return (f"{who}; each time it rests {self.config.guided.still_s:g} s somewhere new with the board in view, "
                "the posture is captured")

    def how_to_stop(self) -> str:
        """How the operator ends the run in this loop."""
        return "add more or stop (Ctrl-C)"

    def missing(self) -> list:
        s = self.state
        return what_is_missing(np.array(s.tool02base).reshape(-1, 4, 4), np.array(s.distances), s.cells,
                               self.thresholds, self.config.guided)

    def say_missing(self) -> None:
        missing = self.missing()
        if not missing:
            self.progress(f"GOOD ENOUGH: {len(self.state.tool02base)} postures meet the verdict's thresholds and the "
                          f"guided targets; {self.how_to_stop()}, then: handeye calibrate {self.session_dir} --report")
            self.observer(Prompt("jog", f"GOOD ENOUGH: {self.how_to_stop()}"))
            return
        self.progress("missing: " + "; ".join(m.line() for m in missing))
        self.observer(Prompt("jog", missing[0].advice))

    def at_rest(self, joints) -> None:
        """The arm rests at ``joints``: capture there when it is somewhere new."""
        g = self.config.guided
        rot, dist, k = self.state.nearest(self.robot.forward_transform(joints))
        if rot < g.min_step_deg and dist < g.min_step_mm:
            if self._told != k:
                self.refuse(self.state.next_index, TOO_CLOSE, f"at rest {rot:.1f} deg and {dist:.0f} mm from a "
                            f"captured posture: move on (at least {g.min_step_deg:g} deg or {g.min_step_mm:g} mm)")
                self._told = k
            return
        self._told = None
        near = self.guard.posture_violation(joints)
        if near is not None:
            self.progress(f"careful: {near.describe()} (cell.margin_mm {self.guard.margin_mm:g}): jog away from it")
        index = self.state.next_index
        joints, tool02base = read_flange(self.config, self.link, self.robot, f"posture {index}")
        result, frame, problem, attempts = measure_with_retries(self.config, self.link,
                                                                grab_observer(self.observer, index, tool02base))
        if problem is not None:
            self.refuse(index, NOT_CAPTURED, f"not captured after {attempts} attempt(s): {problem}; turn back towards "
                        "the board", result.quality if result is not None else {})
            return
        self.store(index, joints, tool02base, result, frame, attempts)

    def refuse(self, index: int, word: str, line: str, quality: dict | None = None) -> None:
        """Tell the operator and the observer why posture ``index`` was not captured (``word``: a
        ``capture_events`` verdict)."""
        self.progress(line)
        self.observer(Verdict(index, word, line, quality or {}))

    def store(self, index: int, joints, tool02base, result, frame, attempts: int) -> None:
        """Write a measured posture, add it to the set and tell the observer, the caller and the operator."""
        store_posture(self.config, self.session_dir, index, joints, tool02base, result, frame, guided=True)
        self.state.add(index, tool02base, result.points_mm, self.view)
        self.captured.append(index)
        count = len(self.state.tool02base)
        line = f"posture {index}: {measurement_line(result.quality)}"
        self.observer(Verdict(index, CAPTURED, line, result.quality, tool02base, result.points_mm))
        self.on_posture(PostureReport(index, count, True, line, result.quality, attempts, done=count))
        self.say_missing()


def guided_capture(
    config: StationConfig,
    session_dir,
    link: StationLink,
    progress: Callable[[str], None] = lambda message: None,
    on_posture: Callable[[PostureReport], None] = lambda report: None,
    stop: threading.Event | None = None,
    clock: Callable[[], float] = time.monotonic,
    observer: Callable | None = None,
) -> GuidedSummary:
    """Run (or resume) an operator-guided capture into ``session_dir`` until ``stop`` is set, Ctrl-C, or
    ``guided.max_postures`` postures are on disk.

    Parameters
    ----------
    config : StationConfig
        ``guided`` (still time, tolerance, steps, targets), ``quality`` (the thresholds), ``capture``
        (per-posture quality).
    session_dir : path
    link : StationLink
        The connected controller (joints and pose reads only) and camera.
    progress : callable
        One-line messages: what was captured, what is missing and what to do next, GOOD ENOUGH.
    on_posture : callable
        A :class:`~handeye.station.capture.loop.PostureReport` after each posture (``index``: the posture's file number).
    stop : threading.Event, optional
        Set to end the run (a test's scripted operator; the command ends on Ctrl-C).
    clock : callable
        Monotonic seconds (the still time is measured on it).
    observer : callable, optional
        Receives the ``station.capture.events`` from the capture thread (the live view): CaptureStarted,
        a Prompt (``jog``) with the next hint after each change, Measured (each grab) and Verdict.

    Raises
    ------
    CaptureError, ControllerError, CameraError
    """
    started = clock()
    session_dir = Path(session_dir)
    stop = stop or threading.Event()
    run = _GuidedRun(config, session_dir, link, progress, on_posture, observer)
    already = len(run.state.tool02base)
    run.say_missing()
    watch = StillWatch(config.guided.still_s, config.guided.still_tolerance_deg)
    while not stop.is_set() and len(run.state.tool02base) < config.guided.max_postures:
        joints = link.controller.read_joints()
        if watch.update(joints, clock()):
            run.at_rest(joints)
        stop.wait(config.guided.poll_s)
    if len(run.state.tool02base) >= config.guided.max_postures:
        progress(f"{config.guided.max_postures} postures (guided.max_postures): done")
    return GuidedSummary(session_dir, run.captured, already, run.missing(), clock() - started)
