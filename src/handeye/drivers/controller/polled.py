"""What the links that poll the RAPID program's state share (Modbus registers, RWS persistent data):
waiting until the robot stands still after a posture request.

The program publishes its state (READY, MOVING, AT, LATE, ACKED, ERROR), the posture and an error
code; the PC writes a request and polls. A back end mixes :class:`PolledHandshake` in before
:class:`~handeye.drivers.controller.interface.Controller` and provides ``_raw_status(deadline) ->
raw`` (``{"state", "posture", "error"}``), ``_wait_for(what, done, deadline) -> raw`` (poll until
``done(raw)``), ``_clear_request``, and how it writes: ``_send_request(k, deadline)`` and
``_send_acknowledgement(k, raw, deadline)``. ``_requested`` is the posture asked for and not yet
acknowledged (0 for none).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from .interface import Controller, Deadline
from .protocol import E_BUSY, E_STATE, ERROR_CODES
from .types import ACKED, AT, ERROR, LATE, MOVING, READY, ControllerStatus, check_posture_index, check_timeout

__all__ = ["PolledHandshake"]

# For the type checker only: the mixin's methods run on a Controller (it is mixed in before Controller);
# at run time its base is object, so the back end's own base list alone makes its method order.
_Host = Controller if TYPE_CHECKING else object


class PolledHandshake(_Host):
    """Posture requests, waits and acknowledgements over a polled state (see the module docstring)."""

    _requested = 0

    if TYPE_CHECKING:  # what the back end provides (see the module docstring)
        def _raw_status(self, deadline: Deadline) -> dict: ...

        def _wait_for(self, what: str, done: Callable[[dict], bool], deadline: Deadline) -> dict: ...

        def _clear_request(self, deadline: Deadline) -> None: ...

        def _send_request(self, k: int, deadline: Deadline) -> None: ...

        def _send_acknowledgement(self, k: int, raw: dict, deadline: Deadline) -> None: ...

    def _request_posture(self, k: int, deadline: Deadline) -> None:
        raw = self._call("read status", self._raw_status, deadline=deadline)
        if raw["state"] in (ACKED, ERROR):
            self._clear_request(deadline)
            raw = self._call("read status", self._raw_status, deadline=deadline)
        if raw["state"] in (AT, LATE, MOVING) and raw["posture"] == k:
            self._requested = k  # already there or on the way (a repeated request)
            return
        if raw["state"] != READY:
            raise self.refused_error(f"robot at {self.address} is busy ({raw['state']} at posture {raw['posture']}): "
                                     f"acknowledge posture {raw['posture']} first", E_BUSY)
        self._send_request(k, deadline)
        self._requested = k

    def acknowledge(self, k: int, timeout: float | None = None) -> ControllerStatus:
        k = check_posture_index(k)
        deadline = self._budget(timeout)
        raw = self._call("read status", self._raw_status, deadline=deadline)
        if raw["posture"] != k or raw["state"] not in (AT, LATE, ACKED, READY):
            raise self.refused_error(f"cannot acknowledge posture {k}: robot is {raw['state']} at posture "
                                     f"{raw['posture']}", E_STATE)
        self._send_acknowledgement(k, raw, deadline)
        self._requested = 0
        return self.status(timeout=max(deadline.remaining(), 1e-3))

    def wait_at_rest(self, k: int | None = None, timeout: float | None = None, *,
                     deadline: Deadline | None = None) -> ControllerStatus:
        deadline = deadline or Deadline(self.motion_timeout if timeout is None else check_timeout("timeout", timeout))
        pending = self._requested if (k is None or k == self._requested) else 0

        def done(raw: dict) -> bool:
            if raw["state"] == ERROR:
                return True
            if raw["state"] == READY:
                return not pending  # a request not yet picked up by the robot reads READY too
            return raw["state"] != MOVING

        raw = self._wait_for("wait for the robot" if k is None else f"wait for posture {k}", done, deadline)
        if raw["state"] == ERROR:
            code = raw["error"]
            self._clear_request(deadline)
            raise self.refused_error(f"robot at {self.address} refused posture {pending or k}: "
                                     f"{ERROR_CODES.get(code, 'error')} (error {code})", code)
        status = ControllerStatus(raw["state"], raw["posture"])
        if k is not None and not status.at_posture(k):
            raise self.refused_error(f"robot is {status.state} at posture {status.posture}, not at posture {k}", E_STATE)
        return status
