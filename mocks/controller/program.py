"""The logic of the generated RAPID program (``HeMain`` + a link module), run on a simulated robot.

Both mock servers drive this one state machine, as the socket, serial and I/O link modules all
call the same ``HeMain`` in RAPID: a posture request is accepted only when READY, the robot moves
with ``MoveAbsJ ... fine`` to an *approved* posture, then stands AT it until the PC acknowledges
(LATE once ``ack_timeout_s`` has passed; the robot never moves on by itself). Tool data are
checked like the RAPID module does before they replace the ``PERS tooldata``.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ...drivers.controller import protocol as P
from ...drivers.controller.types import ACKED, AT, ERROR, LATE, MOVING, READY, ToolData
from ..robot import ZoneViolation

__all__ = ["RapidProgram", "ProgramRefusal"]


class ProgramRefusal(Exception):
    """What the RAPID program answers with ERR ``code`` (or the Modbus error registers)."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


class RapidProgram:
    """State machine of the RAPID program.

    Parameters
    ----------
    robot : SimulatedRobot
    ack_timeout_s : float or None
        After this long at a posture without acknowledgement the state turns LATE (None: never).
    name : str
        Program name in the VERSION reply.
    """

    def __init__(self, robot, ack_timeout_s: float | None = 30.0, name: str = "MOCK"):
        self.robot = robot
        self.ack_timeout_s = ack_timeout_s
        self.name = name
        self._lock = threading.RLock()
        self._state = READY
        self._posture = 0
        self._arrived_at = 0.0
        self.error_code = 0

    @property
    def count(self) -> int:
        return len(self.robot.postures)

    def _advance(self) -> None:
        if self._state == MOVING and not self.robot.is_moving:
            self._state, self._arrived_at = AT, time.monotonic()
        if (self._state == AT and self.ack_timeout_s is not None
                and time.monotonic() - self._arrived_at > self.ack_timeout_s):
            self._state = LATE

    def status(self) -> tuple[str, int]:
        """``(state, posture)`` now."""
        with self._lock:
            self._advance()
            return self._state, self._posture

    def request(self, k: int) -> bool:
        """A request to move to posture ``k``; True if a move started (False: already there/going).

        Raises
        ------
        ProgramRefusal
            E_RANGE (not an approved posture), E_BUSY (moving elsewhere / not acknowledged) or E_FAULT
            (the path enters a volume of the cell: a world zone stops the arm; it did not move).
        """
        with self._lock:
            self._advance()
            if not 1 <= k <= self.count:
                raise ProgramRefusal(P.E_RANGE, f"posture {k} not approved (1..{self.count})")
            if self._state in (AT, LATE, MOVING):
                if k == self._posture:
                    return False
                raise ProgramRefusal(P.E_BUSY, f"busy: acknowledge posture {self._posture} first")
            if self._state != READY:
                raise ProgramRefusal(P.E_BUSY, f"busy: state {self._state}")
            try:
                self.robot.start_posture(k)
            except ZoneViolation as refusal:
                raise ProgramRefusal(P.E_FAULT, str(refusal)) from None
            self._state, self._posture, self.error_code = MOVING, k, 0
            return True

    def wait_move(self, stop: threading.Event | None = None) -> None:
        """Block until the current move ends (what a single-task RAPID program does after GOTO)."""
        self.robot.wait_until_stopped(stop=stop)
        with self._lock:
            self._advance()

    def acknowledge(self, k: int) -> None:
        """The PC is done at posture ``k`` (line protocol ACK): back to READY."""
        with self._lock:
            self._advance()
            if self._state in (AT, LATE) and k == self._posture:
                self._state = READY
                return
            if self._state == READY and k == self._posture:
                return  # repeated ACK
            raise ProgramRefusal(P.E_STATE, f"not at posture {k} (state {self._state} at {self._posture})")

    # -- the Modbus handshake's extra states
    def mark_acked(self) -> None:
        with self._lock:
            self._advance()
            if self._state in (AT, LATE):
                self._state = ACKED

    def mark_ready(self) -> None:
        with self._lock:
            if self._state in (ACKED, ERROR):
                self._state = READY

    def mark_error(self, code: int) -> None:
        with self._lock:
            self._state, self.error_code = ERROR, code

    # -- tool data
    def apply_tool(self, tool: ToolData) -> ToolData:
        """Check tool data as the RAPID module does and store it in the PERS tooldata."""
        p, q, m, c = tool.as_arrays()
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(q)) and np.isfinite(m) and np.all(np.isfinite(c))):
            raise ProgramRefusal(P.E_TOOL, "tool data not finite")
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > 1e-4:
            raise ProgramRefusal(P.E_TOOL, f"tool quaternion not unit (norm {norm:.6f})")
        if not m > 0:
            raise ProgramRefusal(P.E_TOOL, "tool mass must be > 0")
        if float(np.linalg.norm(p)) > 1000.0:
            raise ProgramRefusal(P.E_TOOL, "tool frame over 1000 mm from the flange")
        q = q / norm
        if q[0] < 0:
            q = -q
        stored = ToolData(tuple(map(float, p)), tuple(map(float, q)), float(m), tuple(map(float, c)))
        self.robot.tool = stored
        return stored
