"""Mock Robot Web Services: a real HTTP(S) server on 127.0.0.1 in front of the interpreted RAPID task.

``RwsControllerServer`` serves RWS 1.0 (RobotWare 6: HTTP, Digest authentication, session cookies
``-http-session-`` and ``ABBCX``, XHTML answers or JSON with ``?json=1``) or RWS 2.0 (RobotWare 7:
HTTPS with a self-signed certificate made at start, Basic authentication, ``application/hal+json;v=2.0``)
over the same simulated arm and the same RAPID interpreter as the other mocks:

- ``/rw/motionsystem/mechunits/ROB_1/jointtarget`` and ``robtarget`` read the simulated arm;
- ``/rw/rapid/symbol/...`` reads and writes the task's module data (PERS, VAR) by symbol: the
  posture handshake of HeRws and the camera's PERS tooldata;
- ``/fileservice/$HOME/...`` is a virtual controller file system; ``loadmod`` loads a module of it
  into the task (replacing the one of the same name); ``/rw/rapid/execution`` start/stop/resetpp
  drive the task; PERS values survive a restart of the program (``POST /rw/panel/restart`` or a
  reload) unless their module is loaded again from a file, as on a controller;
- mastership (``/rw/mastership``), the manual-mode grant (``/users/rmmp``), the operating mode and
  the motors state are simulated, with the controller's refusals (403 without mastership or RMMP,
  409 with the motors off).

Faults (:class:`~handeye.mocks.controller.faults.Faults`): ``drop_next``/``drop_after`` (connection
closed instead of an answer), ``delay_s``, ``garbage_next`` (a 200 answer that is not JSON),
``silent`` (requests never answered), ``busy_next``/``busy`` (503), ``mastership_held`` (another
client holds mastership), ``robot_stalled``. Operator-side switches: :attr:`opmode` (``AUTO``,
``MANR``, ``MANF``), :attr:`rmmp_policy` (``allow``, ``deny``, ``ignore``), :meth:`set_motors`.

Where ``abb-robot-client`` and ABB's documentation differ, the mock follows the documentation and
accepts what the client sends when the documentation allows it (comments at those places).

Modules: ``rws_web`` (the HTTP(S) server, error answers, the certificate), ``rws_auth``,
``rws_reads``, ``rws_writes``; this one is the controller: endpoint, program, faults, answers, routing.
"""

from __future__ import annotations

import json
import socket
import ssl
import threading
import time
from typing import TYPE_CHECKING, Any
from urllib.parse import parse_qs, unquote, urlsplit

from ...rapid import Bindings
from .faults import Faults
from .rws_auth import DEFAULT_PASSWORD, DEFAULT_USER, REALM, RwsAuth
from .rws_reads import RwsReads
from .rws_web import HAL_JSON, HttpError, RwsHandler, RwsHttpServer, self_signed_certificate
from .rws_writes import RwsWrites
from .server import DEFAULT_IDLE_TIMEOUT_S, RapidControllerServer
from .sources import ControllerProgram

if TYPE_CHECKING:
    from ..robot import SimulatedRobot

__all__ = ["RwsControllerServer", "DEFAULT_USER", "DEFAULT_PASSWORD", "REALM", "self_signed_certificate"]


