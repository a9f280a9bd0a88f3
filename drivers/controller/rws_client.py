"""The ``rws`` back end: ABB Robot Web Services, RWS 1.0 (RobotWare 6) and RWS 2.0 (RobotWare 7).

No custom server runs on the controller for reads: joints and the flange pose come from the motion
system (``/rw/motionsystem/mechunits/ROB_1/jointtarget`` and ``robtarget?tool=tool0&wobj=wobj0``),
the camera tool data is the ``PERS tooldata`` of HeTool read and written by symbol. Only the posture
sequencing runs in RAPID (``HeRws``): the PC writes ``heRwsPc`` (``[request, grabbed]``), the program
publishes ``heRwsLink`` (``[state, posture, error, count, version]``); the handshake is the Modbus
one (rapid/PROTOCOL.md) with PERS data instead of registers.

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
write key, which never travels over RWS (see the README's threat model).
"""

from __future__ import annotations

import logging
import re
import threading
import time

import numpy as np

from .errors import ControllerRefused, InvalidRequest
from .interface import Controller, Deadline, LinkDown
from .polled import PolledHandshake
from .protocol import E_STATE, PROTOCOL_VERSION
from .types import (ACKED, AT, ERROR, LATE, MOVING, READY, ControllerInfo, ControllerStatus, FlangePose, ToolData,
                    check_fingerprint, check_timeout)

__all__ = ["RwsController", "RateLimiter", "STATE_NAMES", "rapid_literal", "parse_rapid_value", "tooldata_value"]

log = logging.getLogger(__name__)

#: ``heRwsLink{1}`` values (HeMain's HE_READY ...).
STATE_NAMES = {0: READY, 1: MOVING, 2: AT, 3: LATE, 4: ACKED, 5: ERROR}
#: RWS 2.0 media types (ABB RWS 2.0 manual, "Request and response formats").
HAL_JSON = "application/hal+json;v=2.0"
FORM_V2 = "application/x-www-form-urlencoded;v=2.0"
#: What the operator is told when the controller is in manual mode.
RMMP_HINT = "press Allow on the FlexPendant to grant this PC write access in manual mode"


class RateLimiter:
    """A token bucket: at most ``rate`` requests per second on average, bursts of ``burst``."""

    def __init__(self, rate: float, burst: int = 10):
        self.rate, self.burst = float(rate), float(burst)
        self.tokens, self.stamp = float(burst), time.monotonic()
        self._lock = threading.Lock()

    def wait(self) -> None:
        with self._lock:
            now = time.monotonic()
            self.tokens = min(self.burst, self.tokens + (now - self.stamp) * self.rate)
            self.stamp = now
            if self.tokens < 1.0:
                pause = (1.0 - self.tokens) / self.rate
                time.sleep(pause)
                self.stamp = time.monotonic()
                self.tokens = 1.0
            self.tokens -= 1.0


def rapid_literal(values) -> str:
    """A RAPID aggregate literal of nested numbers and bools: ``[TRUE,[[1,2,3],[1,0,0,0]],...]``."""
    if isinstance(values, bool):
        return "TRUE" if values else "FALSE"
    if isinstance(values, (list, tuple)):
        return "[" + ",".join(rapid_literal(v) for v in values) + "]"
    value = float(values)
    return str(int(value)) if value == int(value) and abs(value) < 1e9 else repr(value)


_TOKEN = re.compile(r"\s*(\[|\]|,|\"(?:[^\"]|\"\")*\"|TRUE|FALSE|[-+0-9.eE]+)", re.IGNORECASE)


