"""The ``rws`` back end: ABB Robot Web Services, RWS 1.0 (RobotWare 6) and RWS 2.0 (RobotWare 7).

No custom server runs on the controller for reads: joints and the flange pose come from the motion
system (``/rw/motionsystem/mechunits/ROB_1/jointtarget`` and ``robtarget?tool=tool0&wobj=wobj0``),
the camera tool data is the ``PERS tooldata`` of HeTool read and written by symbol. Only the posture
sequencing runs in RAPID (``HeRws``): the PC writes ``heRwsPc`` (``[request, grabbed]``), the program
publishes ``heRwsLink`` (``[state, posture, error, count, version]``); the handshake is the Modbus
one (src/handeye/rapid/PROTOCOL.md) with PERS data instead of registers.

The generation is detected from the controller: an unauthenticated ``GET /rw/system`` is answered
with a Digest challenge by RWS 1.0 and a Basic one by RWS 2.0, and the RobotWare version read next
confirms it (6.x: RWS 1.0, 7.x: RWS 2.0).

- RWS 1.0: HTTP (port 80), Digest authentication, session cookies (``-http-session-``, ``ABBCX``),
  ``?json=1`` answers (``_embedded._state``), actions as ``?action=...``.
- RWS 2.0: HTTPS (port 443) with the controller's self-signed certificate pinned by its SHA-256
  fingerprint (``controller.tls_fingerprint``), Basic authentication, ``Accept:
  application/hal+json;v=2.0`` (answers under ``state``), actions as path segments
  (``/rw/mastership/edit/request``, ``/rw/rapid/execution/start``), symbol data at
  ``/rw/rapid/symbol/RAPID/T_ROB1/<module>/<name>/data``.

Every write (posture request, acknowledgement, tool data, program load/start/stop) is done inside a
mastership request/release; in manual mode the remote client first needs the "Request Manual Mode
Privileges" grant (RMMP), which the operator gives by pressing Allow on the FlexPendant. Requests are
paced below the controller's documented ceiling (``max_rate``, 20 requests/s by default, with a
short burst). HTTP errors become the shared kinds with the controller's own message: 401 (wrong user
or password) and 403 (mastership held elsewhere, RMMP missing) are :class:`ControllerRefused`, 503
(busy) is retried with back-off within the call's budget and then a :class:`ControllerTimeout`.

Tool writes are authorised by the controller's own users (the RWS account), not by the station's
write key, which never travels over RWS (see the threat model, docs/security.md).

Modules: ``rws_transport`` (pacing, TLS pinning), ``rws_http`` (requests, authentication, errors,
answers, symbols), ``rws_access`` (mastership, RMMP), ``rws_codec`` (RAPID values), ``rws_handshake``
(the posture handshake), ``rws_program`` (loading the program); this one is the link and the reads.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import ControllerRefused, InvalidRequest
from .interface import Controller, Deadline, LinkDown
from .polled import PolledHandshake
from .protocol import PROTOCOL_VERSION
from .rws_access import RwsAccess
from .rws_codec import tool_of_value, tooldata_value
from .rws_handshake import RwsHandshake
from .rws_http import HAL_JSON, RwsHttp
from .rws_program import RwsProgram
from .rws_transport import RateLimiter, close_session
from .types import ControllerInfo, FlangePose, ToolData, check_fingerprint, check_timeout

__all__ = ["RwsController", "SIMULATION_SYSTEM_NAME"]

#: The system name a simulation answers ``GET /rw/system`` with (``handeye mock controller`` announces itself so):
#: a controller of that name is :attr:`RwsController.simulated`.
SIMULATION_SYSTEM_NAME = "handeye-mock"


class RwsController(RwsHandshake, RwsProgram, RwsAccess, RwsHttp, PolledHandshake, Controller):
    """An IRC5 (RobotWare 6) or OmniCore (RobotWare 7) controller through Robot Web Services.

    Parameters
    ----------
    host : str
    port : int, optional
        Default 80 (RWS 1.0, HTTP) or 443 (with ``tls_fingerprint``: RWS 2.0, HTTPS).
    username, password : str
        The controller user (RobotWare's default account is ``Default User`` / ``robotics``;
        give the station a user of its own).
    generation : str or int
        ``auto`` (detect), 1 (RWS 1.0) or 2 (RWS 2.0).
    tls_fingerprint : str, optional
        SHA-256 of the controller's certificate (64 hex digits, colons allowed): HTTPS with the
        certificate pinned. Without it the link is plain HTTP (RWS 1.0).
    task, mechunit : str
        The RAPID task and the mechanical unit (``T_ROB1``, ``ROB_1``).
    tool_name, tool_module : str
        The camera's ``PERS tooldata`` and its module (``tHeCamera`` in ``HeTool``).
    link_module : str
        The module of the handshake data (``HeRws``).
    max_rate : float
        Requests per second at most, on average (ABB documents about 20).
    poll_s : float
        Pause between status reads while waiting for the robot.
    rmmp_timeout : float
        How long to wait for the operator's Allow in manual mode (seconds).
    **options
        See :class:`~handeye.drivers.controller.interface.Controller` (``write_key`` is accepted and
        not used: RWS authorises writes by its users).
    """

    #: No RAPID program serves RWS: the controller's web server does.
    unreachable_hint = ("check the address/port (RobotWare 6: HTTP, port 80; RobotWare 7: HTTPS, port 443 with "
                        "controller.tls_fingerprint) and that this PC reaches the controller's Robot Web Services")

    protocol = "rws"
    writes_need_key = False

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, *, username: str = "Default User",
                 password: str = "robotics", generation: str | int = "auto", tls_fingerprint: str | None = None,
                 task: str = "T_ROB1", mechunit: str = "ROB_1", tool_name: str = "tHeCamera",
                 tool_module: str = "HeTool", link_module: str = "HeRws", max_rate: float = 20.0,
                 poll_s: float = 0.02, rmmp_timeout: float = 60.0, **options: Any):
        if port is not None and (isinstance(port, bool) or not isinstance(port, int) or not 0 < port < 65536):
            raise InvalidRequest(f"TCP port must be an integer 1..65535; got {port!r}")
        if str(generation).lower() not in ("auto", "1", "2"):
            raise InvalidRequest(f"RWS generation must be auto, 1 or 2; got {generation!r}")
        if tls_fingerprint is not None:
            tls_fingerprint = check_fingerprint(tls_fingerprint)
        self.host = str(host)
        self.https = tls_fingerprint is not None
        self.port = int(port) if port is not None else (443 if self.https else 80)
        self.username, self._password = str(username), str(password)
        self.requested_generation = str(generation).lower()
        self.tls_fingerprint = tls_fingerprint
        self.task, self.mechunit = task, mechunit
        self.tool_name, self.tool_module, self.link_module = tool_name, tool_module, link_module
        if not (isinstance(max_rate, (int, float)) and max_rate > 0):
            raise InvalidRequest(f"max_rate must be a positive number of requests per second; got {max_rate!r}")
        self.limiter = RateLimiter(max_rate)
        self.poll_s = check_timeout("poll_s", poll_s)
        self.rmmp_timeout = check_timeout("rmmp_timeout", rmmp_timeout)
        super().__init__(**options)
        self.generation: int | None = None
        self.robotware: str | None = None
        #: The controller's system name (``GET /rw/system``), once connected.
        self.system_name: str | None = None
        self._http = None
        self._connected = False
        self._requested = 0
        #: Requests sent (for diagnostics and tests) and 503 answers met.
        self.requests = 0
        self.busy_answers = 0

    @property
    def is_connected(self) -> bool:
        return self._connected

    def _open(self, deadline: Deadline) -> None:
        try:
            self._identify(deadline)
        except LinkDown:
            raise  # the session (its cookies: mastership) is kept for the retry
        except BaseException:
            self._connected = False
            if self._http is not None:  # refused, garbage, timeout: close the sockets now
                close_session(self._http)
                self._http = None
            raise

    def _identify(self, deadline: Deadline) -> None:
        self._session()
        if self.generation is None:
            self.generation = self._detect(deadline)
        self._connected = True
        try:
            state = self._symbol_value(self.link_module, "heRwsLink", deadline)
        except ControllerRefused as exc:
            if exc.code != 404:
                raise
            # No handeye program in the task yet: reading works, and load_program can install it.
            self._info = ControllerInfo(PROTOCOL_VERSION, f"none ({self.link_module} not loaded)", 0)
            return
        version, count = int(state[4]), int(state[3])
        if version == 0:  # loaded, HeLinkOpen has not run (stopped, or its start failed): reading still works
            self._info = ControllerInfo(PROTOCOL_VERSION, f"none ({self.link_module} loaded, not started)", 0)
            return
        if version != PROTOCOL_VERSION:
            self._connected = False
            raise self.protocol_error(
                f"{self.link_module}.heRwsLink at {self.address} says protocol version {version}, expected "
                f"{PROTOCOL_VERSION}: load the HeRws module handeye rapid generate writes and start the program")
        self._info = ControllerInfo(version, f"RAPID_RWS{self.generation}", count)

    def _detect(self, deadline: Deadline) -> int:
        """RWS 1 or 2 from the authentication challenge, confirmed by the RobotWare version."""

        self.limiter.wait()
        self.requests += 1
        probe, failure = self._send("GET", self._url("/rw/system"), timeout=self._timeout(deadline),
                                    headers={"Accept": f"{HAL_JSON}, application/json"})
        if failure is not None:
            if failure[0] == "link" and not self.https and "refused" not in failure[1].lower():
                failure = ("link", failure[1] + "; a RobotWare 7 controller answers HTTPS only: give its "
                                                 "certificate's fingerprint (controller.tls_fingerprint)")
            self._fail("connect", failure, deadline)
        assert probe is not None  # _send gives a response whenever it gives no failure
        challenge = probe.headers.get("WWW-Authenticate", "").split(" ", 1)[0].lower()
        found = {"digest": 1, "basic": 2}.get(challenge)
        if found is None and probe.status_code == 200:
            found = 2 if self.https else 1
        if found is None:
            raise self.protocol_error(f"{self.address} does not answer like Robot Web Services (GET /rw/system: "
                                      f"HTTP {probe.status_code}, no Digest or Basic challenge)")
        if self.requested_generation != "auto" and int(self.requested_generation) != found:
            raise self.protocol_error(f"{self.address} speaks RWS {found}.0, not the RWS {self.requested_generation}.0 "
                                      "the configuration asks for")
        self.generation = found
        system = self._get("/rw/system", deadline)
        self.robotware = str(system.get("rwversion") or system.get("rwversionname") or "")
        self.system_name = str(system.get("name") or "")
        major = int(self.robotware.split(".")[0]) if self.robotware[:1].isdigit() else None
        if major is not None and (major >= 7) != (found == 2):
            raise self.protocol_error(f"{self.address} runs RobotWare {self.robotware} but answers like RWS {found}.0")
        if found == 2 and not self.https:
            raise self.connection_error(f"{self.address} is RobotWare 7 (RWS 2.0): use HTTPS with the controller's "
                                        "certificate pinned (controller.tls_fingerprint, port 443)")
        return found

    @property
    def simulated(self) -> bool:
        """True when the controller announced itself as a simulation (:data:`SIMULATION_SYSTEM_NAME`)."""
        return self.system_name == SIMULATION_SYSTEM_NAME

    def _drop(self) -> None:
        """Forget the TCP connections; the RWS session (cookies) is kept, so mastership survives a drop."""
        self._connected = False
        if self._http is not None:
            old, self._http = self._http, None
            fresh = self._session()
            fresh.cookies.update(old.cookies)
            close_session(old)

    def _goodbye(self) -> None:
        http = self._http
        if http is None:  # no session: nothing to log out of
            return
        try:
            http.get(self._url("/logout"), timeout=min(self.timeout, 0.5), auth=self._auth())
        finally:
            close_session(http)
            self._http = None

    def ping(self, timeout: float | None = None) -> float:
        start = time.perf_counter()
        self._call("ping", lambda d: self._get("/rw/panel/ctrlstate" if self.generation == 1 else "/rw/panel/ctrl-state",
                                               d, "ping"), timeout)
        return time.perf_counter() - start

    def _numbers(self, state: dict, keys: Sequence[str], what: str) -> np.ndarray:
        try:
            values = np.array([float(state[k]) for k in keys])
        except (KeyError, TypeError, ValueError):
            raise self.protocol_error(f"{what}: answer from {self.address} lacks {', '.join(keys)}: {str(state)[:80]}") from None
        if not np.all(np.isfinite(values)):
            raise self.protocol_error(f"{what}: {self.address} answered {values.tolist()}")
        return values

    def read_joints(self, timeout: float | None = None) -> np.ndarray:
        path = f"/rw/motionsystem/mechunits/{self.mechunit}/jointtarget"
        state = self._call("read joints", lambda d: self._get(path, d, "read joints"), timeout)
        return np.round(self._numbers(state, [f"rax_{i}" for i in range(1, 7)], "read joints"), 4)

    def read_tool0_pose(self, timeout: float | None = None) -> FlangePose:
        path = f"/rw/motionsystem/mechunits/{self.mechunit}/robtarget?tool=tool0&wobj=wobj0&coordinate=Base"
        state = self._call("read flange pose", lambda d: self._get(path, d, "read flange pose"), timeout)
        p = np.round(self._numbers(state, "xyz", "read flange pose"), 3)
        q = self._numbers(state, ("q1", "q2", "q3", "q4"), "read flange pose")
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > 1e-4:
            raise self.protocol_error(f"flange quaternion from {self.address} is not unit (norm {norm:.6g})")
        q = np.round(q / norm, 6)
        q = (-q if q[0] < 0 else q) + 0.0  # + 0.0: no -0.0 in what is printed
        return FlangePose(p + 0.0, q)

    def controller_state(self, timeout: float | None = None) -> dict:
        """``{"ctrlstate": "motoron", "opmode": "AUTO", "execution": "running", "robotware": "6.08"}``."""
        def read(d: Deadline) -> dict:
            ctrl = self._get("/rw/panel/ctrlstate" if self.generation == 1 else "/rw/panel/ctrl-state", d)
            mode = self._get("/rw/panel/opmode", d)
            execution = self._get("/rw/rapid/execution", d)
            return {"ctrlstate": ctrl.get("ctrlstate"), "opmode": mode.get("opmode"),
                    "execution": execution.get("ctrlexecstate"), "robotware": self.robotware}
        return self._call("read controller state", read, timeout)

    def _write_tool(self, tool: ToolData, deadline: Deadline) -> None:
        value = tooldata_value(tool)
        self._call("write tool data", lambda d: self._as_master(
            "write tool data", lambda d2: self._set_symbol(self.tool_module, self.tool_name, value, d2), d),
            deadline=deadline)

    def read_tool(self, timeout: float | None = None) -> ToolData:
        value = self._call("read tool data", lambda d: self._symbol_value(self.tool_module, self.tool_name, d), timeout)
        try:
            tool = tool_of_value(value)
        except ValueError as exc:
            raise self.protocol_error(f"{self.tool_module}.{self.tool_name} at {self.address}: {exc}") from None
        return ToolData(tuple(round(v, 3) for v in tool.position_mm), tuple(round(v, 6) for v in tool.quaternion_wxyz),
                        round(tool.mass_kg, 3), tuple(round(v, 3) for v in tool.cog_mm))
