"""A simulated ABB IRB 1400 for the mock controller: limits, synchronised moves, kinematics, tool data.

The controller's RAPID program (run by the interpreter, ``mocks/controller``) moves it with
``MoveAbsJ``, reads it with ``CJointT``/``CRobT`` and keeps the camera's tool data in its PERS
tooldata (:attr:`SimulatedRobot.tool` reads it there once a program is attached); the world zones
the program defines are kept in :attr:`SimulatedRobot.world_zones`.

The arm moves between joint configurations with all axes starting and stopping together
(a synchronised ``MoveAbsJ``): the move lasts ``max_i |Δq_i| / (speed_fraction * max_speed_i)``,
axes interpolated linearly in time (no acceleration ramps, no path planning). A cell can be given
(``guard``: a :class:`~handeye.robot.clearance.CellGuard`): a move whose joint-interpolated
path takes any link or what the flange carries into one of its volumes, or into the arm's own links
(the robot file's self-collision pairs), is refused before the arm moves (:class:`ZoneViolation`), as
a real cell's world zones, or a real arm's crash, would stop it. Without a cell the arm still
refuses self-collision (:func:`self_guard`, the default). The
flange pose comes from the kinematics model (``robot.kinematics``: the parallel-arm coupling
of axes 2 and 3 included). ``time_scale`` shrinks wall-clock motion time for tests (0.01 = 100x).

Thread-safe: the controller servers move the robot from their threads while a test or the station
reads ``current_joints`` from another.
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from collections.abc import Sequence
from typing import Callable, Protocol

import numpy as np
import numpy.typing as npt

from ..robot import DEFAULT_CARRIED
from ..robot import CellGuard
from ..base import HandEyeError
from ..robot import RobotModel, load_robot
from ..drivers import FlangePose, ToolData

__all__ = ["SimulatedRobot", "DEFAULT_TOOL", "SELF_ONLY", "ZoneViolation", "self_guard"]

#: What a fresh PERS tooldata holds before calibration: tool0's frame, 1 kg at the flange.
DEFAULT_TOOL = ToolData((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), 1.0, (0.0, 0.0, 0.0))


#: ``SimulatedRobot(guard=SELF_ONLY)`` (the default): the arm's self-collision check alone (:func:`self_guard`).
SELF_ONLY = "self-collision only"


def self_guard(model: RobotModel, carried: Sequence = DEFAULT_CARRIED) -> CellGuard:
    """The arm against itself and what its flange carries, no keep-out volume: touching is refused (margin
    0), moves sampled every 5 mm of motion."""
    return CellGuard(model, [], carried, margin_mm=0.0, step_mm=5.0)


class CellViolation(Protocol):
    """What the cell check finds (:class:`handeye.robot.clearance.Violation`): who came too close to what, where."""

    @property
    def body(self) -> str: ...
    @property
    def volume(self) -> str: ...
    @property
    def at(self) -> float: ...
    @property
    def kind(self) -> str: ...
    @property
    def reason(self) -> str: ...
    def describe(self) -> str: ...


class ZoneViolation(HandEyeError):
    """A move refused because its path enters a volume of the cell (what world zones would stop).

    Attributes
    ----------
    violation : handeye.robot.clearance.Violation
        What would have entered which volume, and where along the move.
    target_deg : ndarray, shape (dof,)
    """

    def __init__(self, violation: CellViolation, target_deg: npt.ArrayLike, posture: int = 0):
        where = f"posture {posture}" if posture else "the target"
        if violation.kind == "self":
            text = (f"self-collision: {violation.reason} on the way to {where} ({violation.describe()} at "
                    f"{violation.at:.0%} of the move); the arm did not move")
        else:
            text = (f"world zone: {violation.body} would enter '{violation.volume}' on the way to {where} "
                    f"({violation.describe()} at {violation.at:.0%} of the move); the arm did not move")
        super().__init__(text)
        self.violation = violation
        self.target_deg = np.asarray(target_deg, float)
        self.posture = posture


class SimulatedRobot:
    """The simulated arm.

    Parameters
    ----------
    postures : array-like, shape (n, dof)
        Approved postures (controller angles, deg), 1-based for :meth:`start_posture`.
    model : str
        Robot model name or YAML path (default ``IRB1400``).
    speed_fraction : float
        Fraction of each axis' maximum speed used by moves (default 0.25).
    time_scale : float
        Wall-clock seconds per simulated second (default 1; tests use e.g. 0.001).
    start_joints : array-like, shape (dof,), optional
        Initial configuration (default: all zero).
    clock : callable
        Monotonic time source in seconds (default ``time.monotonic``).
    guard : CellGuard, :data:`SELF_ONLY` or None
        The cell: moves whose path enters one of its volumes, or brings two of the arm's bodies together,
        are refused (:class:`ZoneViolation`). Default :data:`SELF_ONLY`: self-collision alone
        (:func:`self_guard`); None: nothing checked (a test of the motion alone).

    Attributes
    ----------
    arrival_hooks : list of callable
        Each is called as ``hook(k, joints_deg)`` when a move to posture ``k`` ends.
    guard : CellGuard or None
        The cell the moves are checked against (may be replaced at any time).
    refusals : list of ZoneViolation
        The moves refused so far.
    world_zones : dict
        World zones the controller's program defined (number -> zone), checked by its moves.
    tool_source : callable or None
        Where :attr:`tool` reads the camera's tool data (the program's PERS tooldata).
    """

    def __init__(self, postures: npt.ArrayLike, model: str = "IRB1400", speed_fraction: float = 0.25,
                 time_scale: float = 1.0, start_joints: npt.ArrayLike | None = None,
                 clock: Callable[[], float] = time.monotonic, guard: CellGuard | str | None = SELF_ONLY):
        self.model = load_robot(model)
        self.postures = np.array(postures, dtype=float).reshape(-1, self.model.dof)
        for i, row in enumerate(self.postures, start=1):
            problems = self.model.limit_violations(row)
            if problems:
                raise ValueError(f"approved posture {i} is outside the {self.model.name} limits: {'; '.join(problems)}")
        if not 0 < speed_fraction <= 1:
            raise ValueError(f"speed_fraction must be in (0, 1]; got {speed_fraction}")
        if not time_scale > 0:
            raise ValueError(f"time_scale must be > 0; got {time_scale}")
        self.speed_fraction = float(speed_fraction)
        self.time_scale = float(time_scale)
        self._clock = clock
        start = np.zeros(self.model.dof) if start_joints is None else np.asarray(start_joints, dtype=float)
        if self.model.limit_violations(start):
            raise ValueError(f"start configuration outside limits: {self.model.limit_violations(start)}")
        self._lock = threading.RLock()
        self._path = start[None].copy()  # the waypoints of the current move (the start first) and their times
        self._times = np.zeros(1)
        self._t0 = self._clock()
        self._duration = 0.0
        self._target_posture = 0
        self._arrived_posture = 0
        self._arrival_reported = True
        self._tool = DEFAULT_TOOL
        self.arrival_hooks: list[Callable[[int, np.ndarray], None]] = []
        self.world_zones: dict = {}
        self.tool_source: Callable[[], ToolData] | None = None
        #: Number of moves started (for tests).
        self.moves = 0
        #: Simulated seconds of motion so far (what the moves take at full time scale).
        self.motion_s = 0.0
        if isinstance(guard, str) and guard != SELF_ONLY:
            raise ValueError(f"guard must be a CellGuard, SELF_ONLY or None; got {guard!r}")
        self.guard: CellGuard | None = self_guard(self.model) if isinstance(guard, str) else guard
        self.refusals: list[ZoneViolation] = []

    def load_program(self, postures: npt.ArrayLike) -> None:
        """Replace the approved postures, as loading a newly generated RAPID program does.

        Raises
        ------
        ValueError
            If a posture is outside the joint limits (the program would not be approved).
        """
        plan = np.array(postures, dtype=float).reshape(-1, self.model.dof)
        for i, row in enumerate(plan, start=1):
            problems = self.model.limit_violations(row)
            if problems:
                raise ValueError(f"approved posture {i} is outside the {self.model.name} limits: {'; '.join(problems)}")
        with self._lock:
            self.postures = plan

    # ------------------------------------------------------------------ motion
    def motion_time(self, target_deg: npt.ArrayLike) -> float:
        """Simulated seconds of a synchronised move from the current configuration to ``target_deg``."""
        delta = np.abs(np.asarray(target_deg, dtype=float) - self.current_joints)
        return float(np.max(delta / (self.speed_fraction * self.model.max_speed_deg_s)))

    def start_move(self, target_deg: npt.ArrayLike, posture: int = 0) -> float:
        """Start a synchronised move; returns its wall-clock duration in seconds.

        Raises
        ------
        ValueError
            If the target is outside the joint limits (the controller would refuse it too).
        ZoneViolation
            If the path enters a volume of the cell (``guard``); the arm stays where it is.
        """
        return self.start_path(np.asarray(target_deg, dtype=float)[None], posture)

    def start_path(self, configurations: npt.ArrayLike, posture: int = 0) -> float:
        """Start a move through the joint configurations ``(n, dof)`` in turn (each step synchronised and
        joint-interpolated; a ``MoveL`` gives the configurations of its samples along the TCP line);
        returns its wall-clock duration in seconds.

        Raises
        ------
        ValueError
            A configuration outside the joint limits.
        ZoneViolation
            The path from where the arm stands through every configuration enters a volume of the cell
            (:meth:`path_violation`); the arm stays where it is.
        """
        waypoints = np.asarray(configurations, dtype=float).reshape(-1, self.model.dof)
        for row in waypoints:
            problems = self.model.limit_violations(row)
            if problems:
                raise ValueError(f"target outside the joint limits: {'; '.join(problems)}")
        with self._lock:
            self._settle()
            now = self._clock()
            path = np.vstack([self._joints_at(now)[None], waypoints])
            violation = self.path_violation(path)
            if violation is not None:
                refusal = ZoneViolation(violation, waypoints[-1], posture)
                self.refusals.append(refusal)
                raise refusal
            steps = np.max(np.abs(np.diff(path, axis=0)) / (self.speed_fraction * self.model.max_speed_deg_s), axis=1)
            self.motion_s += float(np.sum(steps))
            self._path, self._times = path, np.concatenate([[0.0], np.cumsum(steps * self.time_scale)])
            self._duration, self._t0 = float(self._times[-1]), now
            self._target_posture = int(posture)
            self._arrived_posture = 0
            self._arrival_reported = False
            self.moves += 1
            return self._duration

    def jog(self, target_deg: npt.ArrayLike) -> tuple[float, CellViolation | None]:
        """Jog towards ``target_deg`` (the operator's joystick, here axis-synchronised at the arm's speed);
        returns ``(wall-clock duration, violation or None)``.

        The cell check applies as to a program's moves, but a jog is not refused as a whole: motion
        supervision stops the arm where its path first comes within the margin of a volume (the first
        point the posture check itself finds there), and the violation says which and why.

        Raises
        ------
        ValueError
            The target is outside the joint limits.
        """
        target = np.asarray(target_deg, dtype=float).reshape(self.model.dof)
        problems = self.model.limit_violations(target)
        if problems:
            raise ValueError(f"jog target outside the joint limits: {'; '.join(problems)}")
        with self._lock:
            self._settle()
            start = self._joints_at(self._clock())
            guard = self.guard
            free = self._leaving_fraction(start, target)  # within the margin already: jogging out is allowed
            if free is None:  # (only with a guard: without one every jog is clear)
                return 0.0, guard.posture_violation(start) if guard is not None else None
            clear_from = start + free * (target - start)
            violation = self.path_violation(np.vstack([clear_from, target]))
            if violation is None and free == 0.0:
                return self.start_move(target), None
            at = 1.0 if violation is None else free + violation.at * (1.0 - free)
            while (violation is not None and guard is not None and at < 1.0
                   and guard.posture_violation(start + at * (target - start)) is None):
                at = min(1.0, at + 0.005)
            self.guard = None  # where supervision stops the arm: the move up to there
            try:
                return self.start_move(start + at * (target - start)), violation
            finally:
                self.guard = guard

    def _leaving_fraction(self, start, target) -> float | None:
        """0 when ``start`` is clear of the cell; else the first fraction of the jog ``start -> target`` clear of
        every volume's margin (the arm jogs out of it), None when the jog never leaves it."""
        if self.guard is None or self.guard.posture_violation(start) is None:
            return 0.0
        for at in np.linspace(0.0, 1.0, 201)[1:]:
            if self.guard.posture_violation(start + at * (target - start)) is None:
                return float(at)
        return None

    def path_violation(self, configurations: npt.ArrayLike) -> CellViolation | None:
        """The cell check of a path: the first place where the arm, moving joint-interpolated from each
        configuration of ``configurations`` ``(n, dof)`` to the next, comes closer to a volume of the cell
        (``guard``) than its margin; a :class:`~handeye.robot.clearance.Violation` whose ``at`` is
        the fraction of the whole path, or None (clear, or no cell)."""
        path = np.asarray(configurations, dtype=float).reshape(-1, self.model.dof)
        if self.guard is None:
            return None
        steps = list(zip(path[:-1], path[1:])) or [(path[0], path[0])]
        for i, violation in enumerate(self.guard.moves_violations(steps)):
            if violation is not None:
                return replace(violation, at=(i + violation.at) / len(steps))
        return None

    def start_posture(self, k: int) -> float:
        """Start the move to approved posture ``k`` (1-based); returns the wall-clock duration."""
        if not 1 <= k <= len(self.postures):
            raise ValueError(f"posture {k} is not one of the {len(self.postures)} approved postures")
        return self.start_move(self.postures[k - 1], posture=k)

    def _joints_at(self, now: float) -> np.ndarray:
        if self._duration <= 0:
            return self._path[-1].copy()
        t = min(max(now - self._t0, 0.0), self._duration)
        return np.array([np.interp(t, self._times, axis) for axis in self._path.T])

    def _settle(self) -> None:
        """Report the arrival of a finished move once (runs the hooks)."""
        if self._arrival_reported or self._clock() < self._t0 + self._duration:
            return
        self._arrival_reported = True
        self._arrived_posture = self._target_posture
        if self._target_posture:
            joints = self._path[-1].copy()
            for hook in list(self.arrival_hooks):
                hook(self._target_posture, joints)

    @property
    def is_moving(self) -> bool:
        with self._lock:
            self._settle()
            return not self._arrival_reported

    def update(self) -> None:
        """Advance bookkeeping (fires arrival hooks of a finished move)."""
        with self._lock:
            self._settle()

    def time_to_arrival(self) -> float:
        """Wall-clock seconds until the current move ends (0 when standing still)."""
        with self._lock:
            return max(0.0, self._t0 + self._duration - self._clock())

    def wait_until_stopped(self, timeout: float | None = None, stop: threading.Event | None = None) -> bool:
        """Block until the move ends (True), the timeout passes or ``stop`` is set (False)."""
        end = None if timeout is None else time.monotonic() + timeout
        while True:
            left = self.time_to_arrival()
            if left <= 0:
                self.update()
                return True
            if end is not None:
                left = min(left, end - time.monotonic())
                if left <= 0:
                    return False
            if stop is not None:
                if stop.wait(min(left, 0.05)):
                    return False
            else:
                time.sleep(min(left, 0.05))

    # ------------------------------------------------------------------ state
    @property
    def current_joints(self) -> np.ndarray:
        """Controller axis angles now (deg), shape (dof,)."""
        with self._lock:
            self._settle()
            return self._joints_at(self._clock())

    @property
    def current_posture(self) -> int:
        """The approved posture the robot stands at (0 while moving or elsewhere)."""
        with self._lock:
            self._settle()
            return self._arrived_posture

    def tool0_pose(self) -> FlangePose:
        """tool0 in base from the kinematics of the current joints."""
        p, q = self.model.forward(self.current_joints)
        return FlangePose(np.asarray(p, dtype=float), np.asarray(q, dtype=float))

    @property
    def tool(self) -> ToolData:
        """The PERS tooldata of the camera (the program's, once one is attached)."""
        source = self.tool_source
        if source is not None:
            return source()
        with self._lock:
            return self._tool

    @tool.setter
    def tool(self, value: ToolData) -> None:
        with self._lock:
            self._tool = value
