"""Mock controller servers speaking the handeye line protocol: TCP (socket) and a serial endpoint.

Both are real TCP servers on 127.0.0.1 run by one thread each. They behave like the single-task
RAPID program (``HeSocket`` / ``HeSerial``, see ``rapid/PROTOCOL.md``): one PC at a time, one
request at a time, and after accepting ``GOTO`` the program executes the move before reading the
next request (a STATUS sent meanwhile is answered on arrival).

The link recovers by itself, as the RAPID modules do:

- socket: the server accepts only ``allowed_client`` (the configured PC address; None: any) and
  closes the connection on ``BYE``. A PC that sends no complete request for ``idle_timeout_s``
  while the program waits for requests is disconnected, and the server accepts again. A new
  connection from the PC while one is open takes over at once (the PC restarted; its old
  connection is dead or half-open); one from another address is closed.
- serial: a byte stream reached with pyserial's ``socket://host:port`` URL, standing for a serial
  line. A line has no connections: the newest TCP connection owns the wire at once (the older one is
  closed), and the program's session (POSE snapshot, staged tool parts, authorisation) and any
  unfinished line carry over, as they would on a wire. After ``idle_timeout_s`` without a complete
  request the session is forgotten and the unfinished line discarded (``HeNewSession`` +
  ``ClearIOBuff``); ``BYE`` ends the session too.

Tool writes need ``KEY <write_key>`` first in the session (error 9 otherwise); after
:data:`~handeye.drivers.controller.protocol.KEY_TRIES` wrong keys a session gets no more tries
(socket: the connection is closed).
"""

from __future__ import annotations

import logging
import selectors
import socket
import threading
import time

from ...drivers.controller import protocol as P
from ...drivers.controller.types import ToolData, check_write_key
from .faults import Faults
from .program import ProgramRefusal, RapidProgram

__all__ = ["LineSession", "SocketControllerServer", "SerialControllerServer", "DEFAULT_IDLE_TIMEOUT_S"]

log = logging.getLogger(__name__)

#: The RAPID modules' default idle timeout (``controller.idle_timeout_s``).
DEFAULT_IDLE_TIMEOUT_S = 5.0
#: What the mock answers KEY with when it was started without a write key.
NO_KEY_TEXT = "no write key: start the mock with --write-key or --config"


