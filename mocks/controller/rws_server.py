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
"""

from __future__ import annotations

import base64
import hashlib
import json
import logging
import os
import secrets
import socket
import ssl
import tempfile
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, unquote, urlsplit

import numpy as np

from ...drivers.controller.rws_client import parse_rapid_value
from ...rapid.errors import RapidError
from ...rapid.interpreter import Bindings, ModuleSource, parse_module
from ...rapid.interpreter.values import aggregate, coerce, coerce_array, format_value
from .faults import Faults
from .server import DEFAULT_IDLE_TIMEOUT_S, RapidControllerServer
from .sources import ControllerProgram

__all__ = ["RwsControllerServer", "DEFAULT_USER", "DEFAULT_PASSWORD", "REALM", "self_signed_certificate"]

log = logging.getLogger(__name__)

DEFAULT_USER, DEFAULT_PASSWORD = "Default User", "robotics"
#: The realm RobotWare's RWS challenges with.
REALM = "validusers@robapi.abb"
#: ABB's code in a refusal for a write without mastership (RWS 2.0 manual; reference/abb-controller.md).
E_MASTERSHIP = -1073445862
E_RMMP = -1073445863
E_STATE = -1073445865
HAL_JSON = "application/hal+json;v=2.0"

_CERT_LOCK = threading.Lock()
_CERT: tuple | None = None


def self_signed_certificate() -> tuple[str, str, str]:
    """``(certificate file, key file, SHA-256 fingerprint)`` of a self-signed certificate for
    127.0.0.1, made once per process (as an OmniCore controller makes its own)."""
    global _CERT
    with _CERT_LOCK:
        if _CERT is None:
            import datetime

            from cryptography import x509
            from cryptography.hazmat.primitives import hashes, serialization
            from cryptography.hazmat.primitives.asymmetric import ec
            from cryptography.x509.oid import NameOID

            key = ec.generate_private_key(ec.SECP256R1())
            name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "handeye mock OmniCore")])
            now = datetime.datetime.now(datetime.timezone.utc)
            cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
                    .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(days=1))
                    .not_valid_after(now + datetime.timedelta(days=30)).sign(key, hashes.SHA256()))
            folder = tempfile.mkdtemp(prefix="handeye-rws-")
            cert_file, key_file = os.path.join(folder, "cert.pem"), os.path.join(folder, "key.pem")
            with open(cert_file, "wb") as f:
                f.write(cert.public_bytes(serialization.Encoding.PEM))
            with open(key_file, "wb") as f:
                f.write(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()))
            fingerprint = hashlib.sha256(cert.public_bytes(serialization.Encoding.DER)).hexdigest()
            _CERT = (cert_file, key_file, fingerprint)
        return _CERT


class HttpError(Exception):
    """An error answer: HTTP status, the controller's code and message."""

    def __init__(self, status: int, message: str, code: int = -1, headers=None):
        super().__init__(message)
        self.status, self.message, self.code, self.headers = status, message, code, headers or {}


def _rws_num(value: float) -> str:
    """A num as RWS prints it: the shortest text that gives back the same float32."""
    v = np.float32(value)
    if v == int(v) and abs(v) < 1e9:
        return str(int(v))
    if 1e-4 <= abs(v) < 1e9:
        return np.format_float_positional(v, unique=True, trim="-")
    return np.format_float_scientific(v, unique=True, trim="-").upper()


def _unreadable(value):
    raise HttpError(400, f"a {type(value).__name__} cannot be read over RWS")


