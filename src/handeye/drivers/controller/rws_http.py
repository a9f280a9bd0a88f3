"""HTTP of the ``rws`` back end (a mixin of :class:`~handeye.drivers.controller.rws_client.RwsController`):
the requests session, authentication (Digest for RWS 1.0, Basic for RWS 2.0), the paced requests
with 503 retried with back-off within the call's budget, HTTP errors as the shared kinds with the
controller's own message, the JSON answers of both generations and RAPID symbols read and written."""

from __future__ import annotations

import re
import time
from typing import TYPE_CHECKING, Any, NoReturn

from .errors import ControllerRefused
from .interface import Controller, Deadline, LinkDown
from .rws_codec import RapidData, parse_rapid_value, rapid_literal
from .rws_transport import RateLimiter, failure_reason, pinned_adapter

if TYPE_CHECKING:
    import requests
    from requests.auth import AuthBase

__all__ = ["RwsHttp", "HAL_JSON", "FORM_V2", "RMMP_HINT"]

#: RWS 2.0 media types (ABB RWS 2.0 manual, "Request and response formats").
HAL_JSON = "application/hal+json;v=2.0"
FORM_V2 = "application/x-www-form-urlencoded;v=2.0"
#: What the operator is told when the controller is in manual mode.
RMMP_HINT = "press Allow on the FlexPendant to grant this PC write access in manual mode"

#: Why no answer came (:meth:`RwsHttp._send`): ``(kind, reason)``, kind ``tls``, ``timeout`` or ``link``.
Failure = tuple[str, str]

# For the type checker only: the mixin's methods run on the RwsController, a Controller; at run time its
# base is object, so RwsController's own base list alone makes its method order.
_Host = Controller if TYPE_CHECKING else object


class RwsHttp(_Host):
    """Requests, answers and symbols over RWS (see the module docstring); the controller sets
    ``https``, ``host``, ``port``, ``generation``, ``username``, ``limiter`` and the request counters."""

    # Set by RwsController.__init__ (and generation by its detection at connect).
    https: bool
    host: str
    port: int
    username: str
    _password: str
    tls_fingerprint: str | None
    task: str
    generation: int | None
    limiter: RateLimiter
    requests: int
    busy_answers: int
    _http: requests.Session | None
    _connected: bool

    @property
    def address(self) -> str:
        return f"{'https' if self.https else 'http'}://{self.host}:{self.port}"

    def _session(self) -> requests.Session:
        import requests

        if self._http is None:
            http = requests.Session()
            if self.https:
                if self.tls_fingerprint is None:  # https is set from the fingerprint: a bug if it is missing
                    raise ValueError("RWS over HTTPS needs the controller's certificate fingerprint")
                http.mount("https://", pinned_adapter(self.tls_fingerprint))
                http.verify = False  # the pinned fingerprint replaces the CA check (self-signed)
            self._http = http
        return self._http

    def _tls_message(self, text: str) -> str:
        if "fingerprint" in text.lower():
            return (f"the certificate of {self.address} does not match controller.tls_fingerprint ({text}): another "
                    "device answers, or the controller's certificate changed; check it on the FlexPendant before "
                    "updating the fingerprint")
        return f"TLS with {self.address} failed: {text}"

    def _url(self, path: str) -> str:
        return f"{self.address}{path}"

    def _auth(self) -> AuthBase:
        from requests.auth import HTTPBasicAuth, HTTPDigestAuth

        auth: AuthBase | None = getattr(self, "_auth_obj", None)
        if auth is None:
            cls = HTTPBasicAuth if self.generation == 2 else HTTPDigestAuth
            auth = self._auth_obj = cls(self.username, self._password)
        return auth

    def _timeout(self, deadline: Deadline) -> float:
        left = deadline.remaining()
        if left <= 0:
            raise self.timeout_error(f"no time left within {deadline.seconds:g} s")
        return max(min(self.timeout, left), 1e-3)

    def _request(self, method: str, path: str, deadline: Deadline, data: dict | str | bytes | None = None,
                 what: str = "") -> requests.Response:
        """One request (503 retried with back-off within the budget); the response when 2xx."""

        if not self._connected and self._http is None:
            raise LinkDown("not connected")
        what = what or f"{method} {path.split('?')[0]}"
        if self.generation == 1:
            path += ("&" if "?" in path else "?") + "json=1"
            headers: dict[str, str] = {}
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
            assert response is not None  # _send gives a response whenever it gives no failure
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

    def _send(self, method: str, url: str, **options: Any) -> tuple[requests.Response | None, Failure | None]:
        """``(response, None)``, or ``(None, (kind, reason))`` when no answer came (kind: ``tls``,
        ``timeout``, ``link``). No exception object is kept: its traceback would hold the dropped
        connection's socket until the garbage collector runs."""
        import requests

        failure: Failure | None = None
        try:
            return self._session().request(method, url, allow_redirects=False, **options), None
        except requests.exceptions.SSLError as exc:
            text = failure_reason(exc)
            trust = any(word in text.lower() for word in ("fingerprint", "certificate", "verify"))
            failure = ("tls" if trust else "link", text)
        except requests.exceptions.Timeout:
            failure = ("timeout", "")
        except requests.exceptions.ConnectionError as exc:
            failure = ("link", failure_reason(exc))
        return None, failure

    def _fail(self, what: str, failure: Failure, deadline: Deadline) -> NoReturn:
        kind, reason = failure
        if kind == "tls":
            raise self.connection_error(f"{what}: {self._tls_message(reason)}")
        if kind == "timeout":
            self._drop()  # a late answer must not be taken for the next one
            raise self.timeout_error(f"{what}: no answer from {self.address} within {self._timeout_text(deadline)}")
        raise LinkDown(reason)

    def _timeout_text(self, deadline: Deadline) -> str:
        return f"{min(self.timeout, deadline.seconds):g} s"

    def _message(self, response: requests.Response) -> str:
        """The controller's own message of an error answer (JSON status, or the body's text)."""
        try:
            body = response.json()
        except ValueError:
            return re.sub(r"<[^>]+>|\s+", " ", response.text or "").strip()[:200] or response.reason
        status = body.get("status") or body.get("_embedded", {}).get("status") or {}
        msg = status.get("msg") or status.get("message") or response.reason
        code = status.get("code")
        return f"{msg} (code {code})" if code is not None else str(msg)

    def _http_error(self, response: requests.Response, what: str) -> ControllerRefused:
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

    def _states(self, response: requests.Response, what: str) -> list:
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

    def _symbol_path(self, module: str, name: str) -> str:
        if self.generation == 1:
            return f"/rw/rapid/symbol/data/RAPID/{self.task}/{module}/{name}"
        return f"/rw/rapid/symbol/RAPID/{self.task}/{module}/{name}/data"

    def _symbol_value(self, module: str, name: str, deadline: Deadline) -> Any:
        state = self._get(self._symbol_path(module, name), deadline, f"read {module}.{name}")
        try:
            return parse_rapid_value(state["value"])
        except (KeyError, ValueError) as exc:
            raise self.protocol_error(f"read {module}.{name}: {self.address} answered {str(state)[:80]} ({exc})") from None

    def _set_symbol(self, module: str, name: str, value: RapidData, deadline: Deadline) -> None:
        path = self._symbol_path(module, name)
        path = path + "?action=set" if self.generation == 1 else path
        self._request("POST", path, deadline, data={"value": rapid_literal(value)}, what=f"write {module}.{name}")