class LineSession:
    """One session's view of the program: the POSE snapshot, the staged tool parts, the authorisation.

    Parameters
    ----------
    program : RapidProgram
    write_key : str, optional
        The key KEY must carry (``HE_WRITE_KEY`` of HeKey.sys); None refuses every KEY.
    """

    def __init__(self, program: RapidProgram, write_key: str | None = None):
        self.program = program
        self.write_key = write_key
        self.reset()

    def reset(self) -> None:
        """Forget everything of the session (``HeNewSession``)."""
        self.snapshot = None
        self.staged: dict = {}
        self.authorised = False
        self.key_failures = 0

    @property
    def locked(self) -> bool:
        """True after :data:`KEY_TRIES` wrong keys: no more KEY in this session."""
        return self.key_failures >= P.KEY_TRIES

    def dispatch(self, request: P.Request) -> tuple[bytes, str]:
        """The reply to ``request`` and what to do after sending it (``""``, ``"move"``, ``"bye"``, ``"locked"``)."""
        try:
            return self._dispatch(request)
        except ProgramRefusal as refusal:
            after = "locked" if (request.command == "KEY" and self.locked) else ""
            return P.encode_error(request.id, refusal.code, str(refusal)), after

    def _check_key(self, key: str) -> None:
        if self.write_key is None:
            raise ProgramRefusal(P.E_AUTH, NO_KEY_TEXT)
        if self.locked:
            raise ProgramRefusal(P.E_AUTH, "too many wrong keys")
        if key != self.write_key:
            self.authorised = False
            self.key_failures += 1
            raise ProgramRefusal(P.E_AUTH, "wrong key")
        self.authorised = True

    def _dispatch(self, request: P.Request) -> tuple[bytes, str]:
        program, robot = self.program, self.program.robot
        cmd, args = request.command, request.args
        ok = lambda *values: P.encode_ok(request, *values)  # noqa: E731
        if cmd == "PING":
            return ok(), ""
        if cmd == "VERSION":
            return ok(P.PROTOCOL_VERSION, program.name), ""
        if cmd == "COUNT":
            return ok(program.count), ""
        if cmd == "JOINTS":
            return ok(*robot.current_joints), ""
        if cmd == "POSE":
            self.snapshot = robot.tool0_pose()
            return ok(*self.snapshot.position_mm), ""
        if cmd == "QUAT":
            if self.snapshot is None:
                raise ProgramRefusal(P.E_STATE, "no POSE snapshot on this connection: send POSE first")
            return ok(*self.snapshot.quaternion_wxyz), ""
        if cmd == "GOTO":
            moved = program.request(args[0])
            return ok(args[0]), "move" if moved else ""
        if cmd == "STATUS":
            state, posture = program.status()
            return ok(state, posture), ""
        if cmd == "ACK":
            program.acknowledge(args[0])
            return ok(args[0]), ""
        if cmd == "KEY":
            self._check_key(args[0])
            return ok(), ""
        if cmd in ("TOOLPOS", "TOOLROT", "TOOLLOAD", "TOOLSAVE") and not self.authorised:
            raise ProgramRefusal(P.E_AUTH, "not authorised: send KEY first")
        if cmd in ("TOOLPOS", "TOOLROT", "TOOLLOAD"):
            self.staged[cmd] = args
            return ok(), ""
        if cmd == "TOOLSAVE":
            missing = [c for c in ("TOOLPOS", "TOOLROT", "TOOLLOAD") if c not in self.staged]
            if missing:
                raise ProgramRefusal(P.E_TOOL, f"incomplete tool data: send {', '.join(missing)} first")
            load = self.staged["TOOLLOAD"]
            program.apply_tool(ToolData(self.staged["TOOLPOS"], self.staged["TOOLROT"], load[0], load[1:]))
            self.staged.clear()
            self.authorised = False  # one KEY, one write
            return ok(), ""
        tool = robot.tool
        if cmd == "GETTOOLPOS":
            return ok(*tool.position_mm), ""
        if cmd == "GETTOOLROT":
            return ok(*tool.quaternion_wxyz), ""
        if cmd == "GETTOOLLOAD":
            return ok(tool.mass_kg, *tool.cog_mm), ""
        if cmd == "BYE":
            return ok(), "bye"
        raise ProgramRefusal(P.E_UNKNOWN, f"unknown command {cmd}")  # pragma: no cover - SPECS covers all


class _Link:
    """What the program holds of its PC: the session, the unfinished line, the idle clock."""

    def __init__(self, session: LineSession):
        self.session = session
        self.buffer = bytearray()
        self.fresh = True  # nothing received since the session (re)started
        self.restart_idle()

    def restart_idle(self) -> None:
        self.last = time.monotonic()

    def idle_left(self, idle_timeout_s: float) -> float:
        return idle_timeout_s - (time.monotonic() - self.last)