def _rws_text(value) -> str:
    """A RAPID value as RWS prints it (``ValToStr``'s form with RWS's float32 numbers)."""
    return format_value(value, _rws_num, _unreadable)


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    server_version = "handeye-mock-RWS"
    disable_nagle_algorithm = True  # headers and body are two writes: no 40 ms Nagle/delayed-ACK stall

    def log_message(self, fmt, *args):  # quiet: the test output is ours
        log.debug("mock RWS: " + fmt, *args)

    def setup(self):
        self.timeout = self.server.owner.idle_timeout_s
        super().setup()
        self.server.owner._track(self.connection, True)

    def finish(self):
        try:
            super().finish()
        finally:
            self.server.owner._track(self.connection, False)

    def do_GET(self):
        self._serve("GET")

    def do_POST(self):
        self._serve("POST")

    def do_PUT(self):
        self._serve("PUT")

    def do_DELETE(self):
        self._serve("DELETE")

    def _serve(self, method: str) -> None:
        owner = self.server.owner
        length = int(self.headers.get("Content-Length") or 0)
        body = self.rfile.read(length) if length else b""
        if owner._fault_before_answer(self):
            self.close_connection = True
            return
        try:
            status, payload, headers = owner.dispatch(self, method, body)
        except HttpError as err:
            status, payload, headers = err.status, owner.error_body(self, err), err.headers
        except Exception as exc:  # a bug in the mock must show, not hang the client
            log.exception("mock RWS: %s %s failed", method, self.path)
            status, payload, headers = 500, owner.error_body(self, HttpError(500, str(exc))), {}
        if owner.faults.take("garbage_next"):
            owner.faults.note("garbage")
            status, payload, headers = 200, (owner.faults.garbage, "application/json"), {}
        self._answer(status, payload, headers)

    def _answer(self, status: int, payload, headers: dict) -> None:
        data, ctype = payload if payload is not None else (b"", None)
        self.send_response(status)
        for name, value in headers.items():
            for v in value if isinstance(value, list) else [value]:
                self.send_header(name, v)
        if ctype:
            self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        if data and self.command != "HEAD":
            self.wfile.write(data)


class _Server(ThreadingHTTPServer):
    daemon_threads = False
    block_on_close = True
    allow_reuse_address = True

    def __init__(self, address, owner, tls_context=None):
        self.owner, self.tls_context = owner, tls_context
        super().__init__(address, _Handler)

    def finish_request(self, request, client_address):
        if self.tls_context is not None:  # the handshake in the connection's own thread
            try:
                request.settimeout(self.owner.idle_timeout_s)
                request = self.tls_context.wrap_socket(request, server_side=True)
            except (OSError, ssl.SSLError) as exc:
                log.info("mock RWS: TLS handshake with %s failed: %s", client_address, exc)
                return
        super().finish_request(request, client_address)

    def handle_error(self, request, client_address):
        log.debug("mock RWS: connection from %s ended with an error", client_address, exc_info=True)


