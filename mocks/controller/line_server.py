"""Mock controller servers speaking the handeye line protocol: TCP (socket) and a serial endpoint.

Both are real TCP servers on 127.0.0.1 run by one thread each. They behave like the single-task
RAPID program: one client at a time, one request at a time, and after accepting ``GOTO`` the
program executes the move before reading the next request (a STATUS sent meanwhile is answered on
arrival). The socket server accepts only ``allowed_client`` (the configured PC address) and closes
the connection on ``BYE``; the serial endpoint is a byte stream reached with pyserial's
``socket://host:port`` URL and, like a serial line, ignores BYE.
"""

from __future__ import annotations

import logging
import selectors
import socket
import threading

from ...drivers.controller import protocol as P
from ...drivers.controller.types import ToolData
from .faults import Faults
from .program import ProgramRefusal, RapidProgram

__all__ = ["LineSession", "SocketControllerServer", "SerialControllerServer"]

log = logging.getLogger(__name__)


class LineSession:
    """One connection's view of the program: the POSE snapshot and the staged tool parts."""

    def __init__(self, program: RapidProgram):
        self.program = program
        self.snapshot = None
        self.staged: dict = {}

    def dispatch(self, request: P.Request) -> tuple[bytes, str]:
        """The reply to ``request`` and what to do after sending it (``""``, ``"move"``, ``"bye"``)."""
        try:
            return self._dispatch(request)
        except ProgramRefusal as refusal:
            return P.encode_error(request.id, refusal.code, str(refusal)), ""

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


class _LineServer:
    """Accept loop and request loop shared by the socket and serial mock servers."""

    kind = "line"
    closes_on_bye = True

    def __init__(self, program: RapidProgram, host: str = "127.0.0.1", port: int = 0,
                 faults: Faults | None = None, allowed_client: str | None = None):
        self.program = program
        self.robot = program.robot
        self.host, self._requested_port = host, port
        self.faults = faults or Faults()
        self.allowed_client = allowed_client
        self._listener: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._wake_r, self._wake_w = None, None
        #: Counters for tests and the CLI.
        self.connections = 0
        self.refused_clients = 0
        self.requests = 0

    # ------------------------------------------------------------------ lifecycle
    @property
    def port(self) -> int:
        if self._listener is None:
            return self._requested_port
        return self._listener.getsockname()[1]

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

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

    # ------------------------------------------------------------------ loops
    def _run(self) -> None:
        with selectors.DefaultSelector() as sel:
            sel.register(self._listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while not self._stop.is_set():
                events = sel.select(timeout=0.5)
                if self._stop.is_set():
                    break
                if not any(key.fileobj is self._listener for key, _ in events):
                    continue
                try:
                    conn, addr = self._listener.accept()
                except BlockingIOError:
                    continue
                if self.allowed_client is not None and addr[0] != self.allowed_client:
                    self.refused_clients += 1
                    conn.close()
                    continue
                self.connections += 1
                try:
                    self._serve(conn)
                except Exception:  # a broken client must not kill the server
                    log.exception("mock %s server: connection failed", self.kind)
                finally:
                    conn.close()

    def _serve(self, conn: socket.socket) -> None:
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        session = LineSession(self.program)
        buffer = bytearray()
        with selectors.DefaultSelector() as sel:
            sel.register(conn, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while not self._stop.is_set():
                end = buffer.find(b"\n")
                if end < 0:
                    if len(buffer) > 4 * P.MAX_MESSAGE:  # a RAPID string would overflow: drop it
                        buffer.clear()
                        self._send(conn, P.encode_error(0, P.E_SYNTAX, "line too long"))
                    events = sel.select(timeout=0.5)
                    if self._stop.is_set():
                        return
                    if not any(key.fileobj is conn for key, _ in events):
                        continue
                    try:
                        chunk = conn.recv(4096)
                    except (BlockingIOError, InterruptedError):
                        continue
                    except OSError:
                        return
                    if not chunk:
                        return
                    buffer += chunk
                    continue
                line = bytes(buffer[:end + 1])
                del buffer[:end + 1]
                if self._handle(conn, line, session) == "close":
                    return

    def _send(self, conn: socket.socket, data: bytes) -> None:
        conn.setblocking(True)
        try:
            conn.sendall(data)
        finally:
            conn.setblocking(False)

    def _handle(self, conn: socket.socket, line: bytes, session: LineSession) -> str:
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
            reply, after = session.dispatch(request)
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
        if after == "bye" and self.closes_on_bye:
            return "close"
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
    """

    kind = "socket"
    closes_on_bye = True

    def client_options(self) -> dict:
        return {"host": self.host, "port": self.port}


class SerialControllerServer(_LineServer):
    """The RAPID serial-channel program, mocked: a byte stream behind ``socket://host:port``."""

    kind = "serial"
    closes_on_bye = False

    def __init__(self, program: RapidProgram, host: str = "127.0.0.1", port: int = 0, faults: Faults | None = None):
        super().__init__(program, host, port, faults, allowed_client=None)

    @property
    def url(self) -> str:
        return f"socket://{self.host}:{self.port}"

    def client_options(self) -> dict:
        return {"url": self.url}