class _LineServer:
    """Accept loop and request loop shared by the socket and serial mock servers."""

    kind = "line"

    def __init__(self, program: RapidProgram, host: str = "127.0.0.1", port: int = 0,
                 faults: Faults | None = None, allowed_client: str | None = None, *,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        if not (isinstance(idle_timeout_s, (int, float)) and 0 < idle_timeout_s < float("inf")):
            raise ValueError(f"idle_timeout_s must be a positive number of seconds; got {idle_timeout_s!r}")
        self.program = program
        self.robot = program.robot
        self.host, self._requested_port = host, port
        self.faults = faults or Faults()
        self.allowed_client = allowed_client
        self.idle_timeout_s = float(idle_timeout_s)
        self._write_key = check_write_key(write_key)
        self._listener: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._wake_r, self._wake_w = None, None
        #: Counters for tests and the CLI.
        self.connections = 0
        self.refused_clients = 0
        self.requests = 0
        self.takeovers = 0
        self.idle_closes = 0
        self.idle_resets = 0

    # ------------------------------------------------------------------ lifecycle
    @property
    def port(self) -> int:
        if self._listener is None:
            return self._requested_port
        return self._listener.getsockname()[1]

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def has_write_key(self) -> bool:
        """True when the mock was given a write key (tool writes possible after KEY)."""
        return self._write_key is not None

    def start(self):
        if self._thread is not None:
            return self
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            listener.bind((self.host, self._requested_port))
            listener.listen(4)
        except OSError:
            listener.close()
            raise
        listener.setblocking(False)
        self._listener = listener
        self._wake_r, self._wake_w = socket.socketpair()
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"mock-{self.kind}-{self.port}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        if self._thread is None:
            return
        self._stop.set()
        try:
            self._wake_w.send(b"x")
        except OSError:
            pass
        self._thread.join(timeout=5)
        self._thread = None
        for s in (self._listener, self._wake_r, self._wake_w):
            if s is not None:
                s.close()
        self._listener = self._wake_r = self._wake_w = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # ------------------------------------------------------------------ what differs between socket and serial
    def _link_for(self, previous: _Link | None) -> _Link:
        """The link state a newly accepted connection starts with."""
        raise NotImplementedError

    def _on_idle(self, link: _Link) -> bool:
        """The PC was silent for ``idle_timeout_s``; True to close the connection."""
        raise NotImplementedError

    # ------------------------------------------------------------------ loops
    def _accept_pending(self) -> socket.socket | None:
        """Accept one waiting connection; None if there is none or it is not the PC (then closed)."""
        try:
            conn, addr = self._listener.accept()
        except (BlockingIOError, InterruptedError):
            return None
        except OSError:
            return None
        if self.allowed_client is not None and addr[0] != self.allowed_client:
            self.refused_clients += 1
            conn.close()
            return None
        self.connections += 1
        return conn

    def _run(self) -> None:
        link = None
        with selectors.DefaultSelector() as sel:
            sel.register(self._listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while not self._stop.is_set():
                events = sel.select(timeout=0.5)
                if self._stop.is_set():
                    break
                if not any(key.fileobj is self._listener for key, _ in events):
                    continue
                conn = self._accept_pending()
                while conn is not None and not self._stop.is_set():
                    link = self._link_for(link)
                    following = None
                    try:
                        following = self._serve(conn, link)
                    except Exception:  # a broken client must not kill the server
                        log.exception("mock %s server: connection failed", self.kind)
                    finally:
                        conn.close()
                    conn = following
                if conn is not None:
                    conn.close()

    def _serve(self, conn: socket.socket, link: _Link) -> socket.socket | None:
        """Serve one connection; returns the connection that took over, or None when it ended."""
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        buffer = link.buffer
        with selectors.DefaultSelector() as sel:
            sel.register(conn, selectors.EVENT_READ)
            sel.register(self._listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while not self._stop.is_set():
                end = buffer.find(b"\n")
                if end >= 0:
                    line = bytes(buffer[:end + 1])
                    del buffer[:end + 1]
                    link.restart_idle()
                    link.fresh = False
                    if self._handle(conn, line, link) == "close":
                        return None
                    continue
                if len(buffer) > 4 * P.MAX_MESSAGE:  # a RAPID string would overflow: drop it
                    buffer.clear()
                    self._send(conn, P.encode_error(0, P.E_SYNTAX, "line too long"))
                left = link.idle_left(self.idle_timeout_s)
                if left <= 0:
                    if self._on_idle(link):
                        return None
                    left = self.idle_timeout_s
                events = sel.select(timeout=min(0.5, left))
                if self._stop.is_set():
                    return None
                ready = {key.fileobj for key, _ in events}
                if conn in ready:  # the PC's data first, as RAPID receives before it looks at the listener
                    try:
                        chunk = conn.recv(4096)
                    except (BlockingIOError, InterruptedError):
                        continue
                    except OSError:
                        return None
                    if not chunk:
                        return None
                    buffer += chunk
                    link.fresh = False
                    continue
                if self._listener in ready:
                    newcomer = self._accept_pending()
                    if newcomer is not None:
                        self.takeovers += 1
                        log.info("mock %s server: a new connection takes over the link", self.kind)
                        return newcomer
        return None

    def _send(self, conn: socket.socket, data: bytes) -> None:
        conn.setblocking(True)
        try:
            conn.sendall(data)
        finally:
            conn.setblocking(False)

    def _handle(self, conn: socket.socket, line: bytes, link: _Link) -> str:
        self.requests += 1
        faults = self.faults
        if faults.silent:
            faults.note("silent")
            return ""
        if faults.should_drop():
            return "close"
        try:
            request = P.parse_request(line)
        except P.RequestError as exc:
            reply, after = P.encode_error(exc.request_id, exc.code, str(exc)), ""
        else:
            reply, after = link.session.dispatch(request)
        if faults.delay_s > 0 and self._stop.wait(faults.delay_s):
            return "close"
        if faults.take("garbage_next"):
            faults.note("garbage")
            reply = faults.garbage
        try:
            self._send(conn, reply)
        except OSError:
            return "close"
        if after == "move":
            self.program.wait_move(self._stop)
            link.restart_idle()  # the program waits for requests again only now
        return self._after(after, link)

    def _after(self, after: str, link: _Link) -> str:
        """What the module does after sending a reply that asks for more (``bye``, ``locked``)."""
        return ""


class SocketControllerServer(_LineServer):
    """The RAPID socket server module, mocked: a TCP server on ``host:port``.

    Parameters
    ----------
    program : RapidProgram
    host : str
        Address to bind (default 127.0.0.1).
    port : int
        0 picks a free port (see :attr:`port` after :meth:`start`).
    faults : Faults, optional
    allowed_client : str, optional
        The only client address accepted (the RAPID module's ``HE_PC_ADDRESS``); None accepts any.
    idle_timeout_s : float
        A connected PC silent this long is disconnected (``HE_IDLE_TIMEOUT``).
    write_key : str, optional
        The key ``KEY`` must carry for tool writes (None: tool writes refused).
    """

    kind = "socket"

    def _link_for(self, previous):
        return _Link(LineSession(self.program, self._write_key))  # a new connection starts clean

    def _on_idle(self, link) -> bool:
        self.idle_closes += 1
        log.info("mock socket server: PC silent for %.3g s, connection closed", self.idle_timeout_s)
        return True

    def _after(self, after, link) -> str:
        return "close" if after in ("bye", "locked") else ""

    def client_options(self) -> dict:
        options = {"host": self.host, "port": self.port, "idle_timeout": self.idle_timeout_s}
        if self._write_key is not None:
            options["write_key"] = self._write_key
        return options


class SerialControllerServer(_LineServer):
    """The RAPID serial-channel program, mocked: a byte stream behind ``socket://host:port``.

    A new TCP connection takes the "line" over at once; session and unfinished line carry over
    until ``idle_timeout_s`` of silence or ``BYE`` resets them (see the module docstring).
    """

    kind = "serial"

    def __init__(self, program: RapidProgram, host: str = "127.0.0.1", port: int = 0, faults: Faults | None = None, *,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        super().__init__(program, host, port, faults, allowed_client=None, idle_timeout_s=idle_timeout_s,
                         write_key=write_key)

    def _link_for(self, previous):
        return previous if previous is not None else _Link(LineSession(self.program, self._write_key))  # one wire

    def _on_idle(self, link) -> bool:
        if not link.fresh:
            self.idle_resets += 1
            log.info("mock serial line: silent for %.3g s, session reset", self.idle_timeout_s)
        link.session.reset()
        link.buffer.clear()
        link.fresh = True
        link.restart_idle()
        return False

    def _after(self, after, link) -> str:
        if after == "bye":
            link.session.reset()  # BYE ends the session (the line stays open)
        return ""

    @property
    def url(self) -> str:
        return f"socket://{self.host}:{self.port}"

    def client_options(self) -> dict:
        options = {"url": self.url, "idle_timeout": self.idle_timeout_s}
        if self._write_key is not None:
            options["write_key"] = self._write_key
        return options
