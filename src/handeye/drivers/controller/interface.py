"""The controller interface every back end implements, and ``open_controller`` to pick one by name.

A back end is a class with a name (a :data:`~handeye.drivers.controller.backends.CONTROLLERS` entry); :func:`open_controller`
builds it from keyword options and connects. All methods take an optional ``timeout`` (seconds)
that bounds the whole call, reconnects included; a call that has to (re)connect first is allowed
at least ``idle_timeout + timeout`` (the controller may still be freeing itself from a silent
client). Every value is checked on the PC before anything is sent (:class:`InvalidRequest`).
Tool writes need the station's ``write_key``.

Example
-------
>>> with open_controller("socket", host="127.0.0.1", port=1025) as robot:   # doctest: +SKIP
...     robot.goto_posture(3)
...     joints = robot.read_joints()
...     robot.acknowledge(3)
"""

from __future__ import annotations

import logging
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from .errors import ControllerConnectionError, ControllerError, ControllerRefused, ControllerTimeout, InvalidRequest, ProtocolError
from .types import (
    ControllerInfo,
    ControllerStatus,
    FlangePose,
    ToolData,
    check_joints,
    check_posture_index,
    check_timeout,
    check_tooldata,
    check_write_key,
    robot_model,
)

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["Controller", "Deadline", "LinkDown", "open_controller", "read_robot_state"]

log = logging.getLogger(__name__)

T = TypeVar("T")


class LinkDown(Exception):
    """Internal: the connection dropped or could not be opened (the call may reconnect and retry)."""


class Deadline:
    """The end of a call's time budget (monotonic clock)."""

    def __init__(self, seconds: float):
        self.seconds = float(seconds)
        self.start = time.monotonic()
        self.end = self.start + self.seconds

    def extend(self, seconds: float) -> None:
        """Leave at least ``seconds`` from now (never shortens the budget)."""
        end = time.monotonic() + float(seconds)
        if end > self.end:
            self.end = end
            self.seconds = round(end - self.start, 3)  # the budget messages quote: no 7.00001 s

    def remaining(self) -> float:
        return max(0.0, self.end - time.monotonic())

    @property
    def expired(self) -> bool:
        return time.monotonic() >= self.end