class RwsControllerServer(RwsAuth, RwsReads, RwsWrites, RapidControllerServer):
    """Robot Web Services of a simulated IRC5 (RWS 1.0) or OmniCore (RWS 2.0) controller.

    Parameters
    ----------
    program : ControllerProgram
    robot : SimulatedRobot
    host, port : str, int
        0 picks a free port (see :attr:`port` after :meth:`start`).
    faults : Faults, optional
    generation : int
        1 (RobotWare 6.08, HTTP, Digest) or 2 (RobotWare 7.10, HTTPS, Basic).
    username, password : str
        The one user the controller knows (default ``Default User`` / ``robotics``).
    idle_timeout_s : float
        Connections silent this long are closed.
    write_key : str, optional
        Accepted for symmetry with the other mocks (RWS writes are authorised by the user).
    """

    kind = "rws"

    def __init__(self, program: ControllerProgram, robot: SimulatedRobot, host: str = "127.0.0.1", port: int = 0, faults: Faults | None = None, *,
                 generation: int = 1, username: str = DEFAULT_USER, password: str = DEFAULT_PASSWORD,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        super().__init__(program, robot, host, port, faults, idle_timeout_s=idle_timeout_s, write_key=write_key)
        if int(generation) not in (1, 2):
            raise ValueError(f"RWS generation must be 1 or 2; got {generation!r}")
        self.generation = int(generation)
        self.username, self.password = username, password
        self.robotware = "6.08.0134" if self.generation == 1 else "7.10.0"
        self._httpd: RwsHttpServer | None = None
        self._thread: threading.Thread | None = None
        self._connections: set = set()
        self._lock = threading.RLock()
        self._stopping = threading.Event()
        self.sessions: dict = {}  # session id -> {"user", "rmmp"}
        self.nonces: set = set()
        #: Who holds mastership: a session id, or None.
        self.master: str | None = None
        self.opmode = "AUTO"
        self.rmmp_policy = "allow"
        self.motors_on = True
        self.files: dict = {}  # "$HOME/x.mod" -> bytes
        self._fresh_modules: set = set()  # modules loaded from files since the last start (their PERS reset)
        self._pers: dict = {}  # (module, name) -> value kept across restarts
        self.requests = 0
        self.writes = 0

    @property
    def port(self) -> int:
        return self._httpd.server_address[1] if self._httpd is not None else self._requested_port

    @property
    def tls_fingerprint(self) -> str | None:
        return self_signed_certificate()[2] if self.generation == 2 else None

    def listening(self) -> str:
        security = "HTTPS, Basic" if self.generation == 2 else "HTTP, Digest"
        return (f": Robot Web Services {self.generation}.0 (RobotWare {self.robotware}, {security}) listening on "
                f"{self.host}:{self.port}")

    def link_note(self, idle_timeout_s: float) -> str:
        writes = "tool writes by symbol, authorised by the RWS user and mastership"
        if self.generation == 2:
            writes += ("\n  its self-signed certificate is made anew at every start: pin the fingerprint "
                       "printed now, it changes the next time")
        return writes

    def client_flags(self) -> str:
        pin = f" --tls-fingerprint {self.tls_fingerprint}" if self.generation == 2 else ""
        return f"--host {self.host} --port {self.port} --user '{self.username}' --password {self.password}{pin}"

    def client_options(self) -> dict:
        options = {"host": self.host, "port": self.port, "username": self.username, "password": self.password,
                   "idle_timeout": self.idle_timeout_s}
        if self.generation == 2:
            options["tls_fingerprint"] = self.tls_fingerprint
        return self._client_key(options)

    def _open_endpoint(self) -> Bindings:
        context = None
        if self.generation == 2:
            cert, key, _ = self_signed_certificate()
            context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
            context.load_cert_chain(cert, key)
        self._stopping.clear()
        self._httpd = RwsHttpServer((self.host, self._requested_port), self, context)
        self._thread = threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.05},
                                        name=f"mock-rws-{self.port}", daemon=True)
        self._thread.start()
        return Bindings()

    def _close_endpoint(self) -> None:
        if self._httpd is None:
            return
        self._stopping.set()
        self._httpd.shutdown()
        with self._lock:
            for conn in list(self._connections):
                try:
                    conn.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
        self._httpd.server_close()  # joins the connection threads
        if self._thread is not None:
            self._thread.join(10)
        self._httpd, self._thread = None, None

    def _track(self, conn, opened: bool) -> None:
        with self._lock:
            (self._connections.add if opened else self._connections.discard)(conn)

    def _load(self, program) -> None:
        """Link ``program`` into the task (stopped), its PERS data keeping their values unless their
        module was just loaded from a file, as a controller keeps them."""
        runner = self._live_runner()
        old = runner.program
        if old is not None:
            self._pers.update(self._pers_values(old))
        for symbol in runner.load(program).data:
            key = (symbol.module.lower(), symbol.name.lower())
            if symbol.storage == "PERS" and key in self._pers and symbol.module.lower() not in self._fresh_modules:
                symbol.box[0] = self._pers[key]
        self._fresh_modules.clear()
        self._loaded = program

    def _run(self, program) -> None:
        if getattr(self, "_loaded", None) is not program:
            self._load(program)
        self._live_runner().start()

    @staticmethod
    def _pers_values(program) -> dict:
        return {(s.module.lower(), s.name.lower()): s.box[0] for s in program.data if s.storage == "PERS"}

    def restart(self) -> None:
        """A warm start of the controller: the program restarts from main, PERS values kept."""
        if self.runner is not None:
            self.runner.stop()
            self._load(self.source)
            self.runner.start()

    def set_motors(self, on: bool) -> None:
        """Motors on or off (off: the RAPID program stops, as a controller's does)."""
        self.motors_on = bool(on)
        if not on and self.runner is not None:
            self.runner.stop()

    def _fault_before_answer(self, handler) -> bool:
        """True when the request is to be answered by closing the connection (drop, silent)."""
        faults = self.faults
        if faults.delay_s > 0:
            time.sleep(faults.delay_s)
        if faults.silent:
            faults.note("silent")
            while faults.silent and not self._stopping.is_set():
                time.sleep(0.02)
            return True
        return faults.should_drop()

    def _wants_json(self, handler, query) -> bool:
        if self.generation == 1:
            return query.get("json", [""])[0] == "1"
        return "json" in handler.headers.get("Accept", "")

    def answer(self, handler: RwsHandler, query: dict[str, list[str]], states: list[dict],
               links: object = None) -> tuple[bytes, str]:
        base = f"{'https' if self.generation == 2 else 'http'}://{self.host}:{self.port}/"
        if self._wants_json(handler, query):
            if self.generation == 1:
                body = {"_links": {"base": {"href": base}}, "_embedded": {"_state": states}}
                # abb-robot-client compares the Content-Type with 'application/json' exactly
                return json.dumps(body).encode(), "application/json"
            return json.dumps({"_links": {"base": {"href": base}}, "state": states}).encode(), HAL_JSON
        items = "".join(
            f'<li class="{s.get("_type", "")}" title="{s.get("_title", "")}">'
            + "".join(f'<span class="{k}">{v}</span>' for k, v in s.items() if not k.startswith("_")) + "</li>"
            for s in states)
        page = (f'<?xml version="1.0" encoding="UTF-8"?><html xmlns="http://www.w3.org/1999/xhtml"><head>'
                f'<base href="{base}"/></head><body><div class="state"><ul>{items}</ul></div></body></html>')
        return page.encode(), "application/xhtml+xml;v=2.0" if self.generation == 2 else "application/xhtml+xml"

    def error_body(self, handler: RwsHandler, err: HttpError) -> tuple[bytes, str]:
        status = {"code": err.code, "msg": err.message}
        if self.generation == 1:
            return json.dumps({"_embedded": {"status": status}}).encode(), "application/json"
        return json.dumps({"status": status}).encode(), HAL_JSON

    def dispatch(self, handler: RwsHandler, method: str, body: bytes) -> tuple[int, tuple[bytes, str] | None, dict]:
        self.requests += 1
        faults = self.faults
        if faults.busy or faults.take("busy_next"):
            faults.note("busy")
            raise HttpError(503, "Service unavailable: too many requests or sessions", -1073442813)
        parts = urlsplit(handler.path)
        path, query = unquote(parts.path), parse_qs(parts.query)
        session, cookies = self._authenticate(handler, method)
        form = {k: v[0] for k, v in parse_qs(body.decode("latin-1")).items()} if method == "POST" else {}
        action = query.get("action", [None])[0]
        status, payload = self._route(handler, method, path, query, form, body, session, action)
        return status, payload, cookies

    def _route(self, handler, method, path, query, form, body, session, action):
        if path.startswith("/fileservice/"):
            return self._files(method, path[len("/fileservice/"):], body, session)
        if path == "/logout":
            with self._lock:
                self.sessions.pop(session, None)
                if self.master == session:
                    self.master = None
            return 204, None
        if method == "GET":
            return 200, self.answer(handler, query, self._read(path, query))
        if method != "POST":
            raise HttpError(405, f"{method} is not allowed on {path}")
        return self._post(path, action, form, session)

    def symbol_value(self, name: str, module: str | None = None) -> Any:  # any RAPID value
        """The task's current value of module data ``name`` (tests)."""
        return self._symbol(("T_ROB1", module, name)).box[0]
