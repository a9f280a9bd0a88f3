"""Tool writes need the station's write key, on every transport; reading stays open."""

from __future__ import annotations

import time

import pytest

from handeye.drivers.controller import ControllerRefused, InvalidRequest, ToolData, open_controller
from handeye.drivers.controller import protocol as P
from handeye.drivers.controller.types import write_key_code
from handeye.mocks.controller import start_mock_controller

from helpers import LinePeer

KEY = "right-key_42"
WRONG = "wrong-key_42"
TOOL = ToolData((12.5, -3.25, 88.0), (0.5, 0.5, -0.5, 0.5), 1.4, (0.0, 10.0, 70.0))


def _skip_without_key(server):
    """RWS authorises writes by the controller's users and mastership, not by the key (test_rws.py)."""
    from handeye.drivers.controller.backends import CONTROLLERS

    if not CONTROLLERS[server.protocol].load().writes_need_key:
        pytest.skip(f"{server.protocol}: tool writes are authorised by the controller's users (see test_rws.py)")


@pytest.fixture
def keyed(protocol):
    with start_mock_controller(protocol, time_scale=0.002, ack_timeout_s=None, write_key=KEY) as srv:
        yield srv


def _options(server, **changes):
    options = {**server.client_options(), "timeout": 1.0, "backoff_s": 0.02}
    options.pop("write_key", None)
    return {**options, **changes}


def test_the_right_key_writes_and_reads_back(keyed):
    with open_controller(keyed.protocol, **_options(keyed, write_key=KEY)) as c:
        back = c.set_tool(TOOL)
        assert back.close_to(TOOL) and keyed.robot.tool.close_to(TOOL)
        assert c.read_tool().close_to(TOOL)
        assert c.set_tool(TOOL).close_to(TOOL)  # again: one KEY per write, sent by set_tool each time


def test_a_wrong_key_is_refused_and_nothing_is_written(keyed):
    _skip_without_key(keyed)
    before = keyed.robot.tool
    with open_controller(keyed.protocol, **_options(keyed, write_key=WRONG)) as c:
        with pytest.raises(ControllerRefused, match="write_key") as info:
            c.set_tool(TOOL)
        assert info.value.code == P.E_AUTH
        assert c.read_tool() == before  # reading needs no key
    assert keyed.robot.tool == before


def test_no_key_is_refused_before_anything_is_sent(keyed):
    _skip_without_key(keyed)
    with open_controller(keyed.protocol, **_options(keyed)) as c:
        before = keyed.requests
        with pytest.raises(InvalidRequest, match="controller.write_key.*HeKey.sys.*handeye rapid generate") as info:
            c.set_tool(TOOL)
        assert "\n" not in str(info.value)
        assert keyed.requests == before


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_tool_parts_without_key_are_refused_by_the_controller(keyed):
    peer = LinePeer(keyed)
    try:
        for i, request in enumerate(["TOOLPOS 1 2 3", "TOOLROT 1 0 0 0", "TOOLLOAD 1 0 0 0", "TOOLSAVE"], 1):
            assert peer.ask(f"{i} {request}") == f"{i} ERR 9 not authorised: send KEY first"
        assert peer.ask(f"5 KEY {WRONG}") == "5 ERR 9 wrong key"
        assert peer.ask("6 TOOLPOS 1 2 3").startswith("6 ERR 9")
        assert peer.ask("7 GETTOOLPOS").startswith("7 OK ")  # reading stays open
        assert peer.ask(f"8 KEY {KEY}") == "8 OK"
        assert peer.ask("9 TOOLPOS 1 2 3") == "9 OK"
    finally:
        peer.close()


@pytest.mark.parametrize("protocol", ["socket"])
def test_socket_closes_after_three_wrong_keys_and_a_new_connection_starts_clean(keyed):
    peer = LinePeer(keyed)
    try:
        assert peer.ask(f"1 KEY {WRONG}") == "1 ERR 9 wrong key"
        assert peer.ask(f"2 KEY {WRONG}") == "2 ERR 9 wrong key"
        assert peer.ask(f"3 KEY {WRONG}") == "3 ERR 9 wrong key"
        peer.sock.settimeout(2.0)
        assert peer.file.readline() == b""  # closed by the controller
    finally:
        peer.close()
    again = LinePeer(keyed)
    try:
        assert again.ask("1 TOOLPOS 1 2 3").startswith("1 ERR 9")  # a new connection is not authorised
        assert again.ask(f"2 KEY {KEY}") == "2 OK"
    finally:
        again.close()


