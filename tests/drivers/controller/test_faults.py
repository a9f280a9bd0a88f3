"""Faults injected into the mock: the client recovers or fails clearly, and never blocks past its timeout.

Times are compared with the configured timeout with a generous margin (the machine is shared);
no test asserts absolute speed.
"""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

from handeye.drivers.controller import (
    ControllerConnectionError,
    ControllerTimeout,
    ProtocolError,
    ToolData,
    open_controller,
)
from handeye.mocks.controller import start_mock_controller

TIMEOUT = 0.4


def within_budget(elapsed: float, timeout: float) -> bool:
    """A call bounded by ``timeout`` returned in time: at most twice the timeout plus half a second."""
    return elapsed <= 2 * timeout + 0.5


def test_dropped_connection_reconnects_and_completes(server, connect_to):
    with connect_to(server) as c:
        server.faults.drop_next = 1
        joints = c.read_joints()
        assert np.allclose(joints, server.robot.current_joints, atol=1e-4)
        assert server.faults.fired["drop"] == 1
        assert c.reconnects >= 1


def test_drop_in_the_middle_of_a_multi_message_write_repeats_it_whole(server, connect_to):
    tool = ToolData((1.5, 2.5, 80.0), (0.0, 0.0, 0.0, 1.0), 0.9, (0.0, 0.0, 30.0))
    with connect_to(server) as c:
        server.faults.drop_after = 2  # two messages pass, the third finds the link dropped
        back = c.set_tool(tool)
        assert server.faults.fired["drop"] == 1
    assert back.close_to(tool)
    assert server.robot.tool.close_to(tool)


def test_drop_during_a_posture_sequence(server, connect_to):
    with connect_to(server) as c:
        c.goto_posture(2)
        server.faults.drop_next = 1
        c.acknowledge(2)
        server.faults.drop_next = 1
        status = c.goto_posture(9)
        assert status.at_posture(9)
        assert np.allclose(c.read_joints(), server.robot.postures[8], atol=1e-4)
        assert server.faults.fired["drop"] == 2


def test_garbage_gives_a_protocol_error_then_the_link_recovers(server, connect_to):
    with connect_to(server, timeout=TIMEOUT) as c:
        server.faults.garbage_next = 1
        start = time.monotonic()
        with pytest.raises(ProtocolError, match="garbage") as info:
            c.read_joints()
        assert within_budget(time.monotonic() - start, TIMEOUT)
        # the shared kind, named after the back end that raised it
        assert info.value.backend == server.protocol and str(info.value).startswith(f"{server.protocol}: ")
        assert np.allclose(c.read_joints(), server.robot.current_joints, atol=1e-4)


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_garbage_without_line_end(server, connect_to):
    with connect_to(server, timeout=TIMEOUT) as c:
        server.faults.garbage = b"\x01" * 200  # line noise, no LF
        server.faults.garbage_next = 1
        with pytest.raises(ProtocolError, match="without a line end"):
            c.status()
        assert c.status().state == "READY"


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_late_reply_is_skipped_by_its_id(server, connect_to):
    with connect_to(server, timeout=TIMEOUT) as c:
        server.faults.delay_s = 3 * TIMEOUT
        with pytest.raises(ControllerTimeout):
            c.read_joints()
        server.faults.delay_s = 0.0
        assert np.allclose(c.read_joints(timeout=5.0), server.robot.current_joints, atol=1e-4)
        assert c.stale_replies == 1


def test_delay_within_the_timeout_is_fine(server, connect_to):
    with connect_to(server, timeout=2.0) as c:
        server.faults.delay_s = 0.05
        assert c.status().state == "READY"