def parse_rapid_value(text: str):
    """A RAPID value as RWS prints it (``[1,2,3]``, ``TRUE``, ``"text"``, ``9E+09``) as nested lists.

    Raises
    ------
    ValueError
        Not a RAPID literal of numbers, bools and strings.
    """
    pos, stack = 0, [[]]
    text = str(text).strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise ValueError(f"not a RAPID value at {text[pos:pos + 20]!r}")
        tok, pos = m.group(1), m.end()
        if tok == "[":
            stack.append([])
        elif tok == "]":
            if len(stack) < 2:
                raise ValueError("unbalanced ']'")
            done = stack.pop()
            stack[-1].append(done)
        elif tok == ",":
            continue
        elif tok.upper() in ("TRUE", "FALSE"):
            stack[-1].append(tok.upper() == "TRUE")
        elif tok.startswith('"'):
            stack[-1].append(tok[1:-1].replace('""', '"'))
        else:
            stack[-1].append(float(tok))
    if len(stack) != 1 or len(stack[0]) != 1:
        raise ValueError("not one RAPID value")
    return stack[0][0]


def tooldata_value(tool: ToolData, robhold: bool = True) -> list:
    """A :class:`ToolData` as the nested values of a RAPID ``tooldata`` (inertia axes identity, 0)."""
    return [robhold, [list(tool.position_mm), list(tool.quaternion_wxyz)],
            [tool.mass_kg, list(tool.cog_mm), [1, 0, 0, 0], 0, 0, 0]]


def _tool_of(value) -> ToolData:
    try:
        (_, (p, q), (mass, cog, *_)) = value
        return ToolData(tuple(float(v) for v in p), tuple(float(v) for v in q), float(mass),
                        tuple(float(v) for v in cog))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"not a tooldata value ({exc})") from None