@pytest.mark.parametrize("protocol", ["serial"])
def test_serial_refuses_further_keys_after_three_wrong_ones_until_the_session_ends(keyed):
    peer = LinePeer(keyed)
    try:
        for i in (1, 2, 3):
            assert peer.ask(f"{i} KEY {WRONG}") == f"{i} ERR 9 wrong key"
        assert peer.ask(f"4 KEY {KEY}") == "4 ERR 9 too many wrong keys"  # even the right one
        assert peer.ask("5 BYE") == "5 OK"
        assert peer.ask(f"6 KEY {KEY}") == "6 OK"
    finally:
        peer.close()


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_authorisation_ends_with_the_write_and_with_bye(keyed):
    peer = LinePeer(keyed)
    try:
        assert peer.ask(f"1 KEY {KEY}") == "1 OK"
        for i, request in enumerate(["TOOLPOS 1 2 3", "TOOLROT 1 0 0 0", "TOOLLOAD 1 0 0 0", "TOOLSAVE"], 2):
            assert peer.ask(f"{i} {request}") == f"{i} OK"
        assert peer.ask("6 TOOLPOS 1 2 3").startswith("6 ERR 9")  # one KEY, one write
        assert peer.ask(f"7 KEY {KEY}") == "7 OK"
        assert peer.ask("8 BYE") == "8 OK"
    finally:
        peer.close()
    if keyed.protocol == "serial":  # the line stays: the next PC finds the session ended
        peer = LinePeer(keyed)
        try:
            assert peer.ask("1 TOOLPOS 1 2 3").startswith("1 ERR 9")
        finally:
            peer.close()


@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_a_mock_without_key_runs_the_program_that_refuses_every_tool_write(protocol):
    with start_mock_controller(protocol, time_scale=0.002) as server:
        assert not server.has_write_key and "HeKey" not in [m.source.split(".")[0] for m in server.source.modules]
        peer = LinePeer(server)
        try:  # the keyless program's own answer (key_check_none.tmpl); the CLI banner says how to start a keyed mock
            assert peer.ask(f"1 KEY {KEY}") == "1 ERR 9 no write key: set controller.write_key"
            assert peer.ask("2 TOOLPOS 1 2 3") == "2 ERR 9 not authorised: send KEY first"
        finally:
            peer.close()
        with open_controller(protocol, **_options(server, write_key=KEY)) as c:
            with pytest.raises(ControllerRefused) as info:
                c.set_tool(TOOL)
            assert info.value.code == P.E_AUTH


def _raw_modbus(server):
    from pymodbus.client import ModbusTcpClient

    client = ModbusTcpClient(server.host, port=server.port, timeout=1.0, retries=0)
    assert client.connect()
    return client


def _tool_command(server, client, code: int) -> int:
    """Write tool values with key ``code`` and a new tool_command; returns tool_error once acknowledged."""
    m = server.map
    ack = server.register("tool_ack")[0]
    block = m.encode("tool_values", TOOL.values()) + m.encode("tool_key", code)
    assert not client.write_registers(m["tool_values"].address, block, device_id=m.device_id).isError()
    assert not client.write_registers(m["tool_command"].address, [ack + 1], device_id=m.device_id).isError()
    end = time.monotonic() + 2.0
    while server.register("tool_ack")[0] != ack + 1 and time.monotonic() < end:
        time.sleep(0.005)
    assert server.register("tool_ack")[0] == ack + 1
    return server.register("tool_error")[0]


def test_modbus_key_code_and_lockout_until_the_program_restarts():
    with start_mock_controller("modbus", time_scale=0.002, write_key=KEY) as server:
        before = server.robot.tool
        client = _raw_modbus(server)
        try:
            assert _tool_command(server, client, 0) == P.E_AUTH  # no key code
            assert _tool_command(server, client, write_key_code(WRONG)) == P.E_AUTH
            assert server.robot.tool == before
            assert _tool_command(server, client, write_key_code(KEY)) == 0
            assert server.robot.tool.close_to(TOOL)
            assert _tool_command(server, client, write_key_code(WRONG)) == P.E_AUTH  # the third wrong code
            assert _tool_command(server, client, write_key_code(KEY)) == P.E_AUTH  # locked, even the right one
        finally:
            client.close()
        with open_controller("modbus", **_options(server, write_key=KEY)) as c:
            with pytest.raises(ControllerRefused, match="until the RAPID program restarts"):
                c.set_tool(TOOL)
    with start_mock_controller("modbus", time_scale=0.002, write_key=KEY) as server:  # restarted
        with open_controller("modbus", **_options(server, write_key=KEY)) as c:
            assert c.set_tool(TOOL).close_to(TOOL)
            assert server.register("tool_key") == [0]  # the PC cleared the code after the command


def test_key_request_codec_never_echoes_the_key():
    assert P.encode_request(12, "KEY", KEY) == f"12 KEY {KEY}\n".encode()
    assert P.parse_request(f"12 KEY {KEY}\n".encode()).args == (KEY,)
    for bad in ("short", "x" * 33, "has space", "semi;colon", "ümlaut12"):
        with pytest.raises(ValueError) as info:
            P.encode_request(1, "KEY", bad)
        assert bad not in str(info.value)
    with pytest.raises(P.RequestError) as info:
        P.parse_request(b"1 KEY sh\n")
    assert info.value.code == P.E_ARGS and "sh\n" not in str(info.value)
    assert len(P.encode_request(999, "KEY", "k" * 32)) - 1 <= P.MAX_MESSAGE


@pytest.mark.parametrize("bad", ["short", "x" * 33, "with space!", 12345678])
def test_a_bad_write_key_option_is_refused_without_echo(bad):
    with pytest.raises(InvalidRequest) as info:
        open_controller("socket", connect=False, write_key=bad)
    assert str(bad) not in str(info.value)


def test_the_key_is_not_in_the_controllers_repr(keyed):
    with open_controller(keyed.protocol, **_options(keyed, write_key=KEY)) as c:
        assert KEY not in repr(c) and KEY not in str(c)
