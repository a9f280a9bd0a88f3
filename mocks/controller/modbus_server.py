"""Mock Modbus TCP gateway + the RAPID I/O-handshake program (``HeIo``), on a real pymodbus server.

The server is pymodbus' ``ModbusTcpServer`` on 127.0.0.1 with one device whose holding registers
follow the register map (``drivers/controller/modbus_map.yaml`` by default). A task in the same
asyncio loop plays the RAPID program: every ``publish_period_s`` it publishes joints, flange pose
and a heartbeat (as the RAPID timer interrupt does) and steps the handshake (request -> MOVING ->
AT -> grabbed -> ACKED -> cleared -> READY; tool_command -> tool data applied -> tool_ack).

Faults (see :class:`Faults`): delayed responses, exception responses, garbage instead of a
response, dropped connections, a gateway that stops answering (``silent``) and a RAPID program
that stops while the gateway still answers (``robot_stalled``: the heartbeat freezes).

The gateway serves several connections at once (a silent client blocks nobody) and closes a
connection silent for ``idle_timeout_s``, as gateways commonly do, so a PC that vanished does not
hold a connection slot. Tool data are applied only with the write key's code in ``tool_key``
(``HeKey``); after :data:`~handeye.drivers.controller.protocol.KEY_TRIES` wrong codes every tool
command is refused until the program restarts (a new mock).
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time

from ...drivers.controller import protocol as P
from ...drivers.controller.modbus_map import STATE_CODES, load_register_map
from ...drivers.controller.types import ACKED, AT, ERROR, LATE, READY, ToolData, check_write_key, write_key_code
from .faults import Faults
from .line_server import DEFAULT_IDLE_TIMEOUT_S
from .program import ProgramRefusal, RapidProgram

__all__ = ["ModbusControllerServer"]

log = logging.getLogger(__name__)


def _server_classes():
    """pymodbus server and handler subclasses with fault injection (imported lazily)."""
    from pymodbus.server import ModbusTcpServer
    from pymodbus.server.requesthandler import ServerRequestHandler

    class FaultyHandler(ServerRequestHandler):
        def callback_connected(self) -> None:
            self.last_activity = time.monotonic()
            super().callback_connected()

        def callback_data(self, data: bytes, addr=None) -> int:
            self.last_activity = time.monotonic()
            faults = self.server.faults
            if faults.silent:
                faults.note("silent")
                return len(data)
            if faults.should_drop():
                self.close()
                return len(data)
            return super().callback_data(data, addr)

        def server_send(self, pdu, addr):
            faults = self.server.faults
            if pdu and faults.take("garbage_next"):
                faults.note("garbage")
                self.send(faults.garbage, addr)
                return
            super().server_send(pdu, addr)

    class FaultyTcpServer(ModbusTcpServer):
        def __init__(self, context, faults: Faults, **kwargs):
            self.faults = faults
            super().__init__(context, **kwargs)

        def callback_new_connection(self):
            return FaultyHandler(self, self.trace_packet, self.trace_pdu, self.trace_connect)

    return FaultyTcpServer


class ModbusControllerServer:
    """A real Modbus TCP server playing gateway + RAPID I/O program.

    Parameters
    ----------
    program : RapidProgram
    host : str
    port : int
        0 picks a free port (see :attr:`port` after :meth:`start`).
    register_map : path or RegisterMap, optional
    faults : Faults, optional
    publish_period_s : float
        Period of the RAPID program's timer (joints, pose, heartbeat, handshake); default 0.005 s.
    idle_timeout_s : float
        The gateway closes a connection silent this long.
    write_key : str, optional
        The station's write key; tool commands need its code in ``tool_key`` (None: all refused).
    """

    kind = "modbus"

    def __init__(self, program: RapidProgram, host: str = "127.0.0.1", port: int = 0, register_map=None,
                 faults: Faults | None = None, publish_period_s: float = 0.005, *,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        if not (isinstance(idle_timeout_s, (int, float)) and 0 < idle_timeout_s < float("inf")):
            raise ValueError(f"idle_timeout_s must be a positive number of seconds; got {idle_timeout_s!r}")
        self.idle_timeout_s = float(idle_timeout_s)
        key = check_write_key(write_key)
        self._write_key = key
        self._write_code = None if key is None else write_key_code(key)
        self._key_failures = 0
        #: Connections closed for idleness (for tests).
        self.idle_closes = 0
        self.program = program
        self.robot = program.robot
        self.host, self._requested_port, self._port = host, port, None
        self.map = load_register_map(register_map)
        self.faults = faults or Faults()
        self.publish_period_s = float(publish_period_s)
        self._bank = [0] * self.map.size
        self._bank_lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._started = threading.Event()
        self._error: BaseException | None = None
        self._heartbeat = 0
        self._tool_seq = 0
        self.requests = 0

    # ------------------------------------------------------------------ lifecycle
    @property
    def port(self) -> int:
        return self._port if self._port is not None else self._requested_port

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def has_write_key(self) -> bool:
        """True when the mock was given a write key (tool writes possible with its code)."""
        return self._write_code is not None

    def client_options(self) -> dict:
        options = {"host": self.host, "port": self.port, "register_map": self.map, "idle_timeout": self.idle_timeout_s}
        if self._write_code is not None:
            options["write_key"] = self._write_key
        return options

    def start(self):
        if self._thread is not None:
            return self
        self._started.clear()
        self._error = None
        self._publish(initial=True)
        self._thread = threading.Thread(target=self._thread_main, name=f"mock-modbus-{self._requested_port}", daemon=True)
        self._thread.start()
        if not self._started.wait(10):
            raise RuntimeError("mock Modbus server did not start within 10 s")
        if self._error is not None:
            self._thread.join(5)
            self._thread = None
            raise OSError(f"mock Modbus server could not start on {self.host}:{self._requested_port}: {self._error}")
        return self

    def stop(self) -> None:
        if self._thread is None:
            return
        if self._loop is not None and self._stop_event is not None:
            try:
                self._loop.call_soon_threadsafe(self._stop_event.set)
            except RuntimeError:
                pass
        self._thread.join(timeout=10)
        self._thread = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _thread_main(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:  # reported by start()
            self._error = exc
            self._started.set()

    async def _main(self) -> None:
        from pymodbus.simulator import DataType, SimData, SimDevice

        self._loop = asyncio.get_running_loop()
        self._stop_event = asyncio.Event()
        device = SimDevice(id=self.map.device_id,
                           simdata=[SimData(0, count=self.map.size, values=0, datatype=DataType.REGISTERS)],
                           action=self._action)
        server = _server_classes()(device, self.faults, address=(self.host, self._requested_port))
        try:
            await server.serve_forever(background=True)
            if not server.transport:
                raise OSError("pymodbus could not listen")
            self._port = server.transport.sockets[0].getsockname()[1]
            self._started.set()
            ticker = asyncio.create_task(self._robot_loop())
            watchdog = asyncio.create_task(self._close_idle(server))
            await self._stop_event.wait()
            for task in (ticker, watchdog):
                task.cancel()
                try:
                    await task
                except asyncio.CancelledError:
                    pass
        finally:
            await server.shutdown()
            await asyncio.sleep(0)

    # ------------------------------------------------------------------ the gateway's registers
    async def _action(self, function_code, start_address, address, count, registers, set_values):
        """Called by pymodbus for every register access: faults, then our register bank."""
        from pymodbus.constants import ExcCodes

        self.requests += 1
        faults = self.faults
        if faults.delay_s > 0:
            await asyncio.sleep(faults.delay_s)
        if faults.modbus_exception_next and faults.take("modbus_exception_next"):
            faults.note("modbus_exception")
            return ExcCodes(faults.modbus_exception or 4)
        if faults.modbus_exception:
            faults.note("modbus_exception")
            return ExcCodes(faults.modbus_exception)
        offset = address - start_address
        with self._bank_lock:
            if set_values is None:
                registers[offset:offset + count] = self._bank[address:address + count]
                return None
            for a in range(address, address + len(set_values)):
                if not self._pc_writable(a):
                    return ExcCodes.ILLEGAL_ADDRESS
            self._bank[address:address + len(set_values)] = [int(v) & 0xFFFF for v in set_values]
        return None

    def _pc_writable(self, address: int) -> bool:
        return any(r.access == "pc" and r.address <= address < r.end for r in self.map.registers.values())

    def _get(self, name: str) -> list:
        reg = self.map[name]
        with self._bank_lock:
            return self.map.decode(name, self._bank[reg.address:reg.end], reg.address)

    def _set(self, name: str, values) -> None:
        reg = self.map[name]
        regs = self.map.encode(name, values)
        with self._bank_lock:
            self._bank[reg.address:reg.end] = regs

    def register(self, name: str) -> list:
        """Current values of a register of the map (for tests and tools)."""
        return self._get(name)

    # ------------------------------------------------------------------ the RAPID program
    async def _close_idle(self, server) -> None:
        """Close connections silent for ``idle_timeout_s`` (the gateway's idle timeout)."""
        while True:
            await asyncio.sleep(min(0.1, self.idle_timeout_s / 4))
            now = time.monotonic()
            for handler in list(server.active_connections.values()):
                if now - getattr(handler, "last_activity", now) > self.idle_timeout_s:
                    self.idle_closes += 1
                    log.info("mock Modbus gateway: connection silent for %.3g s closed", self.idle_timeout_s)
                    handler.close()

    async def _robot_loop(self) -> None:
        while True:
            await asyncio.sleep(self.publish_period_s)
            if self.faults.robot_stalled:
                continue
            try:
                self._step()
                self._publish()
            except Exception:  # keep the program running; a bug shows in the log
                log.exception("mock Modbus robot step failed")

    def _step(self) -> None:
        program = self.program
        state, _ = program.status()
        request = self._get("request")[0]
        grabbed = self._get("grabbed")[0]
        command = self._get("tool_command")[0]
        if state == READY:
            if command != self._tool_seq:  # HeIo checks the tool command first
                self._apply_tool(command)
            elif request != 0:
                try:
                    program.request(request)
                except ProgramRefusal as refusal:
                    program.mark_error(refusal.code)
        elif state in (AT, LATE):
            if grabbed == 1:
                program.mark_acked()
        elif state == ACKED:
            if request == 0 and grabbed == 0:
                program.mark_ready()
        elif state == ERROR:
            if request == 0:
                program.mark_ready()

    def _key_accepted(self) -> bool:
        """HeIo's key gate: the code in ``tool_key`` against HeKey's; KEY_TRIES wrong codes lock it."""
        if self._write_code is None or self._key_failures >= P.KEY_TRIES:
            return False
        if self._get("tool_key")[0] == self._write_code:
            return True
        self._key_failures += 1
        log.info("mock Modbus program: tool data with a wrong key code refused (%d)", self._key_failures)
        return False

    def _apply_tool(self, command: int) -> None:
        values = self._get("tool_values")
        try:
            if not self._key_accepted():
                raise ProgramRefusal(P.E_AUTH, "wrong or missing key code")
            self.program.apply_tool(ToolData.from_values(values))
            error = 0
        except ProgramRefusal as refusal:
            error = refusal.code
        except ValueError:
            error = P.E_TOOL
        self._tool_seq = command
        self._set("tool_error", [error])
        self._set("tool_ack", [command])

    def _publish(self, initial: bool = False) -> None:
        program, robot = self.program, self.robot
        state, posture = program.status()
        pose = robot.tool0_pose()
        if not initial:
            self._heartbeat = (self._heartbeat + 1) & 0xFFFF
        self._set("protocol_version", [P.PROTOCOL_VERSION])
        self._set("posture_count", [program.count])
        self._set("joints", list(robot.current_joints))
        self._set("tool0_position", list(pose.position_mm))
        self._set("tool0_quaternion", list(pose.quaternion_wxyz))
        self._set("tool_readback", robot.tool.values())
        self._set("state", [STATE_CODES[state]])
        self._set("posture", [posture])
        self._set("at_posture", [1 if state in (AT, LATE) else 0])
        self._set("error", [program.error_code])
        self._set("heartbeat", [self._heartbeat])