class RwsController(PolledHandshake, Controller):
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
                 password: str = "robotics", generation="auto", tls_fingerprint: str | None = None,
                 task: str = "T_ROB1", mechunit: str = "ROB_1", tool_name: str = "tHeCamera",
                 tool_module: str = "HeTool", link_module: str = "HeRws", max_rate: float = 20.0,
                 poll_s: float = 0.02, rmmp_timeout: float = 60.0, **options):
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
        self._http = None
        self._connected = False
        self._requested = 0
        #: Requests sent (for diagnostics and tests) and 503 answers met.
        self.requests = 0
        self.busy_answers = 0

    # ------------------------------------------------------------------ link
    @property
    def address(self) -> str:
        return f"{'https' if self.https else 'http'}://{self.host}:{self.port}"

    @property
    def is_connected(self) -> bool:
        return self._connected

    def _session(self):
        import requests

        if self._http is None:
            http = requests.Session()
            if self.https:
                http.mount("https://", _pinned_adapter(self.tls_fingerprint))
                http.verify = False  # the pinned fingerprint replaces the CA check (self-signed)
            self._http = http
        return self._http

    def _open(self, deadline: Deadline) -> None:
        try:
            self._identify(deadline)
        except LinkDown:
            raise  # the session (its cookies: mastership) is kept for the retry
        except BaseException:
            self._connected = False
            if self._http is not None:  # refused, garbage, timeout: close the sockets now
                _close_session(self._http)
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
        major = int(self.robotware.split(".")[0]) if self.robotware[:1].isdigit() else None
        if major is not None and (major >= 7) != (found == 2):
            raise self.protocol_error(f"{self.address} runs RobotWare {self.robotware} but answers like RWS {found}.0")
        if found == 2 and not self.https:
            raise self.connection_error(f"{self.address} is RobotWare 7 (RWS 2.0): use HTTPS with the controller's "
                                        "certificate pinned (controller.tls_fingerprint, port 443)")
        return found

    def _drop(self) -> None:
        """Forget the TCP connections; the RWS session (cookies) is kept, so mastership survives a drop."""
        self._connected = False
        if self._http is not None:
            old, self._http = self._http, None
            fresh = self._session()
            fresh.cookies.update(old.cookies)
            _close_session(old)

    def _goodbye(self) -> None:
        try:
            self._http.get(self._url("/logout"), timeout=min(self.timeout, 0.5), auth=self._auth())
        finally:
            _close_session(self._http)
            self._http = None

    def _tls_message(self, text: str) -> str:
        if "fingerprint" in text.lower():
            return (f"the certificate of {self.address} does not match controller.tls_fingerprint ({text}): another "
                    "device answers, or the controller's certificate changed; check it on the FlexPendant before "
                    "updating the fingerprint")
        return f"TLS with {self.address} failed: {text}"

    # ------------------------------------------------------------------ HTTP
    def _url(self, path: str) -> str:
        return f"{self.address}{path}"

    def _auth(self):
        from requests.auth import HTTPBasicAuth, HTTPDigestAuth

        if getattr(self, "_auth_obj", None) is None:
            cls = HTTPBasicAuth if self.generation == 2 else HTTPDigestAuth
            self._auth_obj = cls(self.username, self._password)
        return self._auth_obj

    def _timeout(self, deadline: Deadline) -> float:
        left = deadline.remaining()
        if left <= 0:
            raise self.timeout_error(f"no time left within {deadline.seconds:g} s")
        return max(min(self.timeout, left), 1e-3)

    def _request(self, method: str, path: str, deadline: Deadline, data=None, what: str = ""):
        """One request (503 retried with back-off within the budget); the response when 2xx."""

        if not self._connected and self._http is None:
            raise LinkDown("not connected")
        what = what or f"{method} {path.split('?')[0]}"
        if self.generation == 1:
            path += ("&" if "?" in path else "?") + "json=1"
            headers = {}
            if data is not None:
                headers["Content-Type"] = "application/x-www-form-urlencoded"
        else:
            headers = {"Accept": HAL_JSON}
            if data is not None:
                headers["Content-Type"] = FORM_V2
        delay = self.backoff_s
        while True:
            self.limiter.wait()
            self.requests += 1
            response, failure = self._send(method, self._url(path), data=data, headers=headers, auth=self._auth(),
                                           timeout=self._timeout(deadline))
            if failure is not None:
                self._fail(what, failure, deadline)
            if response.status_code != 503:
                break
            self.busy_answers += 1
            if deadline.remaining() <= delay:
                raise self.timeout_error(f"{what}: {self.address} stayed busy (HTTP 503: {self._message(response)}) "
                                         f"for {deadline.seconds:g} s; too many clients or requests: retry later")
            time.sleep(delay)
            delay = min(2 * delay, self.backoff_max_s)
        if response.status_code >= 300:
            raise self._http_error(response, what)
        return response

    def _send(self, method: str, url: str, **options):
        """``(response, None)``, or ``(None, (kind, reason))`` when no answer came (kind: ``tls``,
        ``timeout``, ``link``). No exception object is kept: its traceback would hold the dropped
        connection's socket until the garbage collector runs."""
        import requests

        failure = None
        try:
            return self._session().request(method, url, allow_redirects=False, **options), None
        except requests.exceptions.SSLError as exc:
            text = _reason(exc)
            trust = any(word in text.lower() for word in ("fingerprint", "certificate", "verify"))
            failure = ("tls" if trust else "link", text)
        except requests.exceptions.Timeout:
            failure = ("timeout", "")
        except requests.exceptions.ConnectionError as exc:
            failure = ("link", _reason(exc))
        return None, failure

    def _fail(self, what: str, failure: tuple, deadline: Deadline):
        kind, reason = failure
        if kind == "tls":
            raise self.connection_error(f"{what}: {self._tls_message(reason)}")
        if kind == "timeout":
            self._drop()  # a late answer must not be taken for the next one
            raise self.timeout_error(f"{what}: no answer from {self.address} within {self._timeout_text(deadline)}")
        raise LinkDown(reason)

    def _timeout_text(self, deadline: Deadline) -> str:
        return f"{min(self.timeout, deadline.seconds):g} s"

    def _message(self, response) -> str:
        """The controller's own message of an error answer (JSON status, or the body's text)."""
        try:
            body = response.json()
        except ValueError:
            return re.sub(r"<[^>]+>|\s+", " ", response.text or "").strip()[:200] or response.reason
        status = body.get("status") or body.get("_embedded", {}).get("status") or {}
        msg = status.get("msg") or status.get("message") or response.reason
        code = status.get("code")
        return f"{msg} (code {code})" if code is not None else str(msg)

    def _http_error(self, response, what: str):
        status, message = response.status_code, self._message(response)
        if status == 401:
            return self.refused_error(f"{what}: {self.address} refused the login: wrong user or password for "
                                      f"{self.username!r} (HTTP 401: {message}); check controller.username and "
                                      "controller.password", 401)
        if status == 403:
            lower = message.lower()
            if "rmmp" in lower or "manual" in lower:
                return self.refused_error(f"{what}: {self.address} is in manual mode and this PC has no write access "
                                          f"(HTTP 403: {message}); {RMMP_HINT}", 403)
            return self.refused_error(f"{what}: {self.address} refused (HTTP 403: {message}); mastership may be "
                                      "held by another client (a FlexPendant, RobotStudio, another PC): release it "
                                      "there", 403)
        if status == 409:
            return self.refused_error(f"{what}: {self.address} refused in its current state (HTTP 409: {message})", 409)
        if status == 404:
            return self.refused_error(f"{what}: {self.address} has no such resource (HTTP 404: {message}); check "
                                      "that the handeye modules are loaded in task " + self.task, 404)
        return self.refused_error(f"{what}: {self.address} answered HTTP {status}: {message}", status)

    def _states(self, response, what: str) -> list:
        try:
            body = response.json()
        except ValueError:
            raise self.protocol_error(f"{what}: garbage from {self.address} instead of a JSON answer: "
                                      f"{response.content[:32]!r}") from None
        states = body.get("state") if isinstance(body, dict) else None
        if states is None and isinstance(body, dict):
            embedded = body.get("_embedded") or {}
            states = embedded.get("_state") or embedded.get("resources")
        if not isinstance(states, list) or not states or not isinstance(states[0], dict):
            raise self.protocol_error(f"{what}: answer from {self.address} holds no state: {str(body)[:80]}")
        return states

    def _get(self, path: str, deadline: Deadline, what: str = "") -> dict:
        return self._states(self._request("GET", path, deadline, what=what), what or path)[0]

    # ------------------------------------------------------------------ symbols
    def _symbol_path(self, module: str, name: str) -> str:
        if self.generation == 1:
            return f"/rw/rapid/symbol/data/RAPID/{self.task}/{module}/{name}"
        return f"/rw/rapid/symbol/RAPID/{self.task}/{module}/{name}/data"

    def _symbol_value(self, module: str, name: str, deadline: Deadline):
        state = self._get(self._symbol_path(module, name), deadline, f"read {module}.{name}")
        try:
            return parse_rapid_value(state["value"])
        except (KeyError, ValueError) as exc:
            raise self.protocol_error(f"read {module}.{name}: {self.address} answered {str(state)[:80]} ({exc})") from None

    def _set_symbol(self, module: str, name: str, value, deadline: Deadline) -> None:
        path = self._symbol_path(module, name)
        path = path + "?action=set" if self.generation == 1 else path
        self._request("POST", path, deadline, data={"value": rapid_literal(value)}, what=f"write {module}.{name}")

    # ------------------------------------------------------------------ mastership
    def _mastership(self, action: str, deadline: Deadline) -> None:
        path = f"/rw/mastership?action={action}" if self.generation == 1 else f"/rw/mastership/edit/{action}"
        self._request("POST", path, deadline, data={}, what=f"mastership {action}")

    def _as_master(self, what: str, write, deadline: Deadline):
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

    # ------------------------------------------------------------------ reading
    def ping(self, timeout=None) -> float:
        start = time.perf_counter()
        self._call("ping", lambda d: self._get("/rw/panel/ctrlstate" if self.generation == 1 else "/rw/panel/ctrl-state",
                                               d, "ping"), timeout)
        return time.perf_counter() - start

    def _numbers(self, state: dict, keys, what: str) -> np.ndarray:
        try:
            values = np.array([float(state[k]) for k in keys])
        except (KeyError, TypeError, ValueError):
            raise self.protocol_error(f"{what}: answer from {self.address} lacks {', '.join(keys)}: {str(state)[:80]}") from None
        if not np.all(np.isfinite(values)):
            raise self.protocol_error(f"{what}: {self.address} answered {values.tolist()}")
        return values

    def read_joints(self, timeout=None) -> np.ndarray:
        path = f"/rw/motionsystem/mechunits/{self.mechunit}/jointtarget"
        state = self._call("read joints", lambda d: self._get(path, d, "read joints"), timeout)
        return np.round(self._numbers(state, [f"rax_{i}" for i in range(1, 7)], "read joints"), 4)

    def read_tool0_pose(self, timeout=None) -> FlangePose:
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

    def controller_state(self, timeout=None) -> dict:
        """``{"ctrlstate": "motoron", "opmode": "AUTO", "execution": "running", "robotware": "6.08"}``."""
        def read(d):
            ctrl = self._get("/rw/panel/ctrlstate" if self.generation == 1 else "/rw/panel/ctrl-state", d)
            mode = self._get("/rw/panel/opmode", d)
            execution = self._get("/rw/rapid/execution", d)
            return {"ctrlstate": ctrl.get("ctrlstate"), "opmode": mode.get("opmode"),
                    "execution": execution.get("ctrlexecstate"), "robotware": self.robotware}
        return self._call("read controller state", read, timeout)

    def _raw_status(self, deadline: Deadline) -> dict:
        values = self._symbol_value(self.link_module, "heRwsLink", deadline)
        try:
            code, posture, error = (int(v) for v in values[:3])
        except (TypeError, ValueError):
            raise self.protocol_error(f"heRwsLink at {self.address} holds {values}") from None
        if code not in STATE_NAMES:
            raise self.protocol_error(f"heRwsLink at {self.address} holds state {code}, not a known state")
        return {"state": STATE_NAMES[code], "posture": posture, "error": error}

    def status(self, timeout=None) -> ControllerStatus:
        raw = self._call("read status", self._raw_status, timeout)
        return ControllerStatus(raw["state"], raw["posture"])

    # ------------------------------------------------------------------ motion
    def check_posture(self, k, expected_joints=None) -> int:
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

    def _wait_for(self, what: str, done, deadline: Deadline) -> dict:
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

    # ------------------------------------------------------------------ tool data
    def _write_tool(self, tool: ToolData, deadline: Deadline) -> None:
        value = tooldata_value(tool)
        self._call("write tool data", lambda d: self._as_master(
            "write tool data", lambda d2: self._set_symbol(self.tool_module, self.tool_name, value, d2), d),
            deadline=deadline)

    def read_tool(self, timeout=None) -> ToolData:
        value = self._call("read tool data", lambda d: self._symbol_value(self.tool_module, self.tool_name, d), timeout)
        try:
            tool = _tool_of(value)
        except ValueError as exc:
            raise self.protocol_error(f"{self.tool_module}.{self.tool_name} at {self.address}: {exc}") from None
        return ToolData(tuple(round(v, 3) for v in tool.position_mm), tuple(round(v, 6) for v in tool.quaternion_wxyz),
                        round(tool.mass_kg, 3), tuple(round(v, 3) for v in tool.cog_mm))

    # ------------------------------------------------------------------ the program
    def load_program(self, modules, timeout: float | None = None, folder: str = "$HOME/handeye") -> None:
        """Upload RAPID modules, load them into the task (replacing those of the same name), reset the
        program pointer and start ``main``.

        Parameters
        ----------
        modules : iterable of (filename, text)
            ``HeMain.mod``, ``HeRws.mod``, ``HeTool.mod`` (what ``handeye rapid generate`` writes).
        """
        deadline = self._budget(timeout if timeout is not None else max(self.timeout, 10.0))
        files = [(str(name), str(text)) for name, text in modules]
        if not files:
            raise InvalidRequest("no RAPID modules to load")

        def load(d):
            self._execution("stop", d, {"stopmode": "stop", "usetsp": "normal"})
            for name, text in files:
                self._request("PUT", f"/fileservice/{folder}/{name}", d, data=text.encode("latin-1"),
                              what=f"upload {name}")
                if self.generation == 1:
                    path = f"/rw/rapid/tasks/{self.task}?action=loadmod"
                else:
                    path = f"/rw/rapid/tasks/{self.task}/loadmod"
                self._request("POST", path, d, data={"modulepath": f"{folder}/{name}", "replace": "true"},
                              what=f"load {name}")
            self._execution("resetpp", d, {})
            if any(name.lower().startswith(self.link_module.lower() + ".") for name, _ in files):
                # a PERS keeps the last run's value until HeLinkOpen runs: clear it, so that a stale READY
                # is not taken for the new program's
                self._set_symbol(self.link_module, "heRwsLink", [0, 0, 0, 0, 0], d)
            self._execution("start", d, {"regain": "continue", "execmode": "continue", "cycle": "forever",
                                         "condition": "none", "stopatbp": "disabled", "alltaskbytsp": "false"})

        self._call("load the program", lambda d: self._as_master("load the program", load, d), deadline=deadline)
        while self._call("wait for the program", lambda d: self._symbol_value(self.link_module, "heRwsLink", d),
                         deadline=deadline)[4] != PROTOCOL_VERSION:
            if deadline.remaining() <= self.poll_s:
                raise self.timeout_error(f"the program loaded at {self.address} did not start within "
                                         f"{deadline.seconds:g} s (heRwsLink stays cleared): check the FlexPendant")
            time.sleep(self.poll_s)
        self._info = None
        self._connected = False  # read the program's identity again
        self.connect(max(deadline.remaining(), self.timeout))

    def stop_program(self, timeout: float | None = None) -> None:
        """Stop RAPID execution (the end of a capture)."""
        self._call("stop the program", lambda d: self._as_master(
            "stop the program", lambda d2: self._execution("stop", d2, {"stopmode": "stop", "usetsp": "normal"}), d),
            timeout)

    def _execution(self, action: str, deadline: Deadline, data: dict) -> None:
        path = f"/rw/rapid/execution?action={action}" if self.generation == 1 else f"/rw/rapid/execution/{action}"
        self._request("POST", path, deadline, data=data, what=f"execution {action}")