class Controller(ABC):
    """A robot controller running the handeye RAPID program.

    Parameters (keyword-only, shared by every back end)
    ----------
    timeout : float
        Default budget of one call in seconds (default 2).
    motion_timeout : float
        Budget for waiting until the robot stands still at a posture (default 120).
    retries : int
        Reconnect attempts within one call after the link dropped (default 3).
    backoff_s, backoff_max_s : float
        First wait before reconnecting, doubled after each failure up to the maximum.
    robot : str
        Robot model for joint-limit checks (default ``IRB1400``).
    postures : array-like, shape (n, dof), optional
        The approved postures the PC expects (the plan the RAPID program was generated from):
        checked against the joint limits at construction and before each move.
    max_tool_mass_kg : float
        Heaviest tool accepted by :meth:`set_tool` (default 5, the IRB 1400 payload).
    idle_timeout : float
        The controller's idle timeout (``controller.idle_timeout_s``, default 5 s): a server busy
        with a silent client frees itself within it, so connecting may wait up to
        ``idle_timeout + timeout`` for the first reply (the call's budget is stretched to that).
    write_key : str, optional
        The station's write key (``controller.write_key``; the one in ``HeKey.sys`` on the
        controller). :meth:`set_tool` refuses to write without it. Never printed.
    """

    #: True once the controller has said it is a simulation (``handeye mock controller``): a session made
    #: with it is never a real one (``station.config.station_kind``). A back end whose protocol cannot say so keeps False.
    simulated = False
    #: What a connection failure tells the operator to check (a back end with no RAPID server overrides it).
    unreachable_hint = "check that the RAPID program runs and the address/port"

    #: Back-end name; set by subclasses (the name it is registered under).
    protocol = "abstract"
    #: Whether tool writes need the station's write key (False where the link authorises writes by
    #: itself: Robot Web Services checks the controller's own users and mastership).
    writes_need_key = True

    # The shared error kinds (src/handeye/drivers/errors.py), named after this back end.
    def connection_error(self, message: str) -> ControllerConnectionError:
        return ControllerConnectionError(message, backend=self.protocol)

    def timeout_error(self, message: str) -> ControllerTimeout:
        return ControllerTimeout(message, backend=self.protocol)

    def protocol_error(self, message: str) -> ProtocolError:
        return ProtocolError(message, backend=self.protocol)

    def refused_error(self, message: str, code: int = 0) -> ControllerRefused:
        return ControllerRefused(message, code, backend=self.protocol)

    def __init__(self, *, timeout: float = 2.0, motion_timeout: float = 120.0, retries: int = 3,
                 backoff_s: float = 0.05, backoff_max_s: float = 1.0, robot: str = "IRB1400",
                 postures: npt.ArrayLike | None = None, max_tool_mass_kg: float = 5.0, idle_timeout: float = 5.0, write_key: str | None = None):
        self.timeout = check_timeout("timeout", timeout)
        self.idle_timeout = check_timeout("idle_timeout", idle_timeout)
        self._write_key = check_write_key(write_key)
        self.motion_timeout = check_timeout("motion_timeout", motion_timeout)
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise InvalidRequest(f"retries must be an integer >= 0; got {retries!r}")
        self.retries = retries
        self.backoff_s = check_timeout("backoff_s", backoff_s)
        self.backoff_max_s = check_timeout("backoff_max_s", backoff_max_s)
        try:
            robot_model(robot)
        except ValueError as exc:
            raise InvalidRequest(str(exc)) from None
        self.robot = robot
        if not isinstance(max_tool_mass_kg, (int, float)) or not 0 < max_tool_mass_kg < float("inf"):
            raise InvalidRequest(f"max_tool_mass_kg must be a positive number of kg; got {max_tool_mass_kg!r}")
        self.max_tool_mass_kg = float(max_tool_mass_kg)
        self.postures = None
        if postures is not None:
            plan = np.asarray(postures, dtype=float)
            if plan.ndim != 2:
                raise InvalidRequest(f"postures must be a list of joint-angle rows; got shape {plan.shape}")
            self.postures = np.array([check_joints(row, robot, f"planned posture {i}") for i, row in enumerate(plan, 1)])
        self._info: ControllerInfo | None = None
        self._lock = threading.RLock()  # one exchange at a time when threads share a controller
        #: Counters for diagnostics and tests.
        self.reconnects = 0

    # ------------------------------------------------------------------ lifecycle
    @property
    @abstractmethod
    def address(self) -> str:
        """Where the controller is (``host:port``, serial URL)."""

    @property
    @abstractmethod
    def is_connected(self) -> bool:
        """True while the link is open."""

    @abstractmethod
    def _open(self, deadline: Deadline) -> None:
        """Open the link and check the controller (raise LinkDown if it cannot be reached)."""

    @abstractmethod
    def _drop(self) -> None:
        """Close the link at once, without talking to the controller."""

    def _goodbye(self) -> None:
        """Tell the controller the session ends (best effort, short)."""

    def connect(self, timeout: float | None = None) -> "Controller":
        """Open the link (with retries and back-off) and read the controller's identity."""
        if not self.is_connected:
            self._call("connect", lambda d: None, timeout)
        return self

    def close(self) -> None:
        """Say goodbye (best effort) and close the link. Safe to call twice."""
        if self.is_connected:
            try:
                self._goodbye()
            except Exception as exc:  # closing must not fail
                log.debug("goodbye to %s failed: %s", self.address, exc)
        self._drop()

    def __enter__(self) -> "Controller":
        return self.connect()

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "connected" if self.is_connected else "closed"
        return f"<{type(self).__name__} {self.address} {state}>"

    # ------------------------------------------------------------------ the retry loop
    def _budget(self, timeout: float | None) -> Deadline:
        return Deadline(self.timeout if timeout is None else check_timeout("timeout", timeout))

    def _call(self, what: str, operation: Callable[[Deadline], T], timeout: float | None = None,
              deadline: Deadline | None = None) -> T:
        """Run ``operation(deadline)``; reconnect with back-off if the link drops, within the budget."""
        deadline = deadline or self._budget(timeout)
        with self._lock:
            return self._retry(what, operation, deadline)

    def _retry(self, what: str, operation: Callable[[Deadline], T], deadline: Deadline) -> T:
        delay = self.backoff_s
        failures = 0
        while True:
            try:
                if not self.is_connected:
                    # The request may wait in the server's backlog until its idle timeout frees it
                    # from a silent client (a PC that lost power): allow for that when connecting.
                    deadline.extend(self.idle_timeout + self.timeout)
                    self._open(deadline)
                return operation(deadline)
            except LinkDown as exc:
                self._drop()
                failures += 1
                left = deadline.remaining()
                if failures > self.retries or left <= delay:
                    raise self.connection_error(
                        f"{what}: no link to the controller at {self.address} ({exc}) after {failures} attempt(s) "
                        f"in {time.monotonic() - deadline.start:.1f} s; {self.unreachable_hint}") from None
                log.info("%s: link to %s down (%s); reconnecting in %.3f s", what, self.address, exc, delay)
                time.sleep(delay)
                delay = min(2 * delay, self.backoff_max_s)
                self.reconnects += 1
            except ProtocolError:
                self._drop()  # the stream is out of step: start clean next time
                raise

    # ------------------------------------------------------------------ reading
    def info(self, timeout: float | None = None) -> ControllerInfo:
        """Protocol version, program name and number of approved postures (read at connect)."""
        self.connect(timeout)
        assert self._info is not None
        return self._info

    @abstractmethod
    def ping(self, timeout: float | None = None) -> float:
        """Round-trip time of one request, seconds."""

    @abstractmethod
    def read_joints(self, timeout: float | None = None) -> np.ndarray:
        """Controller axis angles (``CJointT``), degrees, shape (6,)."""

    @abstractmethod
    def read_tool0_pose(self, timeout: float | None = None) -> FlangePose:
        """tool0 in base (``CRobT(\\Tool:=tool0 \\WObj:=wobj0)``)."""

    @abstractmethod
    def status(self, timeout: float | None = None) -> ControllerStatus:
        """The program's state and current posture."""

    # ------------------------------------------------------------------ motion
    def check_posture(self, k: int, expected_joints: npt.ArrayLike | None = None) -> int:
        """Validate a posture request on the PC (index, plan, joint limits); returns the index."""
        count = self._info.postures if self._info is not None else None
        k = check_posture_index(k, count)
        if self.postures is not None:
            if k > len(self.postures):
                raise InvalidRequest(f"posture {k} is not in the plan of {len(self.postures)} postures; nothing was sent")
            check_joints(self.postures[k - 1], self.robot, f"posture {k}")
        if expected_joints is not None:
            check_joints(expected_joints, self.robot, f"posture {k}")
        return k

    def goto_posture(self, k: int, *, expected_joints: npt.ArrayLike | None = None, wait: bool = True,
                     timeout: float | None = None) -> ControllerStatus | None:
        """Move to approved posture ``k`` (1-based) with ``MoveAbsJ ... fine``.

        Parameters
        ----------
        k : int
            Index into the postures embedded in the RAPID program.
        expected_joints : array-like, shape (dof,), optional
            The joint angles the PC expects at ``k``: refused if outside the joint limits.
        wait : bool
            Return only when the robot stands still at ``k`` (default); else return None as soon as
            the request is sent (a single-task RAPID program answers the next request only after
            the move; :meth:`wait_at_rest` waits for it).
        timeout : float, optional
            Budget for the whole call (default: ``motion_timeout`` when waiting, else ``timeout``).

        Raises
        ------
        InvalidRequest
            Before anything is sent: bad index, posture outside the joint limits, NaN.
        ControllerRefused
            The program refused (busy: the previous posture is not acknowledged).
        """
        k = self.check_posture(k, expected_joints)  # before anything is sent
        budget = self._budget(timeout if timeout is not None else (self.motion_timeout if wait else None))
        if not self.is_connected:
            self._call("connect", lambda d: None, deadline=budget)
        k = self.check_posture(k)  # against the program's posture count, read at connect
        self._request_posture(k, budget)
        if not wait:
            return None
        return self.wait_at_rest(k, deadline=budget)

    @abstractmethod
    def _request_posture(self, k: int, deadline: Deadline) -> None:
        """Send the move request (the RAPID program checks it once more)."""

    @abstractmethod
    def wait_at_rest(self, k: int | None = None, timeout: float | None = None, *,
                     deadline: Deadline | None = None) -> ControllerStatus:
        """Wait until the robot stands still (at posture ``k`` if given) and return the status.

        The default budget is ``motion_timeout``.
        """

    @abstractmethod
    def acknowledge(self, k: int, timeout: float | None = None) -> ControllerStatus:
        """Tell the program the PC is done at posture ``k`` (images grabbed); returns the status."""

    # ------------------------------------------------------------------ tool data
    def set_tool(self, tool: ToolData, timeout: float | None = None) -> ToolData:
        """Write the camera's tool data to the program's ``PERS tooldata`` and read it back.

        Returns the tool data read back. Refused before anything is sent: NaN, a non-unit quaternion,
        a tool frame over 1 m from the flange, a mass <= 0 or above ``max_tool_mass_kg``, no
        ``write_key``. The key goes first (``KEY`` request / ``tool_key`` register), in the same
        exchange as the tool parts, so a retry after a dropped link repeats it too.

        Raises
        ------
        InvalidRequest
            Bad tool data, or no write key configured (nothing sent).
        ControllerRefused
            The controller refused the key (code 9) or the tool data (code 6).
        ControllerError
            When the value read back differs from the one written.
        """
        tool = check_tooldata(tool, self.max_tool_mass_kg)
        if self._write_key is None and self.writes_need_key:
            raise InvalidRequest(f"cannot write tool data to {self.address} without the station's write key: set "
                                 "controller.write_key in the station config and load HeKey.sys on the controller "
                                 "(handeye rapid generate --config STATION.yaml -o DIR writes it); nothing was sent")
        deadline = self._budget(timeout)
        self._write_tool(tool, deadline)
        back = self.read_tool(timeout=max(deadline.remaining(), 1e-3))
        if not back.close_to(tool):
            raise ControllerError(f"tool data read back from {self.address} differs from what was written: "
                                  f"wrote {tool.values()}, read {back.values()}")
        return back

    @abstractmethod
    def _write_tool(self, tool: ToolData, deadline: Deadline) -> None:
        """Send validated tool data."""

    @abstractmethod
    def read_tool(self, timeout: float | None = None) -> ToolData:
        """The program's camera tool data."""

    # ------------------------------------------------------------------ the guided program
    def guide(self, verdict: int, hint: int, timeout: float | None = None) -> int:
        """Guided program (``src/handeye/rapid/guided.py``): the PC's verdict on the posture offered last and the next
        hint (codes of ``rapid.guided``); the pendant then prompts the operator. Returns the number of
        postures the operator offered so far.

        Raises
        ------
        ControllerRefused
            The link has no guided program (this base class: Robot Web Services guides with no program), or
            the program is not waiting for a verdict.
        """
        raise self.refused_error(f"the {self.protocol} link has no guided program: capture --guided reads the "
                                 "joints while the operator jogs")

    def wait_operator(self, timeout: float) -> ControllerStatus | None:
        """Guided program: wait up to ``timeout`` s for the operator: ``AT k`` (Start pressed after jogging to
        the k-th posture offered) or ``DONE``; None when the operator is still at the pendant.

        Over a line the program answers nothing while it prompts or is stopped (a single-task program):
        the request waits, and a reply arriving after ``timeout`` is skipped by its id later.
        """
        raise self.refused_error(f"the {self.protocol} link has no guided program")


