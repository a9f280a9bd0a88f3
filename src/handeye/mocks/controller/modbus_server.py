"""Mock Modbus TCP gateway on a real pymodbus server, and the generated HeIo program executed behind it.

The gateway is pymodbus' ``ModbusTcpServer`` with one device whose holding registers follow the
register map (``src/handeye/drivers/controller/modbus_map.yaml`` by default). The register map names the
controller signal each register is mapped to (``goHeState``, ``aoHeJ1..aoHeJ6`` ...): those are the
I/O signals of the controller's configuration, which the RAPID program (``HeIo``, run by the
interpreter) drives with ``SetGO``/``SetDO``/``SetAO`` and reads with ``GInput``/``DInput``/``AInput``/
``WaitDI``/``WaitUntil``; its timer interrupt publishes joints, pose and the heartbeat. Nothing of
the handshake is Python.

Faults (see :class:`Faults`): delayed responses, exception responses, garbage instead of a
response, dropped connections, a gateway that stops answering (``silent``) and a RAPID program
that is held while the gateway still answers (``robot_stalled``: the heartbeat freezes).

The gateway serves several connections at once (a silent client blocks nobody) and closes a
connection silent for ``idle_timeout_s``, as gateways commonly do, so a PC that vanished does not
hold a connection slot.
"""

from __future__ import annotations

import asyncio
import logging
import os
import re
import threading
import time
from typing import TYPE_CHECKING, cast

from ...drivers import load_register_map
from ...rapid import Bindings, IoBinding, RapidFatalError
from .faults import Faults
from .server import DEFAULT_IDLE_TIMEOUT_S, RapidControllerServer
from .sources import ControllerProgram

if TYPE_CHECKING:
    from ..robot import SimulatedRobot

__all__ = ["ModbusControllerServer", "GatewayIo"]

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


class GatewayIo(IoBinding):
    """The controller signals a gateway maps onto the registers of ``register_map``.

    A signal's type comes from its name's prefix (``di``, ``do``, ``gi``, ``go``, ``ai``, ``ao``, as
    the map and HeIo name them); a range ``aoHeJ1..aoHeJ6`` maps one signal to each value of the
    register. Group signals are as wide as their register (16 or 32 bits).
    """

    _TYPES = {"di": "signaldi", "do": "signaldo", "gi": "signalgi", "go": "signalgo", "ai": "signalai",
              "ao": "signalao"}

    def __init__(self, register_map, bank: list, lock: threading.Lock):
        self.map, self.bank, self.lock = register_map, bank, lock
        self.where: dict = {}  # signal name (lower case) -> (register name, index, signal name)
        for reg in register_map.registers.values():
            for i, name in enumerate(self._names(reg.signal, reg.count)):
                self.where[name.lower()] = (reg.name, i, name)

    @staticmethod
    def _names(signal: str, count: int) -> list:
        if not signal:
            return []
        m = re.fullmatch(r"([A-Za-z_]+?)(\d+)\.\.\1(\d+)", signal) or re.fullmatch(r"([A-Za-z_]+?)([A-Z])\.\.\1([A-Z])", signal)
        if m is None:
            return [signal]
        first, last = m.group(2), m.group(3)
        if first.isdigit():
            names = [f"{m.group(1)}{i}" for i in range(int(first), int(last) + 1)]
        else:
            names = [f"{m.group(1)}{chr(c)}" for c in range(ord(first), ord(last) + 1)]
        if len(names) != count:
            raise ValueError(f"register signal {signal} names {len(names)} signals for {count} values")
        return names

    def signals(self) -> dict:
        out = {}
        for _, _, name in self.where.values():
            kind = self._TYPES.get(name[:2].lower())
            if kind is not None:
                out[name] = kind
        return out

    def _locate(self, name: str):
        try:
            return self.where[name.lower()]
        except KeyError:
            raise RapidFatalError(f"signal {name} is not mapped by the gateway") from None

    def read(self, name: str) -> float:
        register, index, _ = self._locate(name)
        reg = self.map[register]
        with self.lock:
            values = self.map.decode(register, self.bank[reg.address:reg.end], reg.address)
        return float(values[index])

    def write(self, name: str, value: float) -> None:
        register, index, _ = self._locate(name)
        reg = self.map[register]
        with self.lock:
            values = list(self.map.decode(register, self.bank[reg.address:reg.end], reg.address))
            values[index] = value
            self.bank[reg.address:reg.end] = self.map.encode(register, values)

    def bits(self, name: str) -> int:
        register, _, _ = self._locate(name)
        return 32 if self.map[register].type == "uint32" else 16


class ModbusControllerServer(RapidControllerServer):
    """A real Modbus TCP gateway and the HeIo program behind it.

    Parameters
    ----------
    program : ControllerProgram
    robot : SimulatedRobot
    host : str
    port : int
        0 picks a free port (see :attr:`port` after :meth:`start`).
    faults : Faults, optional
    register_map : path or RegisterMap, optional
    idle_timeout_s : float
        The gateway closes a connection silent this long.
    write_key : str, optional
        The station's write key (its code goes into ``tool_key``; HeKey.sys holds it on the controller).
    """

    kind = "modbus"

    def __init__(self, program: ControllerProgram, robot: SimulatedRobot, host: str = "127.0.0.1", port: int = 0,
                 faults: Faults | None = None, *, register_map: str | os.PathLike[str] | None = None, idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        super().__init__(program, robot, host, port, faults, idle_timeout_s=idle_timeout_s, write_key=write_key)
        #: Connections closed for idleness (for tests).
        self.idle_closes = 0
        self._port = None
        self.map = load_register_map(register_map)
        self._bank = [0] * self.map.size
        self._bank_lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._started = threading.Event()
        self._error: BaseException | None = None
        self.requests = 0

    # ------------------------------------------------------------------ lifecycle
    @property
    def port(self) -> int:
        return self._port if self._port is not None else self._requested_port

    def client_options(self) -> dict:
        return self._client_key({"host": self.host, "port": self.port, "register_map": self.map,
                                 "idle_timeout": self.idle_timeout_s})

    def _open_endpoint(self) -> Bindings:
        self._started.clear()
        self._error = None
        self._thread = threading.Thread(target=self._thread_main, name=f"mock-modbus-{self._requested_port}",
                                        daemon=True)
        self._thread.start()
        if not self._started.wait(10):
            raise RuntimeError("mock Modbus server did not start within 10 s")
        if self._error is not None:
            self._thread.join(5)
            self._thread = None
            raise OSError(f"mock Modbus server could not start on {self.host}:{self._requested_port}: {self._error}")
        return Bindings(io=GatewayIo(self.map, self._bank, self._bank_lock))

    def _close_endpoint(self) -> None:
        if self._thread is None:
            return
        if self._loop is not None and self._stop_event is not None:
            try:
                self._loop.call_soon_threadsafe(self._stop_event.set)
            except RuntimeError:
                pass
        self._thread.join(timeout=10)
        self._thread = None

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
            listener = cast(asyncio.Server, server.transport)  # pymodbus keeps loop.create_server's Server there
            self._port = listener.sockets[0].getsockname()[1]
            self._started.set()
            watchdog = asyncio.create_task(self._close_idle(server))
            await self._stop_event.wait()
            watchdog.cancel()
            try:
                await watchdog
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

    def register(self, name: str) -> list:
        """Current values of a register of the map (for tests and tools)."""
        reg = self.map[name]
        with self._bank_lock:
            return self.map.decode(name, self._bank[reg.address:reg.end], reg.address)

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
