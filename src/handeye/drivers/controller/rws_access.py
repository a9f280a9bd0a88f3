"""Write access of the ``rws`` back end (a mixin of :class:`~handeye.drivers.controller.rws_client.RwsController`):
every write inside a mastership request/release, and in manual mode the "Request Manual Mode
Privileges" grant (RMMP) the operator gives by pressing Allow on the FlexPendant."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

from .errors import ControllerRefused
from .interface import Deadline, LinkDown
from .rws_http import RMMP_HINT, RwsHttp

__all__ = ["RwsAccess"]

log = logging.getLogger("handeye.drivers.controller.rws_client")

T = TypeVar("T")

# For the type checker only: the mixin's methods use RwsHttp's (RwsController mixes both in); at run time
# its base is object, so RwsController's own base list alone makes its method order.
_Host = RwsHttp if TYPE_CHECKING else object


class RwsAccess(_Host):
    """Mastership and RMMP (see the module docstring)."""

    # Set by RwsController.__init__.
    poll_s: float
    rmmp_timeout: float

    def _mastership(self, action: str, deadline: Deadline) -> None:
        path = f"/rw/mastership?action={action}" if self.generation == 1 else f"/rw/mastership/edit/{action}"
        self._request("POST", path, deadline, data={}, what=f"mastership {action}")

    def _as_master(self, what: str, write: Callable[[Deadline], T], deadline: Deadline) -> T:
        """``write(deadline)`` inside a mastership request/release; in manual mode, where the controller
        refuses mastership without RMMP, the grant is asked for (the operator presses Allow) first."""
        try:
            self._mastership("request", deadline)
        except ControllerRefused as exc:
            if exc.code != 403 or RMMP_HINT not in str(exc):
                raise
            self._grant_rmmp(deadline)
            self._mastership("request", deadline)
        try:
            return write(deadline)
        finally:
            try:
                self._mastership("release", Deadline(max(deadline.remaining(), min(self.timeout, 0.5))))
            except LinkDown as exc:  # the session keeps it; the next request (or the next write) frees it
                log.info("%s: releasing mastership at %s failed: %s", what, self.address, exc)

    def _grant_rmmp(self, deadline: Deadline) -> None:
        """Ask for Request Manual Mode Privileges and wait for the operator's Allow (within the budget)."""
        state = self._get("/users/rmmp", deadline, "read RMMP").get("privilege", "none")
        if str(state).lower() == "modify":
            return
        self._request("POST", "/users/rmmp", deadline, data={"privilege": "modify"}, what="request RMMP")
        log.warning("%s is in manual mode: %s", self.address, RMMP_HINT)
        wait = Deadline(min(self.rmmp_timeout, max(deadline.remaining(), 1e-3)))
        poll = "/users/rmmp/poll" if self.generation == 1 else "/users/rmmp"
        while True:
            answer = self._get(poll, deadline, "poll RMMP")
            status = str(answer.get("status") or answer.get("privilege") or "").lower()
            if status in ("granted", "modify"):
                return
            if status in ("denied", "rejected"):
                raise self.refused_error(f"{self.address} is in manual mode and the operator denied write access "
                                         "(RMMP); ask again and press Allow on the FlexPendant", 403)
            if wait.remaining() <= self.poll_s:
                raise self.timeout_error(f"{self.address} is in manual mode: waited {wait.seconds:g} s for write access "
                                         f"(RMMP); {RMMP_HINT}")
            time.sleep(self.poll_s)