class RwsControllerServer(RapidControllerServer):
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

    def __init__(self, program, robot, host: str = "127.0.0.1", port: int = 0, faults: Faults | None = None, *,
                 generation: int = 1, username: str = DEFAULT_USER, password: str = DEFAULT_PASSWORD,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        super().__init__(program, robot, host, port, faults, idle_timeout_s=idle_timeout_s, write_key=write_key)
        if int(generation) not in (1, 2):
            raise ValueError(f"RWS generation must be 1 or 2; got {generation!r}")
        self.generation = int(generation)
        self.username, self.password = username, password
        self.robotware = "6.08.0134" if self.generation == 1 else "7.10.0"
        self._httpd: _Server | None = None
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

    # ------------------------------------------------------------------ endpoint
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
        self._httpd = _Server((self.host, self._requested_port), self, context)
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
        self._thread.join(10)
        self._httpd, self._thread = None, None

    def _track(self, conn, opened: bool) -> None:
        with self._lock:
            (self._connections.add if opened else self._connections.discard)(conn)

    # ------------------------------------------------------------------ program, with PERS kept
    def _load(self, program) -> None:
        """Link ``program`` into the task (stopped), its PERS data keeping their values unless their
        module was just loaded from a file, as a controller keeps them."""
        old = self.runner.program
        if old is not None:
            self._pers.update(self._pers_values(old))
        self.runner.load(program)
        for symbol in self.runner.program.data:
            key = (symbol.module.lower(), symbol.name.lower())
            if symbol.storage == "PERS" and key in self._pers and symbol.module.lower() not in self._fresh_modules:
                symbol.box[0] = self._pers[key]
        self._fresh_modules.clear()
        self._loaded = program

    def _run(self, program) -> None:
        if getattr(self, "_loaded", None) is not program:
            self._load(program)
        self.runner.start()

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

    # ------------------------------------------------------------------ faults
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

    # ------------------------------------------------------------------ authentication
    def _session_of(self, handler) -> str | None:
        cookies = handler.headers.get("Cookie", "")
        for part in cookies.split(";"):
            name, _, value = part.strip().partition("=")
            if name == "-http-session-" and value in self.sessions:
                return value
        return None

    def _authenticate(self, handler, method: str) -> tuple[str, dict]:
        """The session of the request (a new one after a good login); 401 otherwise."""
        session = self._session_of(handler)
        if session is not None:
            return session, {}
        header = handler.headers.get("Authorization", "")
        if self._credentials_ok(header, method):
            session = secrets.token_hex(12)
            with self._lock:
                self.sessions[session] = {"user": self.username, "rmmp": "none", "rmmp_asked": False}
            return session, {"Set-Cookie": [f"-http-session-={session}; Path=/; HttpOnly",
                                            f"ABBCX={secrets.token_hex(6)}; Path=/"]}
        if self.generation == 1:
            nonce = secrets.token_hex(16)
            self.nonces.add(nonce)
            challenge = f'Digest realm="{REALM}", nonce="{nonce}", qop="auth", algorithm=MD5'
        else:
            challenge = f'Basic realm="{REALM}"'
        raise HttpError(401, "Unauthorized: wrong user name or password" if header else "Unauthorized",
                        headers={"WWW-Authenticate": challenge})

    def _credentials_ok(self, header: str, method: str) -> bool:
        scheme, _, rest = header.partition(" ")
        if self.generation == 2:
            if scheme.lower() != "basic":
                return False
            try:
                user, _, password = base64.b64decode(rest).decode("utf-8").partition(":")
            except (ValueError, UnicodeDecodeError):
                return False
            return user == self.username and password == self.password
        if scheme.lower() != "digest":
            return False
        fields = {}
        for item in _split_header(rest):
            name, _, value = item.partition("=")
            fields[name.strip().lower()] = value.strip().strip('"')
        if fields.get("username") != self.username or fields.get("nonce") not in self.nonces:
            return False
        md5 = lambda text: hashlib.md5(text.encode("utf-8")).hexdigest()  # noqa: E731 - RFC 2617 names
        ha1 = md5(f"{self.username}:{REALM}:{self.password}")
        ha2 = md5(f"{method}:{fields.get('uri', '')}")
        expected = md5(f"{ha1}:{fields['nonce']}:{fields.get('nc', '')}:{fields.get('cnonce', '')}:{fields.get('qop', '')}:{ha2}")
        return secrets.compare_digest(expected, fields.get("response", ""))

    # ------------------------------------------------------------------ answers
    def _wants_json(self, handler, query) -> bool:
        if self.generation == 1:
            return query.get("json", [""])[0] == "1"
        return "json" in handler.headers.get("Accept", "")

    def answer(self, handler, query, states: list, links=None):
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

    def error_body(self, handler, err: HttpError):
        status = {"code": err.code, "msg": err.message}
        if self.generation == 1:
            return json.dumps({"_embedded": {"status": status}}).encode(), "application/json"
        return json.dumps({"status": status}).encode(), HAL_JSON

    # ------------------------------------------------------------------ routing
    def dispatch(self, handler, method: str, body: bytes):
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

    # ------------------------------------------------------------------ reading
    def _read(self, path: str, query) -> list:
        robot = self.robot
        mech = "/rw/motionsystem/mechunits/ROB_1/"
        if path == mech + "jointtarget":
            joints = robot.current_joints
            state = {"_type": "ms-jointtarget", "_title": "ROB_1"}
            state.update({f"rax_{i + 1}": f"{float(v):.6f}" for i, v in enumerate(joints)})
            state.update({f"eax_{c}": "9E+09" for c in "abcdef"})
            return [state]
        if path == mech + "robtarget":
            return [self._robtarget(query)]
        if path in ("/rw/panel/ctrlstate", "/rw/panel/ctrl-state"):
            return [{"_type": "pnl-ctrlstate", "_title": "ctrlstate", "ctrlstate": "motoron" if self.motors_on else "motoroff"}]
        if path == "/rw/panel/opmode":
            return [{"_type": "pnl-opmode", "_title": "opmode", "opmode": self.opmode}]
        if path == "/rw/rapid/execution":
            return [{"_type": "rap-execution", "_title": "execution",
                     "ctrlexecstate": "running" if self.running else "stopped", "cycle": "forever"}]
        if path == "/rw/system":
            return [{"_type": "sys-system", "_title": "system", "name": "handeye-mock", "rwversion": self.robotware,
                     "rwversionname": f"RobotWare {self.robotware}", "sysid": "{mock}"}]
        if path in ("/users/rmmp", "/users/rmmp/poll"):
            return [self._rmmp_state(path)]
        if path == "/rw/rapid/tasks":
            return [{"_type": "rap-task-li", "_title": "T_ROB1", "name": "T_ROB1", "type": "norm",
                     "taskstate": "linked", "excstate": "started" if self.running else "stopped",
                     "active": "On", "motiontask": "TRUE"}]
        symbol = self._symbol_of(path)
        if symbol is not None:
            value = self._symbol(symbol).box[0]
            return [{"_type": "rap-data", "_title": "/".join(s for s in symbol if s), "value": _rws_text(value)}]
        raise HttpError(404, f"no resource {path}", -1073442812)

    def _robtarget(self, query) -> dict:
        tool = query.get("tool", ["tool0"])[0].lower()
        wobj = query.get("wobj", ["wobj0"])[0].lower()
        if tool != "tool0" or wobj != "wobj0":
            raise HttpError(400, f"the mock reports the flange only (tool0, wobj0); got tool={tool}, wobj={wobj}")
        pose = self.robot.tool0_pose()  # what CRobT(\Tool:=tool0 \WObj:=wobj0) gives the program
        p, q = pose.position_mm, pose.quaternion_wxyz
        state = {"_type": "ms-robtargets", "_title": "ROB_1"}
        state.update({c: f"{float(v):.6f}" for c, v in zip("xyz", p)})
        state.update({f"q{i + 1}": f"{float(v):.9f}" for i, v in enumerate(q)})
        state.update({"cf1": "0", "cf4": "0", "cf6": "0", "cfx": "0"})
        state.update({f"eax{c}": "9E+09" for c in "abcdef"})
        return state

    def _rmmp_state(self, path: str) -> dict:
        rights = {s["rmmp"] for s in self.sessions.values()}
        if "modify" in rights:
            status = "GRANTED"
        elif "denied" in rights:
            status = "DENIED"
        elif self.rmmp_policy == "ignore" and any(s.get("rmmp_asked") for s in self.sessions.values()):
            status = "PENDING"  # nobody pressed Allow or Deny on the FlexPendant
        else:
            status = "NONE"
        if path.endswith("poll"):
            return {"_type": "user-rmmp-poll", "_title": "poll", "status": status}
        return {"_type": "user-rmmp", "_title": "rmmp", "privilege": "modify" if status == "GRANTED" else "none",
                "status": status}

    # ------------------------------------------------------------------ symbols
    def _symbol_of(self, path: str):
        """``(task, module or None, name)`` of a symbol path of either generation, else None."""
        if self.generation == 1 or path.startswith("/rw/rapid/symbol/data/"):
            prefix = "/rw/rapid/symbol/data/RAPID/"
            if not path.startswith(prefix):
                return None
            parts = path[len(prefix):].strip("/").split("/")
        else:
            prefix = "/rw/rapid/symbol/RAPID/"
            if not path.startswith(prefix) or not path.endswith("/data"):
                return None
            parts = path[len(prefix):-len("/data")].strip("/").split("/")
        # ABB's documentation names symbols RAPID/<task>/<module>/<name>; abb-robot-client sends
        # RAPID/<task>/<name>, which a controller resolves for global data: both are served.
        if len(parts) == 3:
            return tuple(parts)
        if len(parts) == 2:
            return (parts[0], None, parts[1])
        return None

    def _symbol(self, symbol):
        task, module, name = symbol
        if task.upper() != "T_ROB1":
            raise HttpError(404, f"no task {task}", -1073442812)
        program = self.runner.program if self.runner is not None else None
        found = program.datum(name, module) if program is not None else None
        if found is None:
            where = f"{module}/{name}" if module else name
            raise HttpError(404, f"symbol RAPID/{task}/{where} not found", -1073442812)
        return found

    def _set_symbol(self, symbol, text: str) -> None:
        datum = self._symbol(symbol)
        if datum.storage == "CONST":
            raise HttpError(400, f"{datum.name} is a CONST", -1073442811)
        try:
            value = parse_rapid_value(text)
            if datum.dims:
                new = coerce_array(aggregate(value), datum.type, datum.dims, self.runner.program.records, datum.name)
            else:
                new = coerce(aggregate(value), datum.type, self.runner.program.records, datum.name)
        except (ValueError, RapidError) as exc:
            raise HttpError(400, f"value {text[:60]!r} for {datum.name}: {exc}", -1073442811) from None
        datum.box[0] = new
        self.writes += 1
        if datum.storage == "PERS":
            self._pers[(datum.module.lower(), datum.name.lower())] = new

    # ------------------------------------------------------------------ writing
    def _may_write(self, session: str, what: str, implicit: bool = True) -> None:
        """Refuse a write without the right to it: RMMP in manual mode, mastership held elsewhere.

        RWS 1.0 takes mastership implicitly for a single write when nobody holds it (what
        abb-robot-client relies on); RWS 2.0 requires an explicit request (ABB RWS 2.0 manual).
        """
        if self.opmode.startswith("MAN") and self.sessions.get(session, {}).get("rmmp") != "modify":
            raise HttpError(403, f"{what}: the controller is in manual mode and this client has no RMMP "
                                 "(request it and press Allow on the FlexPendant)", E_RMMP)
        if self.faults.mastership_held:
            raise HttpError(403, f"{what}: mastership is held by another client (FlexPendant)", E_MASTERSHIP)
        if self.master not in (None, session):
            raise HttpError(403, f"{what}: mastership is held by another client", E_MASTERSHIP)
        if self.master is None and not (implicit and self.generation == 1):
            raise HttpError(403, f"{what}: mastership is required; request it first", E_MASTERSHIP)

    def _post(self, path, action, form, session):
        gen2 = self.generation == 2
        if path.startswith("/rw/mastership"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            return self._mastership(verb, session)
        if path == "/users/rmmp":
            return self._request_rmmp(form, session)
        if path == "/rw/panel/restart" or (path == "/rw/panel" and action == "restart"):
            self._may_write(session, "restart")
            self.restart()
            return 204, None
        if path.startswith("/rw/rapid/execution"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            return self._execution(verb, session)
        if path.startswith("/rw/rapid/tasks/T_ROB1"):
            verb = path.rsplit("/", 1)[-1] if gen2 else action
            if verb == "loadmod":
                return self._loadmod(form, session)
            raise HttpError(400, f"task action {verb!r} is not simulated")
        symbol = self._symbol_of(path)
        if symbol is not None and (gen2 or action == "set"):
            if "value" not in form:
                raise HttpError(400, "a symbol write needs the form field value", -1073442811)
            with self._lock:
                self._may_write(session, f"write {'/'.join(s for s in symbol if s)}")
                self._set_symbol(symbol, form["value"])
            return 204, None
        raise HttpError(404, f"no resource {path} (action {action})", -1073442812)

    def _mastership(self, verb, session):
        with self._lock:
            if verb == "request":
                if self.opmode.startswith("MAN") and self.sessions.get(session, {}).get("rmmp") != "modify":
                    raise HttpError(403, "mastership: the controller is in manual mode and this client has no RMMP "
                                         "(request it and press Allow on the FlexPendant)", E_RMMP)
                if self.faults.mastership_held or self.master not in (None, session):
                    raise HttpError(403, "mastership is held by another client (FlexPendant)", E_MASTERSHIP)
                self.master = session
                return 204, None
            if verb == "release":
                if self.master == session:
                    self.master = None
                return 204, None
        raise HttpError(400, f"mastership action {verb!r} unknown")

    def _request_rmmp(self, form, session):
        if form.get("privilege") != "modify":
            raise HttpError(400, "RMMP privilege must be modify")
        self.sessions[session]["rmmp_asked"] = True
        if self.rmmp_policy == "allow":
            self.sessions[session]["rmmp"] = "modify"
        elif self.rmmp_policy == "deny":
            self.sessions[session]["rmmp"] = "denied"
        return 202, None

    def _execution(self, verb, session):
        with self._lock:
            self._may_write(session, f"execution {verb}")
            if verb == "start":
                if not self.motors_on:
                    raise HttpError(409, "cannot start: the motors are off", E_STATE)
                if not self.running:
                    try:
                        self._run(self.source)
                    except RapidError as exc:  # link errors of the loaded modules, as the pendant shows them
                        raise HttpError(409, f"cannot start the program: {exc}", E_STATE) from None
            elif verb == "stop":
                if self.runner is not None:
                    self.runner.stop()
            elif verb != "resetpp":  # the mock always starts from main: resetpp has nothing more to do
                raise HttpError(400, f"execution action {verb!r} unknown")
        return 204, None

    def _loadmod(self, form, session):
        with self._lock:
            self._may_write(session, "load module")
            if self.running:
                raise HttpError(409, "load module: the task is running; stop it first", E_STATE)
            path = form.get("modulepath", "")
            data = self.files.get(self._file_key(path))
            if data is None:
                raise HttpError(400, f"load module: no file {path}", -1073442811)
            name = path.rsplit("/", 1)[-1]
            text = data.decode("latin-1")
            try:
                module = parse_module(text, name).name
            except RapidError as exc:
                raise HttpError(400, f"load module {name}: {exc}", -1073442811) from None
            kept = [m for m in self.source.modules if parse_module(m.text, m.source).name.lower() != module.lower()]
            if len(kept) == len(self.source.modules) or form.get("replace", "false").lower() == "true":
                program = ControllerProgram(tuple(kept) + (ModuleSource(text, name),), self.source.origin,
                                            self.source.link, self.source.tool_name)
                self._fresh_modules.add(module.lower())
                self.source = program
                try:
                    self._load(program)  # linked now: its symbols are there before the start
                except RapidError as exc:
                    # a controller loads a module whose references are not there yet (the next module
                    # brings them); the link errors stop the start, as on the FlexPendant
                    log.info("mock RWS: %s loaded, not linked yet: %s", name, exc)
                    self._loaded = None
            else:
                raise HttpError(409, f"load module: {module} is loaded already (replace=true replaces it)", E_STATE)
        return 204, None

    # ------------------------------------------------------------------ files
    @staticmethod
    def _file_key(path: str) -> str:
        path = path.strip("/")
        return path if path.startswith("$") else "$HOME/" + path

    def _files(self, method, path, body, session):
        key = self._file_key(path)
        if method == "PUT":
            self.files[key] = bytes(body)
            return 201, None
        if method == "DELETE":
            self.files.pop(key, None)
            return 204, None
        if method == "GET" and key in self.files:
            return 200, (self.files[key], "text/plain")
        raise HttpError(404, f"no file {key}", -1073442812)

    # ------------------------------------------------------------------ for tests
    def symbol_value(self, name: str, module: str | None = None):
        """The task's current value of module data ``name`` (tests)."""
        return self._symbol(("T_ROB1", module, name)).box[0]


def _split_header(text: str) -> list:
    """Comma-separated ``name=value`` items of an Authorization header (commas inside quotes kept)."""
    items, current, quoted = [], "", False
    for ch in text:
        if ch == '"':
            quoted = not quoted
        if ch == "," and not quoted:
            items.append(current)
            current = ""
        else:
            current += ch
    if current.strip():
        items.append(current)
    return items