def _close_session(http) -> None:
    """Close a requests session and its sockets now: urllib3 2 leaves the pools of a cleared
    PoolManager to the garbage collector, which may keep a socket open long after a dropped link."""
    for adapter in http.adapters.values():
        pools = getattr(getattr(adapter, "poolmanager", None), "pools", None)
        for key in list(pools.keys()) if pools is not None else []:
            try:
                pools[key].close()
            except KeyError:
                pass
    http.close()


def _reason(exc) -> str:
    """The innermost reason of a requests/urllib3 error, one line."""
    text = str(exc)
    m = re.search(r"\((?:Caused by )?\w+\((.*)\)\)\)?$", text)
    text = m.group(1) if m else text
    return re.sub(r"\s+", " ", text)[:200]


def _pinned_adapter(fingerprint: str):
    """A requests adapter that accepts exactly the certificate of SHA-256 ``fingerprint`` (self-signed)."""
    from requests.adapters import HTTPAdapter

    class PinnedAdapter(HTTPAdapter):
        def init_poolmanager(self, *args, **kwargs):
            kwargs["assert_fingerprint"] = fingerprint
            kwargs["cert_reqs"] = "CERT_NONE"
            kwargs["assert_hostname"] = False
            super().init_poolmanager(*args, **kwargs)

        def cert_verify(self, conn, url, verify, cert):
            super().cert_verify(conn, url, False, cert)
            conn.assert_fingerprint = fingerprint

    return PinnedAdapter()

