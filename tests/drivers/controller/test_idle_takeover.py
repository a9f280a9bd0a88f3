"""The link recovers by itself: a silent, vanished or half-open PC never blocks the controller.

Every server here has a short idle timeout (IDLE); bounds like "served within IDLE + 2 s" state the
functional property (the server freed itself), not a speed.
"""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

from handeye.drivers.controller import ControllerTimeout, ToolData, open_controller
from handeye.mocks.controller import start_mock_controller

from helpers import LinePeer

IDLE = 0.4
TIME_SCALE = 0.002
TEST_KEY = "link-test-key"


@pytest.fixture
def quick(protocol):
    """A mock controller of ``protocol`` with an idle timeout of IDLE seconds."""
    with start_mock_controller(protocol, time_scale=TIME_SCALE, ack_timeout_s=None, idle_timeout_s=IDLE,
                               write_key=TEST_KEY) as srv:
        yield srv


def _wait_for(condition, seconds: float = 2.0) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.01)
    return condition()


def _silent_pc(server, partial: bytes = b"") -> socket.socket:
    """A PC that connected (maybe sent half a request) and went quiet: power lost, never closed."""
    sock = socket.create_connection((server.host, server.port), timeout=2)
    if partial:
        sock.sendall(partial)
    if hasattr(server, "connections"):  # line servers: wait until the silent PC holds the link
        assert _wait_for(lambda: server.connections >= 1)
    else:
        time.sleep(0.05)
    return sock


def _ask_after_silence(peer: LinePeer, text: str, attempts: int = 3) -> str:
    """The first request after a silence of the serial line. The program's idle reset comes every IDLE
    s while nothing arrives, and one that falls as the request arrives discards it (the unfinished line
    it is there to drop): no reply ever comes, and a PC's client sends it again. So does this."""
    for _ in range(attempts):
        try:
            return peer.ask(text)
        except socket.timeout:
            peer.file = peer.sock.makefile("rb")  # a timed-out reader cannot read again
    raise AssertionError(f"no reply to {text!r} in {attempts} attempts")


@pytest.mark.parametrize("partial", [b"", b"7 JOI"], ids=["silent", "half-a-request"])
def test_a_silent_client_does_not_block_another(quick, connect_to, partial):
    silent = _silent_pc(quick, partial if quick.protocol != "modbus" else partial[:3])
    try:
        start = time.monotonic()
        with connect_to(quick, timeout=1.0, retries=1) as c:
            joints = c.read_joints()
        assert time.monotonic() - start <= IDLE + 2.0
        assert np.allclose(joints, quick.robot.current_joints, atol=1e-4)
    finally:
        silent.close()


def test_a_client_idle_past_the_idle_timeout_reads_again(quick, connect_to):
    with connect_to(quick, timeout=1.0) as c:
        first = c.read_joints()
        time.sleep(IDLE + 0.4)  # the server drops (socket, Modbus gateway) or forgets (serial) the quiet PC
        again = c.read_joints()
        assert np.allclose(first, again) and np.allclose(again, quick.robot.current_joints, atol=1e-4)
        if quick.protocol in ("socket", "modbus"):
            assert quick.idle_closes >= 1 and c.reconnects >= 1  # it was closed, and the client came back alone
        tool = ToolData((5.0, -6.0, 70.0), (1.0, 0.0, 0.0, 0.0), 1.1)
        assert c.set_tool(tool).close_to(tool)  # a whole multi-message exchange after the idle gap


@pytest.mark.parametrize("protocol", ["socket"])
def test_socket_server_closes_a_silent_client_and_accepts_the_next(quick):
    silent = _silent_pc(quick)
    try:
        silent.settimeout(IDLE + 2.0)
        assert silent.recv(16) == b""  # closed by the server (within IDLE + 2 s), program still running
        assert quick.idle_closes == 1 and quick.running
        peer = LinePeer(quick)
        try:
            assert peer.ask("1 COUNT") == "1 OK 12"
        finally:
            peer.close()
    finally:
        silent.close()


@pytest.mark.parametrize("protocol", ["socket"])
def test_socket_takeover_starts_a_new_session_and_refuses_strangers(quick):
    old = LinePeer(quick)
    try:
        assert old.ask("1 POSE").startswith("1 OK ")
        new = LinePeer(quick)  # the same PC again (it restarted): takes over at once
        try:
            assert new.ask("1 QUAT").startswith("1 ERR 7")  # the old connection's snapshot is not the new one's
            assert quick.takeovers == 1
            old.sock.settimeout(2.0)
            assert old.file.readline() == b""  # the old connection was closed
        finally:
            new.close()
    finally:
        old.close()


