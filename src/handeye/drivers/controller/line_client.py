"""The line protocol over a byte stream: shared by the socket and the serial back ends.

A back end supplies a :class:`LineTransport` (open, write, read one line before a deadline, close);
this module does the rest: request ids, skipping late replies to requests that timed out, turning
``ERR`` replies into :class:`ControllerRefused`, multi-message operations (the flange pose, the tool
data) repeated as a whole when the link dropped half-way.
"""

from __future__ import annotations

import logging
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

import numpy as np

from . import protocol as P
from .errors import ControllerRefused, ControllerTimeout, InvalidRequest
from .interface import Controller, Deadline, LinkDown
from .types import AT, DONE, LATE, MOVING, READY, ControllerInfo, ControllerStatus, FlangePose, ToolData, check_posture_index, check_timeout

__all__ = ["LineTransport", "LineController"]

log = logging.getLogger(__name__)

#: How often ``wait_at_rest`` asks again while the program reports MOVING.
POLL_S = 0.005


class LineTransport(ABC):
    """A byte stream to the controller. Errors: LinkDown (dropped), the controller's timeout class."""

    #: True for a line without connections (serial): what an earlier PC left on it reaches us too.
    shared_line = False

    @abstractmethod
    def open(self, deadline: Deadline) -> None: ...

    @abstractmethod
    def close(self) -> None: ...

    @property
    @abstractmethod
    def is_open(self) -> bool: ...

    @abstractmethod
    def write(self, data: bytes, deadline: Deadline) -> None: ...

    @abstractmethod
    def read_line(self, deadline: Deadline) -> bytes:
        """Bytes up to and including LF; raise the timeout error when the deadline passes first."""


class LineBuffer:
    """Accumulates received bytes and cuts lines; too long a run without LF is garbage."""

    def __init__(self, protocol_error: Callable[[str], Exception]):
        self.data = bytearray()
        self.protocol_error = protocol_error

    def feed(self, chunk: bytes) -> None:
        self.data += chunk

    def take_line(self) -> bytes | None:
        end = self.data.find(b"\n")
        if end < 0:
            if len(self.data) > P.MAX_MESSAGE + 1:
                sample = bytes(self.data[:40])
                self.data.clear()
                raise self.protocol_error(f"garbage from the controller: {len(sample)}+ bytes without a line end "
                                          f"({sample!r}...)")
            return None
        line = bytes(self.data[:end + 1])
        del self.data[:end + 1]
        return line

    def clear(self) -> None:
        self.data.clear()

    def timeout_text(self) -> str:
        """What a timeout message says about bytes received without a line end."""
        if not self.data:
            return "timed out"
        return f"timed out with {len(self.data)} bytes of an unfinished line (garbage?): {bytes(self.data[:40])!r}"


