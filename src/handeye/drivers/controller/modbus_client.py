"""The ``modbus`` back end: the I/O handshake through a Modbus TCP gateway, with pymodbus.

The RAPID program (``HeIo`` module) drives controller signals that a gateway exposes as holding
registers (map: ``modbus_map.yaml``). The handshake for one posture ``k``:

1. PC writes ``request = k`` (robot READY) -> robot MOVING -> after ``MoveAbsJ ... fine``: AT,
   ``posture = k``, ``at_posture = 1``;
2. PC grabs, writes ``grabbed = 1`` -> robot ACKED (``at_posture = 0``);
3. PC writes ``request = 0, grabbed = 0`` -> robot READY.

The robot counts ``heartbeat`` up every publish period; a heartbeat that stops while the gateway
still answers means the RAPID program stopped, reported as a timeout naming it.
"""

from __future__ import annotations

import logging
import os
import time
from typing import Any

import numpy as np

from .errors import InvalidRequest, ProtocolError, StationError
from .interface import Controller, Deadline, LinkDown
from .modbus_map import GUIDED_REGISTERS, STATE_NAMES, RegisterMap, load_register_map
from .polled import PolledHandshake
from .protocol import E_AUTH, E_BUSY, E_STATE, E_TOOL, HINT, VERDICT, ERROR_CODES, KEY_TRIES, PROTOCOL_VERSION, write_key_code
from .types import ACKED, AT, DONE, ERROR, LATE, READY, ControllerInfo, ControllerStatus, FlangePose, ToolData, check_timeout

__all__ = [
    "ModbusController",
    "ModbusExceptionResponse",
    "EXCEPTION_NAMES",
]

log = logging.getLogger(__name__)
# pymodbus logs connection failures at ERROR level; without a handler Python's last-resort handler
# would print them on stderr beside our own one-line error. A NullHandler keeps them out of the
# terminal while an application that configures logging still receives them.
logging.getLogger("pymodbus.logging").addHandler(logging.NullHandler())

EXCEPTION_NAMES = {
    1: "illegal function", 2: "illegal data address", 3: "illegal data value", 4: "server device failure",
    5: "acknowledge", 6: "server device busy", 7: "negative acknowledge", 8: "memory parity error",
    10: "gateway path unavailable", 11: "gateway target device failed to respond",
}


class ModbusExceptionResponse(ProtocolError):
    """The gateway answered with a Modbus exception response.

    Attributes
    ----------
    exception_code : int
    """

    def __init__(self, message: str, exception_code: int):
        super().__init__(message, backend="modbus")
        self.exception_code = exception_code