def _stranger(server) -> socket.socket:
    """A connection from 127.0.0.2: another host as far as the program's address check goes."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.settimeout(2)
    sock.bind(("127.0.0.2", 0))
    sock.connect((server.host, server.port))
    return sock


def test_socket_takeover_accepts_only_the_configured_pc():
    with start_mock_controller("socket", time_scale=TIME_SCALE, idle_timeout_s=IDLE,
                               allowed_client="127.0.0.1") as server:
        assert server.allowed_client == "127.0.0.1"  # the program's HE_PC_ADDRESS decides, not Python
        pc = LinePeer(server)
        try:
            assert pc.ask("1 PING") == "1 OK"
            stranger = _stranger(server)
            try:
                stranger.settimeout(2.0)
                assert stranger.recv(16) == b""  # refused while the PC keeps its link
                assert server.refused_clients == 1 and server.takeovers == 0
            finally:
                stranger.close()
            assert pc.ask("2 PING") == "2 OK"
        finally:
            pc.close()


@pytest.mark.parametrize("protocol", ["serial"])
def test_serial_idle_reset_forgets_staged_tool_data(quick):
    """A TOOLPOS staged before the silence cannot be committed by a TOOLSAVE after it."""
    before = quick.robot.tool
    peer = LinePeer(quick)
    try:
        assert peer.ask(f"1 KEY {TEST_KEY}") == "1 OK"
        assert peer.ask("2 TOOLPOS 1 2 3") == "2 OK"
        assert peer.ask("3 TOOLROT 1 0 0 0") == "3 OK"
        assert peer.ask("4 TOOLLOAD 1 0 0 0") == "4 OK"
        assert peer.ask("5 POSE").startswith("5 OK ")
        resets = quick.idle_resets
        time.sleep(IDLE + 0.4)
        # the program forgets the session when its idle check runs, later on a loaded machine: wait for it
        assert _wait_for(lambda: quick.idle_resets > resets, 10.0)
        assert _ask_after_silence(peer, "6 QUAT").startswith("6 ERR 7")  # the POSE snapshot is gone
        assert peer.ask("7 TOOLSAVE").startswith("7 ERR 9")  # so is the authorisation
        assert peer.ask(f"8 KEY {TEST_KEY}") == "8 OK"
        assert peer.ask("9 TOOLSAVE").startswith("9 ERR 6")  # and the staged parts
        assert quick.robot.tool == before and quick.idle_resets >= 1
    finally:
        peer.close()


@pytest.mark.parametrize("protocol", ["serial"])
def test_serial_idle_reset_discards_an_unfinished_line(quick):
    peer = LinePeer(quick)
    try:
        resets = quick.idle_resets
        peer.sock.sendall(b"12 JOI")  # a PC that died mid-line
        time.sleep(IDLE + 0.4)
        assert _wait_for(lambda: quick.idle_resets > resets, 10.0)  # the idle check has run
        assert _ask_after_silence(peer, "1 PING") == "1 OK"  # not glued to "12 JOI"
    finally:
        peer.close()


@pytest.mark.parametrize("protocol", ["serial"])
def test_serial_new_connection_takes_the_line_over_and_bye_ends_the_session(quick):
    old = LinePeer(quick)
    try:
        assert old.ask(f"1 KEY {TEST_KEY}") == "1 OK"
        new = LinePeer(quick)  # owns the wire at once; a line has no connections, the session carries over
        try:
            assert new.ask("1 TOOLPOS 1 2 3") == "1 OK"
            assert quick.takeovers == 1
            assert new.ask("2 BYE") == "2 OK"
            assert new.ask("3 TOOLPOS 1 2 3").startswith("3 ERR 9")  # BYE ended the session
        finally:
            new.close()
    finally:
        old.close()


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_first_exchange_may_wait_for_the_idle_timeout(protocol):
    """Connecting allows idle_timeout + timeout: the request may sit in the backlog meanwhile."""
    with start_mock_controller(protocol, time_scale=TIME_SCALE, idle_timeout_s=IDLE) as server:
        server.faults.delay_s = 0.25  # every reply 0.25 s late: the first exchange takes 0.5 s or more
        options = {**server.client_options(), "timeout": 0.3, "retries": 0}
        with open_controller(protocol, **{**options, "idle_timeout": 1.5}) as c:
            assert c.info().postures == 12
            server.faults.delay_s = 0.0
            assert np.allclose(c.read_joints(), server.robot.current_joints, atol=1e-4)
        server.faults.delay_s = 0.25
        with pytest.raises(ControllerTimeout):  # an idle timeout too short for the wait: refused clearly
            open_controller(protocol, **{**options, "idle_timeout": 0.1})