class LineController(Controller):
    """A :class:`Controller` speaking the handeye line protocol over a :class:`LineTransport`."""

    def __init__(self, **options: Any):
        super().__init__(**options)
        self._transport: LineTransport | None = None
        self._last_id = 0
        #: Late replies skipped (to requests that had timed out).
        self.stale_replies = 0
        #: Replies dropped while flushing a shared (serial) line at connect.
        self.flushed_replies = 0
        #: The id of a STATUS still waiting for its reply (``wait_operator``).
        self._pending_status: int | None = None
        #: When the last line came from the controller (monotonic): a shared line quiet for the idle
        #: timeout is woken with a PING first (see :meth:`_flush_line`).
        self._heard_at: float | None = None

    # ------------------------------------------------------------------ link
    @abstractmethod
    def _make_transport(self) -> LineTransport: ...

    @property
    def is_connected(self) -> bool:
        return self._transport is not None and self._transport.is_open

    def _link(self) -> LineTransport:
        """The open transport (:class:`LinkDown` when there is none: the call reconnects)."""
        if self._transport is None:
            raise LinkDown("not connected")
        return self._transport

    def _open(self, deadline: Deadline) -> None:
        transport = self._make_transport()
        transport.open(deadline)
        self._transport = transport
        try:
            if transport.shared_line:
                self._flush_line(deadline)
            (version, program), (count,) = self._exchange([("VERSION", ()), ("COUNT", ())], deadline)
        except BaseException:
            self._drop()
            raise
        if version != P.PROTOCOL_VERSION:
            self._drop()
            raise self.protocol_error(
                f"the controller at {self.address} speaks handeye protocol {version}, this PC speaks "
                f"{P.PROTOCOL_VERSION}: regenerate and load the RAPID modules with `handeye rapid generate`")
        self._info = ControllerInfo(version, program, count)

    def _flush_line(self, deadline: Deadline) -> None:
        """Start clean on a shared line: end whatever it holds with a line break, then PING.

        A serial line may hold the unfinished request of a PC that died mid-line (the controller
        would glue our first request to it) and late replies to an earlier PC. The line break ends
        the unfinished request; every reply before the PING's own ``OK`` is dropped. A line that is
        no reply at all (an echo, noise) is a protocol error, as everywhere.

        The program clears its input buffer each idle timeout while nothing arrives, and a clear that
        falls as our line arrives discards it: no reply ever comes. So a PING unanswered for half
        the idle timeout is sent again (a new id; a late reply to the first is dropped like the rest),
        within ``deadline``. PING changes nothing on the controller, so sending it twice is harmless.
        """
        resend_s = max(self.idle_timeout / 2.0, 0.05)
        while True:
            request_id = self._next_id()
            self._link().write(b"\n" + P.encode_request(request_id, "PING"), deadline)
            if deadline.remaining() <= resend_s:
                self._await_pong(request_id, deadline)
                return
            try:
                self._await_pong(request_id, Deadline(resend_s))
                return
            except ControllerTimeout:
                log.debug("no reply to PING %d within %.2f s on %s: sending it again", request_id, resend_s,
                          self.address)

    def _await_pong(self, request_id: int, deadline: Deadline) -> None:
        """Read lines up to the reply to PING ``request_id``, dropping every other reply."""
        while True:
            raw = self._read_line("PING", deadline)
            if not raw.strip(b"\r\n"):
                continue  # our own line break, echoed
            reply = self._parse_reply(raw, "PING")
            if reply.id == request_id and reply.ok and not reply.tokens:
                return
            self.flushed_replies += 1
            log.debug("dropping %r left on the line before our PING", raw)

    def _drop(self) -> None:
        self._pending_status = None
        if self._transport is not None:
            transport, self._transport = self._transport, None
            transport.close()

    def _goodbye(self) -> None:
        deadline = Deadline(min(self.timeout, 0.5))
        self._exchange([("BYE", ())], deadline)

    # ------------------------------------------------------------------ requests
    def _next_id(self) -> int:
        self._last_id = self._last_id % P.MAX_ID + 1
        return self._last_id

    def _exchange(self, steps, deadline: Deadline) -> list[tuple]:
        """Send each ``(command, args)`` in turn and return the typed values of each OK reply."""
        self._pending_status = None  # its reply, if it comes, is skipped as late
        if (self._transport is not None and self._transport.shared_line and self._heard_at is not None
                and time.monotonic() - self._heard_at >= self.idle_timeout):
            self._flush_line(deadline)  # the program may be clearing its buffer as our request arrives
        results = []
        for command, args in steps:
            request_id = self._next_id()
            try:
                data = P.encode_request(request_id, command, *args)
            except ValueError as exc:
                raise InvalidRequest(f"{command}: {exc}; nothing was sent") from None
            if self._transport is None:
                raise LinkDown("not connected")
            self._transport.write(data, deadline)
            reply = self._read_reply(request_id, command, deadline)
            if not reply.ok:
                meaning = P.ERROR_CODES.get(reply.code, "unknown error")
                refused = self.refused_error(
                    f"controller at {self.address} refused {command}: {reply.message or meaning} (error {reply.code}: {meaning})",
                    reply.code)
                refused.reason = reply.message or meaning
                raise refused
            try:
                results.append(P.decode_values(command, reply))
            except P.ProtocolError as exc:
                raise self.protocol_error(f"bad {command} reply from {self.address}: {exc.detail}") from None
        return results

    def _read_line(self, command: str, deadline: Deadline) -> bytes:
        """One line from the transport, its failures worded for ``command``."""
        try:
            line = self._link().read_line(deadline)
            self._heard_at = time.monotonic()
            return line
        except P.ProtocolError as exc:
            raise self.protocol_error(f"{command}: {exc.detail}") from None
        except ControllerTimeout as exc:
            raise self.timeout_error(f"{command}: no reply from the controller at {self.address} within "
                                     f"{deadline.seconds:g} s ({exc.detail})") from None

    def _parse_reply(self, raw: bytes, command: str) -> P.Reply:
        try:
            return P.parse_reply(raw)
        except P.ProtocolError as exc:
            raise self.protocol_error(f"garbage from the controller at {self.address} after {command}: {exc.detail}") from None

    def _read_reply(self, request_id: int, command: str, deadline: Deadline) -> P.Reply:
        while True:
            raw = self._read_line(command, deadline)
            reply = self._parse_reply(raw, command)
            if reply.id == request_id:
                return reply
            if reply.id == 0 and not reply.ok:
                raise self.protocol_error(f"the controller at {self.address} could not read our {command} request "
                                          f"(ERR {reply.code} {reply.message}); check line noise / settings")
            self.stale_replies += 1
            log.debug("skipping late reply %r while waiting for id %d", raw, request_id)

    def _run(self, what: str, steps, timeout=None, deadline=None) -> list[tuple]:
        return self._call(what, lambda d: self._exchange(steps, d), timeout, deadline)

    # ------------------------------------------------------------------ reading
    def ping(self, timeout: float | None = None) -> float:
        start = time.perf_counter()
        self._run("ping", [("PING", ())], timeout)
        return time.perf_counter() - start

    def read_joints(self, timeout: float | None = None) -> np.ndarray:
        (values,) = self._run("read joints", [("JOINTS", ())], timeout)
        return np.array(values, dtype=float)

    def read_tool0_pose(self, timeout: float | None = None) -> FlangePose:
        position, quaternion = self._run("read flange pose", [("POSE", ()), ("QUAT", ())], timeout)
        q = np.array(quaternion, dtype=float)
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > 1e-4:
            raise self.protocol_error(f"flange quaternion from {self.address} is not unit (norm {norm:.6g})")
        q = q / norm
        return FlangePose(np.array(position, dtype=float), -q if q[0] < 0 else q)

    def status(self, timeout: float | None = None) -> ControllerStatus:
        return self._status(self._budget(timeout))

    def _status(self, deadline: Deadline) -> ControllerStatus:
        ((state, posture),) = self._run("read status", [("STATUS", ())], deadline=deadline)
        return ControllerStatus(state, posture)

    # ------------------------------------------------------------------ motion
    def _request_posture(self, k: int, deadline: Deadline) -> None:
        ((echo,),) = self._run(f"go to posture {k}", [("GOTO", (k,))], deadline=deadline)
        if echo != k:
            raise self.protocol_error(f"controller accepted posture {echo} when asked for {k}")

    def wait_at_rest(self, k: int | None = None, timeout: float | None = None, *,
                     deadline: Deadline | None = None) -> ControllerStatus:
        # A single-task RAPID program answers STATUS only after MoveAbsJ ... fine returned, so one
        # STATUS may take the whole move: it gets the whole remaining budget.
        deadline = deadline or Deadline(self.motion_timeout if timeout is None else timeout)
        while True:
            status = self._status(deadline)
            if status.state != MOVING:
                if k is not None and not status.at_posture(k):
                    raise self.refused_error(f"robot is {status.state} at posture {status.posture}, not at posture {k}")
                return status
            if deadline.remaining() <= POLL_S:
                raise self.timeout_error(f"robot still moving to posture {status.posture} after {deadline.seconds:g} s")
            time.sleep(POLL_S)

    def acknowledge(self, k: int, timeout: float | None = None) -> ControllerStatus:
        k = check_posture_index(k)
        deadline = self._budget(timeout)
        ((echo,),) = self._run(f"acknowledge posture {k}", [("ACK", (k,))], deadline=deadline)
        if echo != k:
            raise self.protocol_error(f"controller acknowledged posture {echo} when told {k}")
        return self._status(deadline)

    # ------------------------------------------------------------------ the guided program
    def guide(self, verdict: int, hint: int, timeout: float | None = None) -> int:
        ((offered,),) = self._run("send the verdict and hint", [("GUIDE", (verdict, hint))], timeout)
        return offered

    def wait_operator(self, timeout: float) -> ControllerStatus | None:
        # One STATUS waits for the program to serve again (it prompts, or is stopped): a later call reads on
        # for the same reply rather than queueing more requests on the line. (No wake PING here, unlike
        # _exchange: a program that prompts reads nothing, and a PING per poll would pile up on its line.)
        def wait(deadline: Deadline) -> tuple:
            if self._pending_status is None:
                request_id = self._next_id()
                self._link().write(P.encode_request(request_id, "STATUS"), deadline)
                self._pending_status = request_id
            reply = self._read_reply(self._pending_status, "STATUS", deadline)
            self._pending_status = None
            if not reply.ok:
                raise self.refused_error(f"controller at {self.address} refused STATUS: {reply.message}", reply.code)
            try:
                return P.decode_values("STATUS", reply)
            except P.ProtocolError as exc:
                raise self.protocol_error(f"bad STATUS reply from {self.address}: {exc.detail}") from None

        try:
            state, posture = self._call("wait for the operator", wait, deadline=Deadline(check_timeout("timeout", timeout)))
        except ControllerTimeout:
            return None  # the program prompts or is stopped: its reply comes later
        return ControllerStatus(state, posture) if state in (AT, LATE, DONE) else None

    # ------------------------------------------------------------------ tool data
    def _write_tool(self, tool: ToolData, deadline: Deadline) -> None:
        p, q, m, c = tool.as_arrays()
        steps = [("KEY", (self._write_key,)), ("TOOLPOS", tuple(p)), ("TOOLROT", tuple(q)), ("TOOLLOAD", (m, *c)),
                 ("TOOLSAVE", ())]
        try:
            self._run("write tool data", steps, deadline=deadline)
        except ControllerRefused as exc:
            if exc.code != P.E_AUTH:
                raise
            reason = getattr(exc, "reason", "not authorised")
            raise self.refused_error(
                f"the controller at {self.address} refused to write tool data: {reason} (error {exc.code}); check "
                "that controller.write_key in the station config is the key of the HeKey.sys loaded on the "
                "controller (handeye rapid generate --config STATION.yaml -o DIR writes it)", exc.code) from None

    def read_tool(self, timeout: float | None = None) -> ToolData:
        p, q, load = self._run("read tool data", [("GETTOOLPOS", ()), ("GETTOOLROT", ()), ("GETTOOLLOAD", ())], timeout)
        return ToolData(tuple(p), tuple(q), load[0], tuple(load[1:]))


# States a STATUS reply may report over the line protocol.
LINE_STATES = (READY, MOVING, AT, LATE)