class ModbusController(PolledHandshake, Controller):
    """The I/O-handshake RAPID program through a Modbus TCP gateway.

    Parameters
    ----------
    host : str
        Address of the gateway.
    port : int
        Modbus TCP port (default 502).
    register_map : str, Path or RegisterMap, optional
        Register map YAML (default: the built-in ``modbus_map.yaml``).
    heartbeat_timeout : float
        A heartbeat that does not change for this long means the robot program stopped (default 1 s).
    poll_s : float
        Polling period while waiting for the robot (default 5 ms).
    **options
        See :class:`~handeye.drivers.controller.interface.Controller`.
    """

    protocol = "modbus"

    def __init__(self, host: str = "127.0.0.1", port: int = 502, *, register_map: str | os.PathLike[str] | RegisterMap | None = None,
                 heartbeat_timeout: float = 1.0, poll_s: float = 0.005, **options: Any):
        if isinstance(port, bool) or not isinstance(port, int) or not 0 < port < 65536:
            raise InvalidRequest(f"TCP port must be an integer 1..65535; got {port!r}")
        self.host, self.port = str(host), int(port)
        self.map = load_register_map(register_map)
        self.heartbeat_timeout = check_timeout("heartbeat_timeout", heartbeat_timeout)
        self.poll_s = check_timeout("poll_s", poll_s)
        super().__init__(**options)
        self._client = None
        self._received = b""
        self._requested = 0

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def is_connected(self) -> bool:
        return self._client is not None and self._client.connected

    # ------------------------------------------------------------------ link
    def _trace_packet(self, sending: bool, data: bytes) -> bytes:
        if not sending:
            self._received = bytes(data)
        return data

    def _open(self, deadline: Deadline) -> None:
        from pymodbus.client import ModbusTcpClient

        client = ModbusTcpClient(self.host, port=self.port, timeout=max(min(self.timeout, deadline.remaining()), 1e-3),
                                 retries=0, reconnect_delay=0, trace_packet=self._trace_packet)
        if not client.connect():
            client.close()
            raise LinkDown(f"cannot connect to the Modbus gateway at {self.address}")
        self._client = client
        try:
            start, count = self.map.span("protocol_version", "posture_count")
            block = self._read(start, count, deadline, "identity")
        except BaseException:
            self._drop()
            raise
        version = self.map.decode("protocol_version", block, start)[0]
        postures = self.map.decode("posture_count", block, start)[0]
        if version != PROTOCOL_VERSION:
            self._drop()
            raise self.protocol_error(
                f"register protocol_version at {self.address} is {version}, expected {PROTOCOL_VERSION}: check the "
                f"register map ({self.map.source}) and that the HeIo RAPID module runs")
        self._info = ControllerInfo(version, "RAPID_IO", postures)

    def _drop(self) -> None:
        if self._client is not None:
            client, self._client = self._client, None
            client.close()

    # ------------------------------------------------------------------ register access
    def _io(self, what: str, call, deadline: Deadline):
        from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

        if self._client is None:
            raise LinkDown("not connected")
        left = deadline.remaining()
        if left <= 0:
            raise self.timeout_error(f"{what}: no time left within {deadline.seconds:g} s")
        self._client.comm_params.timeout_connect = max(min(self.timeout, left), 1e-3)
        self._received = b""
        try:
            response = call(self._client)
        except ConnectionException as exc:
            raise LinkDown(f"{exc}") from None
        except ModbusIOException:
            garbage, self._received = self._received, b""
            self._drop()  # a late response must not be taken for the next one
            if garbage:
                raise self.protocol_error(f"{what}: garbage from {self.address} instead of a Modbus response: "
                                          f"{garbage[:32]!r}") from None
            raise self.timeout_error(f"{what}: no Modbus response from {self.address} within "
                                     f"{self._client_timeout(left):g} s") from None
        except ModbusException as exc:
            self._drop()
            raise self.protocol_error(f"{what}: {exc}") from None
        except OSError as exc:
            raise LinkDown(f"{exc}") from None
        if response.isError():
            code = int(getattr(response, "exception_code", 0) or 0)
            raise ModbusExceptionResponse(
                f"{what}: the gateway at {self.address} answered Modbus exception {code} "
                f"({EXCEPTION_NAMES.get(code, 'unknown')}); check the register map ({self.map.source}) "
                f"and the gateway", code)
        return response

    def _client_timeout(self, left: float) -> float:
        return max(min(self.timeout, left), 1e-3)

    def _read(self, start: int, count: int, deadline: Deadline, what: str) -> list[int]:
        response = self._io(f"read {what} (registers {start}..{start + count - 1})",
                            lambda c: c.read_holding_registers(start, count=count, device_id=self.map.device_id), deadline)
        regs = list(response.registers)
        if len(regs) != count:
            raise self.protocol_error(f"read {what}: asked {count} registers, got {len(regs)}")
        return regs

    def _read_named(self, deadline: Deadline, *names) -> dict:
        start, count = self.map.span(*names)
        block = self._read(start, count, deadline, ", ".join(names))
        return {n: self.map.decode(n, block, start) for n in names}

    def _write_named(self, deadline: Deadline, values: dict) -> None:
        """Write registers; names given together must be adjacent (one request)."""
        names = sorted(values, key=lambda n: self.map[n].address)
        start, count = self.map.span(*names)
        block = []
        for n in names:
            if self.map[n].address != start + len(block):
                raise ValueError(f"registers {names} are not adjacent; write them separately")
            block += self.map.encode(n, values[n])
        self._io(f"write {', '.join(names)}",
                 lambda c: c.write_registers(start, block, device_id=self.map.device_id), deadline)

    # ------------------------------------------------------------------ reading
    def ping(self, timeout: float | None = None) -> float:
        start = time.perf_counter()
        self._call("ping", lambda d: self._read_named(d, "heartbeat"), timeout)
        return time.perf_counter() - start

    def _floats(self, values, what, limit, decimals: int) -> np.ndarray:
        """float32 register values as float64, rounded to the line protocol's precision."""
        arr = np.array(values, dtype=float)
        if not np.all(np.isfinite(arr)) or np.any(np.abs(arr) > limit):
            raise self.protocol_error(f"{what} registers at {self.address} hold {arr.tolist()}: not valid values "
                                      f"(check word_order in {self.map.source})")
        return np.round(arr, decimals)

    def read_joints(self, timeout: float | None = None) -> np.ndarray:
        values = self._call("read joints", lambda d: self._read_named(d, "joints"), timeout)
        return self._floats(values["joints"], "joint", 400.0, 4)

    def read_tool0_pose(self, timeout: float | None = None) -> FlangePose:
        values = self._call("read flange pose", lambda d: self._read_named(d, "tool0_position", "tool0_quaternion"), timeout)
        p = self._floats(values["tool0_position"], "flange position", 4000.0, 3)
        q = self._floats(values["tool0_quaternion"], "flange quaternion", 1.0 + 1e-6, 6)
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > 1e-4:
            raise self.protocol_error(f"flange quaternion from {self.address} is not unit (norm {norm:.6g})")
        q = q / norm
        return FlangePose(p, -q if q[0] < 0 else q)

    def _raw_status(self, deadline: Deadline) -> dict:
        values = self._read_named(deadline, "state", "posture", "at_posture", "error", "heartbeat")
        code = values["state"][0]
        if code not in STATE_NAMES:
            raise self.protocol_error(f"state register at {self.address} holds {code}, not a known state")
        return {"state": STATE_NAMES[code], "posture": values["posture"][0], "error": values["error"][0],
                "heartbeat": values["heartbeat"][0]}

    def status(self, timeout: float | None = None) -> ControllerStatus:
        raw = self._call("read status", self._raw_status, timeout)
        return ControllerStatus(raw["state"], raw["posture"])

    # ------------------------------------------------------------------ waiting
    def _wait_for(self, what: str, done, deadline: Deadline) -> dict:
        """Poll the status until ``done(raw)``; watch the heartbeat; return the last raw status."""
        beat, beat_time = None, time.monotonic()
        while True:
            raw = self._call(what, self._raw_status, deadline=deadline)
            now = time.monotonic()
            if raw["heartbeat"] != beat:
                beat, beat_time = raw["heartbeat"], now
            if done(raw):
                return raw
            if now - beat_time > self.heartbeat_timeout:
                raise self.timeout_error(
                    f"{what}: the robot program at {self.address} stopped (heartbeat stuck at {beat} for "
                    f"{now - beat_time:.2f} s while the gateway answers); check the controller")
            if deadline.remaining() <= self.poll_s:
                raise self.timeout_error(f"{what}: robot is {raw['state']} at posture {raw['posture']} after "
                                         f"{deadline.seconds:g} s")
            time.sleep(self.poll_s)

    def _clear_request(self, deadline: Deadline) -> None:
        self._call("clear the request", lambda d: self._write_named(d, {"request": 0, "grabbed": 0}), deadline=deadline)
        self._requested = 0
        self._wait_for("wait for READY", lambda r: r["state"] == READY, deadline)

    # ------------------------------------------------------------------ motion
    def _send_request(self, k: int, deadline: Deadline) -> None:
        self._call(f"request posture {k}", lambda d: self._write_named(d, {"request": k}), deadline=deadline)

    def _send_acknowledgement(self, k: int, raw: dict, deadline: Deadline) -> None:
        if raw["state"] in (AT, LATE):
            self._call(f"acknowledge posture {k}", lambda d: self._write_named(d, {"grabbed": 1}), deadline=deadline)
            self._wait_for("wait for ACKED", lambda r: r["state"] in (ACKED, READY), deadline)
        if raw["state"] != READY:
            self._clear_request(deadline)

    # ------------------------------------------------------------------ the guided program
    def _guide_registers(self) -> None:
        missing = [n for n in GUIDED_REGISTERS if n not in self.map.registers]
        if missing:
            raise self.refused_error(f"the register map {self.map.source} has no {', '.join(missing)}: the guided "
                                     "program needs them (see src/handeye/drivers/controller/modbus_map.yaml)", E_STATE)

    def guide(self, verdict: int, hint: int, timeout: float | None = None) -> int:
        """Write ``guide_hint`` then ``guide_verdict`` in READY/DONE, wait until the program took them (it
        leaves READY/DONE), clear ``guide_verdict``; returns the ``posture`` register (postures offered)."""
        self._guide_registers()
        VERDICT.format(verdict), HINT.format(hint)  # the codec's ranges
        deadline = self._budget(timeout)
        raw = self._call("read status", self._raw_status, deadline=deadline)
        if raw["state"] not in (READY, DONE):
            raise self.refused_error(f"the guided program at {self.address} is {raw['state']}, not waiting for a "
                                     "verdict", E_STATE)
        self._call("send the hint", lambda d: self._write_named(d, {"guide_hint": hint}), deadline=deadline)
        self._call("send the verdict", lambda d: self._write_named(d, {"guide_verdict": verdict}), deadline=deadline)
        raw = self._poll_state("wait for the program to take the verdict", lambda r: r["state"] not in (READY, DONE),
                               deadline)
        self._call("clear the verdict", lambda d: self._write_named(d, {"guide_verdict": 0}), deadline=deadline)
        if raw is None:
            raise self.timeout_error(f"the guided program at {self.address} did not take the verdict within "
                                     f"{deadline.seconds:g} s")
        return raw["posture"]

    def _poll_state(self, what: str, done, deadline: Deadline) -> dict | None:
        """Poll the status until ``done(raw)`` (the raw status) or the deadline (None). No heartbeat watch: the
        guided program is stopped while the operator jogs."""
        while True:
            raw = self._call(what, self._raw_status)  # each read its own link timeout
            if done(raw):
                return raw
            if deadline.remaining() <= self.poll_s:
                return None
            time.sleep(self.poll_s)

    def wait_operator(self, timeout: float) -> ControllerStatus | None:
        self._guide_registers()
        deadline = Deadline(check_timeout("timeout", timeout))
        raw = self._poll_state("wait for the operator", lambda r: r["state"] in (AT, LATE, DONE), deadline)
        return None if raw is None else ControllerStatus(raw["state"], raw["posture"])

    # ------------------------------------------------------------------ tool data
    def _write_tool(self, tool: ToolData, deadline: Deadline) -> None:
        key = self._write_key
        if key is None:  # set_tool refuses a write without the key before it comes here
            raise InvalidRequest(f"cannot write tool data to {self.address} without the station's write key; "
                                 "nothing was sent")
        raw = self._call("read status", self._raw_status, deadline=deadline)
        if raw["state"] in (ACKED, ERROR):
            self._clear_request(deadline)
        elif raw["state"] != READY:
            raise self.refused_error(f"robot at {self.address} is busy ({raw['state']} at posture {raw['posture']}); "
                                     "tool data is taken only when it is READY: acknowledge the posture first", E_BUSY)
        (last,) = self._call("read tool_ack", lambda d: self._read_named(d, "tool_ack"), deadline=deadline)["tool_ack"]
        seq = last % 0xFFFF + 1
        code = write_key_code(key)
        self._call("write tool values and key", lambda d: self._write_named(d, {"tool_values": tool.values(), "tool_key": code}),
                   deadline=deadline)
        code = self._await_tool_ack(seq, deadline)
        self._clear_key(deadline)  # only once the robot took the command: a late pick-up still finds the key
        if code == E_AUTH:
            raise self.refused_error(
                f"robot at {self.address} refused the tool data: wrong or missing key code (error {code}; after "
                f"{KEY_TRIES} wrong codes it refuses tool data until the RAPID program restarts): check that "
                "controller.write_key in the station config is the key of the HeKey.sys loaded on the controller", code)
        if code:
            raise self.refused_error(f"robot at {self.address} refused the tool data (error {code}: "
                                     f"{ERROR_CODES.get(code, 'error')})", code or E_TOOL)

    def _await_tool_ack(self, seq: int, deadline: Deadline) -> int:
        """Send ``tool_command = seq``, wait for ``tool_ack == seq``; returns ``tool_error``."""
        self._call("write tool command", lambda d: self._write_named(d, {"tool_command": seq}), deadline=deadline)
        beat, beat_time = None, time.monotonic()
        while True:
            values = self._call("wait for tool_ack",
                                lambda d: self._read_named(d, "heartbeat", "tool_ack", "tool_error"), deadline=deadline)
            if values["tool_ack"][0] == seq:
                break
            now = time.monotonic()
            if values["heartbeat"][0] != beat:
                beat, beat_time = values["heartbeat"][0], now
            if now - beat_time > self.heartbeat_timeout:
                raise self.timeout_error(f"write tool data: the robot program at {self.address} stopped "
                                         f"(heartbeat stuck at {beat})")
            if deadline.remaining() <= self.poll_s:
                raise self.timeout_error(f"write tool data: the robot did not take the tool data within {deadline.seconds:g} s")
            time.sleep(self.poll_s)
        return values["tool_error"][0]

    def _clear_key(self, deadline: Deadline) -> None:
        """Zero ``tool_key`` after a tool command, so the code does not linger in the gateway (best effort)."""
        try:
            self._call("clear tool_key", lambda d: self._write_named(d, {"tool_key": 0}), deadline=Deadline(
                max(deadline.remaining(), min(self.timeout, 0.5))))
        except StationError as exc:
            log.info("could not clear tool_key at %s: %s", self.address, exc)

    def read_tool(self, timeout: float | None = None) -> ToolData:
        values = self._call("read tool data", lambda d: self._read_named(d, "tool_readback"), timeout)["tool_readback"]
        arr = self._floats(values, "tool read-back", 4000.0, 6)
        p, q, m, c = arr[0:3], arr[3:7], arr[7], arr[8:11]
        return ToolData(tuple(float(v) for v in np.round(p, 3)), tuple(float(v) for v in q), float(np.round(m, 3)),
                        tuple(float(v) for v in np.round(c, 3)))
