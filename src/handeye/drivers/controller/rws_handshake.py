"""The posture handshake of the ``rws`` back end (a mixin of
:class:`~handeye.drivers.controller.rws_client.RwsController`): the Modbus one (src/handeye/rapid/PROTOCOL.md)
with PERS data instead of registers. The PC writes ``heRwsPc`` (``[request, grabbed]``), the
program publishes ``heRwsLink`` (``[state, posture, error, count, version]``)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from .interface import Deadline
from .protocol import E_STATE
from .rws_access import RwsAccess
from .types import ACKED, AT, ERROR, LATE, MOVING, READY, ControllerStatus

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["RwsHandshake", "STATE_NAMES"]

#: ``heRwsLink{1}`` values (HeMain's HE_READY ...).
STATE_NAMES = {0: READY, 1: MOVING, 2: AT, 3: LATE, 4: ACKED, 5: ERROR}

# For the type checker only: the mixin's methods use RwsAccess's and RwsHttp's (RwsController mixes them
# in); at run time its base is object, so RwsController's own base list alone makes its method order.
_Host = RwsAccess if TYPE_CHECKING else object


class RwsHandshake(_Host):
    """What :class:`~handeye.drivers.controller.polled.PolledHandshake` needs over RWS: the state, the
    request and the acknowledgement written under mastership, and the check that the program runs."""

    # Set by RwsController.__init__.
    link_module: str

    def _raw_status(self, deadline: Deadline) -> dict:
        values = self._symbol_value(self.link_module, "heRwsLink", deadline)
        try:
            code, posture, error = (int(v) for v in values[:3])
        except (TypeError, ValueError):
            raise self.protocol_error(f"heRwsLink at {self.address} holds {values}") from None
        if code not in STATE_NAMES:
            raise self.protocol_error(f"heRwsLink at {self.address} holds state {code}, not a known state")
        return {"state": STATE_NAMES[code], "posture": posture, "error": error}

    def status(self, timeout: float | None = None) -> ControllerStatus:
        raw = self._call("read status", self._raw_status, timeout)
        return ControllerStatus(raw["state"], raw["posture"])

    def check_posture(self, k: int, expected_joints: npt.ArrayLike | None = None) -> int:
        if self._info is not None and self._info.postures == 0:
            raise self.refused_error(f"no handeye program runs in {self.task} at {self.address} ({self._info.program}): "
                                     "handeye capture loads it over RWS, or load HeMain, HeRws and HeTool and start "
                                     "it", E_STATE)
        return super().check_posture(k, expected_joints)

    def _write_pc(self, what: str, request: int, grabbed: int, deadline: Deadline) -> None:
        self._call(what, lambda d: self._as_master(
            what, lambda d2: self._set_symbol(self.link_module, "heRwsPc", [request, grabbed], d2), d), deadline=deadline)

    def _check_running(self, deadline: Deadline, what: str) -> None:
        """Refuse with the reason when the robot cannot run the program (motors off, program stopped)."""
        state = self._call(what, lambda d: (
            self._get("/rw/panel/ctrlstate" if self.generation == 1 else "/rw/panel/ctrl-state", d),
            self._get("/rw/rapid/execution", d)), deadline=deadline)
        ctrl, execution = state[0].get("ctrlstate"), state[1].get("ctrlexecstate")
        if ctrl != "motoron":
            raise self.refused_error(f"{what}: the motors of {self.address} are off ({ctrl}): switch them on "
                                     "(FlexPendant or the motors-on button) and start the program", E_STATE)
        if execution != "running":
            raise self.refused_error(f"{what}: the RAPID program at {self.address} is {execution}: start it "
                                     "(handeye loads and starts it with the capture, or press Play)", E_STATE)

    def _wait_for(self, what: str, done: Callable[[dict], bool], deadline: Deadline) -> dict:
        while True:
            raw = self._call(what, self._raw_status, deadline=deadline)
            if done(raw):
                return raw
            if deadline.remaining() <= self.poll_s:
                self._check_running(Deadline(min(self.timeout, 1.0)), what)
                raise self.timeout_error(f"{what}: robot is {raw['state']} at posture {raw['posture']} after "
                                         f"{deadline.seconds:g} s")
            time.sleep(self.poll_s)

    def _clear_request(self, deadline: Deadline) -> None:
        self._write_pc("clear the request", 0, 0, deadline)
        self._requested = 0
        self._wait_for("wait for READY", lambda r: r["state"] == READY, deadline)

    def _send_request(self, k: int, deadline: Deadline) -> None:
        self._check_running(deadline, f"request posture {k}")
        self._write_pc(f"request posture {k}", k, 0, deadline)

    def _send_acknowledgement(self, k: int, raw: dict, deadline: Deadline) -> None:
        if raw["state"] in (AT, LATE):
            # HeRws clears heRwsPc itself once it has seen the acknowledgement: READY follows
            self._write_pc(f"acknowledge posture {k}", k, 1, deadline)
            self._wait_for("wait for READY", lambda r: r["state"] == READY, deadline)
        elif raw["state"] == ACKED:
            self._clear_request(deadline)