OPERATIONS = {
    "ping": lambda c, t: c.ping(timeout=t),
    "joints": lambda c, t: c.read_joints(timeout=t),
    "pose": lambda c, t: c.read_tool0_pose(timeout=t),
    "status": lambda c, t: c.status(timeout=t),
    "goto": lambda c, t: c.goto_posture(4, timeout=t),
    "acknowledge": lambda c, t: c.acknowledge(4, timeout=t),
    "set_tool": lambda c, t: c.set_tool(ToolData((0, 0, 50), (1, 0, 0, 0), 1.0), timeout=t),
    "read_tool": lambda c, t: c.read_tool(timeout=t),
}


@pytest.mark.parametrize("operation", sorted(OPERATIONS))
def test_no_call_blocks_longer_than_its_timeout(server, connect_to, operation):
    with connect_to(server, timeout=TIMEOUT) as c:
        server.faults.silent = True  # requests are read and never answered
        start = time.monotonic()
        with pytest.raises(ControllerTimeout):
            OPERATIONS[operation](c, TIMEOUT)
        assert within_budget(time.monotonic() - start, TIMEOUT)
        server.faults.silent = False


def test_unreachable_controller_fails_within_its_timeout(protocol):
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    options = {"url": f"socket://127.0.0.1:{port}"} if protocol == "serial" else {"host": "127.0.0.1", "port": port}
    start = time.monotonic()
    with pytest.raises(ControllerConnectionError, match=str(port)):
        open_controller(protocol, timeout=1.0, retries=3, backoff_s=0.05, **options)
    assert within_budget(time.monotonic() - start, 1.0)


def test_socket_server_accepts_only_the_configured_pc(connect_to):
    with start_mock_controller("socket", allowed_client="10.11.12.13") as server:
        with pytest.raises(ControllerConnectionError):
            connect_to(server, timeout=1.0, retries=1)
        assert server.refused_clients >= 1
        assert server.connections == 0


@pytest.mark.parametrize("protocol", ["modbus"])
def test_modbus_exception_response_is_a_clear_error(server, connect_to):
    from handeye.drivers.controller.modbus_client import ModbusExceptionResponse

    with connect_to(server, timeout=TIMEOUT) as c:
        server.faults.modbus_exception = 2
        with pytest.raises(ModbusExceptionResponse, match="exception 2 \\(illegal data address\\)") as info:
            c.read_joints()
        assert info.value.exception_code == 2
        server.faults.modbus_exception = 0
        server.faults.modbus_exception_next = 1  # one "server device failure", then normal
        with pytest.raises(ModbusExceptionResponse, match="device failure"):
            c.status()
        assert c.status().state == "READY"


@pytest.mark.parametrize("protocol", ["modbus"])
def test_modbus_write_to_a_robot_register_is_refused_by_the_gateway(server):
    from pymodbus.client import ModbusTcpClient

    client = ModbusTcpClient("127.0.0.1", port=server.port, timeout=1.0, retries=0)
    try:
        assert client.connect()
        response = client.write_registers(server.map["joints"].address, [0, 0], device_id=server.map.device_id)
        assert response.isError() and response.exception_code == 2
    finally:
        client.close()


@pytest.mark.parametrize("protocol", ["modbus"])
def test_modbus_robot_program_that_stops_is_detected_by_its_heartbeat(server, connect_to):
    with connect_to(server, timeout=TIMEOUT, heartbeat_timeout=0.3) as c:
        server.faults.robot_stalled = True  # the gateway still answers, the RAPID program does not
        start = time.monotonic()
        with pytest.raises(ControllerTimeout, match="heartbeat"):
            c.goto_posture(5, timeout=10.0)
        assert within_budget(time.monotonic() - start, 0.3)
        assert server.robot.moves == 0


def test_serial_line_that_echoes_is_not_taken_for_a_controller():
    # pyserial's loop:// hands every request back: our own "1 VERSION" is not a reply
    from handeye.drivers.controller.errors import ProtocolError

    start = time.monotonic()
    with pytest.raises(ProtocolError, match="^serial: .*not a reply") as info:
        open_controller("serial", url="loop://", timeout=TIMEOUT)
    assert info.value.backend == "serial"
    assert within_budget(time.monotonic() - start, TIMEOUT)
