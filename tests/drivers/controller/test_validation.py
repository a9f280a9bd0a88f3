"""Bad input is refused on the PC before anything is sent to the controller."""

from __future__ import annotations

import math

import pytest

from handeye.drivers.controller import InvalidRequest, ToolData, open_controller
from handeye.drivers.controller.types import check_joints, check_tooldata
from handeye.mocks.backends import mock_variants
from handeye.mocks.controller import start_mock_controller

GOOD_Q = (1.0, 0.0, 0.0, 0.0)
PROTOCOLS = mock_variants()
KEY = "validation-key_01"


@pytest.fixture(scope="module", params=PROTOCOLS, ids=[getattr(p, "label", p) for p in PROTOCOLS])
def protocol(request):
    return request.param


@pytest.fixture(scope="module")
def server(protocol):
    """One mock controller per back end for the whole module: its tests check that nothing reaches it,
    so none changes its state (a test that moves the arm starts its own, ``own_server``)."""
    with start_mock_controller(protocol, time_scale=0.002, ack_timeout_s=None, write_key=KEY) as srv:
        yield srv


@pytest.fixture
def own_server(protocol):
    with start_mock_controller(protocol, time_scale=0.002, ack_timeout_s=None, write_key=KEY) as srv:
        yield srv


BAD_TOOLS = {
    "nan position": ToolData((math.nan, 0.0, 50.0), GOOD_Q, 1.0),
    "inf quaternion": ToolData((0.0, 0.0, 50.0), (math.inf, 0.0, 0.0, 0.0), 1.0),
    "non-unit quaternion": ToolData((0.0, 0.0, 50.0), (1.0, 0.1, 0.0, 0.0), 1.0),
    "zero quaternion": ToolData((0.0, 0.0, 50.0), (0.0, 0.0, 0.0, 0.0), 1.0),
    "over 1 m": ToolData((800.0, 700.0, 50.0), GOOD_Q, 1.0),
    "zero mass": ToolData((0.0, 0.0, 50.0), GOOD_Q, 0.0),
    "nan mass": ToolData((0.0, 0.0, 50.0), GOOD_Q, math.nan),
    "too heavy": ToolData((0.0, 0.0, 50.0), GOOD_Q, 50.0),
    "nan cog": ToolData((0.0, 0.0, 50.0), GOOD_Q, 1.0, (0.0, math.nan, 0.0)),
    "wrong shape": ToolData((0.0, 50.0), GOOD_Q, 1.0),
}


@pytest.mark.parametrize("case", sorted(BAD_TOOLS))
def test_bad_tool_data_is_refused_before_sending(controller, server, case):
    before_tool, before_requests = server.robot.tool, server.requests
    with pytest.raises(InvalidRequest):
        controller.set_tool(BAD_TOOLS[case])
    assert server.requests == before_requests  # nothing reached the controller
    assert server.robot.tool == before_tool


@pytest.mark.parametrize("k", [0, -1, 13, 2.5, math.nan, True, "3", None])
def test_bad_posture_index_is_refused_before_sending(controller, server, k):
    before, moves = server.requests, server.robot.moves
    with pytest.raises(InvalidRequest):
        controller.goto_posture(k)
    assert server.requests == before
    assert server.robot.moves == moves


@pytest.mark.parametrize("joints", [
    [0, 75, 0, 0, 0, 0],           # axis 2 beyond +70
    [0, 0, 0, 0, 0, 301],          # axis 6 beyond +300
    [0, 0, math.nan, 0, 0, 0],
    [0, 0, 0, 0, 0],               # five axes
])
def test_expected_posture_outside_the_limits_is_refused(controller, server, joints):
    before, moves = server.requests, server.robot.moves
    with pytest.raises(InvalidRequest):
        controller.goto_posture(1, expected_joints=joints)
    assert server.requests == before
    assert server.robot.moves == moves


def test_plan_with_a_posture_outside_the_limits_is_refused_at_construction(server):
    plan = [list(p) for p in server.robot.postures]
    plan[4][2] = -66.0  # axis 3 below -65
    before = server.requests
    with pytest.raises(InvalidRequest, match="axis 3"):
        open_controller(server.protocol, postures=plan, **server.client_options())
    assert server.requests == before


def test_plan_limits_the_postures_that_can_be_requested(own_server, connect_to):
    plan = own_server.robot.postures[:3]
    with connect_to(own_server, postures=plan) as c:
        before = own_server.requests
        with pytest.raises(InvalidRequest, match="not in the plan"):
            c.goto_posture(4)
        assert own_server.requests == before
        assert c.goto_posture(3).posture == 3


def test_limit_messages_name_the_axis():
    with pytest.raises(InvalidRequest, match=r"axis 2 = 75\.0000 deg outside \[-70, 70\]"):
        check_joints([0, 75, 0, 0, 0, 0])


def test_valid_tool_is_normalised():
    tool = check_tooldata(ToolData((1, 2, 3), (-1.00002, 0, 0, 0), 1.0))
    assert tool.quaternion_wxyz == (1.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("options", [
    {"name": "profibus"},
    {"name": "socket", "port": 70000},
    {"name": "socket", "port": "1025"},
    {"name": "socket", "timeout": math.nan},
    {"name": "socket", "timeout": -1},
    {"name": "socket", "retries": -1},
    {"name": "socket", "retries": "3"},
    {"name": "socket", "robot": "IRB9999"},
    {"name": "socket", "max_tool_mass_kg": 0},
    {"name": "serial", "url": ""},
    {"name": "modbus", "colour": "red"},
])
def test_bad_options_are_refused(options):
    options = dict(options)
    with pytest.raises(InvalidRequest):
        open_controller(options.pop("name"), connect=False, **options)
