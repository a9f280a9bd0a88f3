"""What the links that poll the RAPID program's state share (Modbus registers, RWS persistent data):
waiting until the robot stands still after a posture request.

The program publishes its state (READY, MOVING, AT, LATE, ACKED, ERROR), the posture and an error
code; the PC writes a request and polls. A back end mixes :class:`PolledHandshake` in before
:class:`~handeye.drivers.controller.interface.Controller` and provides ``_wait_for(what, done,
deadline) -> raw`` (poll ``{"state", "posture", "error"}`` until ``done(raw)``), ``_clear_request``
and ``_requested`` (the posture asked for and not yet acknowledged, 0 for none).
"""

from __future__ import annotations

from .interface import Deadline
from .protocol import E_STATE, ERROR_CODES
from .types import ERROR, MOVING, READY, ControllerStatus, check_timeout

__all__ = ["PolledHandshake"]


class PolledHandshake:
    """``wait_at_rest`` over a polled state (see the module docstring)."""

    _requested = 0

    def wait_at_rest(self, k=None, timeout=None, *, deadline=None) -> ControllerStatus:
        deadline = deadline or Deadline(self.motion_timeout if timeout is None else check_timeout("timeout", timeout))
        pending = self._requested if (k is None or k == self._requested) else 0

        def done(raw):
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