def open_controller(name: str, *, connect: bool = True, **options: Any) -> Controller:
    """A controller back end by name (any registered one: :data:`~.backends.CONTROLLERS`), connected
    unless ``connect=False``.

    Options are the back end's keyword arguments (``host``, ``port``, ``url``, ``register_map``,
    ``timeout`` ...) plus those of :class:`Controller`. The names come from
    :data:`~handeye.drivers.controller.backends.CONTROLLERS`.

    Raises
    ------
    InvalidRequest
        Unknown back-end name or option.
    ControllerError
        The controller cannot be reached.
    """
    from .backends import CONTROLLERS

    try:
        backend = CONTROLLERS[name]
    except KeyError:
        raise InvalidRequest(CONTROLLERS.unknown(name)) from None
    cls = backend.load()
    try:
        controller = cls(**options)
    except TypeError as exc:
        raise InvalidRequest(f"{name} controller: {exc}") from None
    if connect:
        controller.connect()
    return controller


def read_robot_state(controller: Controller, timeout: float | None = None) -> dict:
    """``{"joints_deg": [...], "tool0_in_base": {"position_mm": [...], "quaternion_wxyz": [...]}}``."""
    joints = controller.read_joints(timeout=timeout)
    pose = controller.read_tool0_pose(timeout=timeout)
    return {"joints_deg": [float(v) for v in joints], "tool0_in_base": pose.to_json()}
