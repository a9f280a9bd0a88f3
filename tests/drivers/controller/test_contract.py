"""Contract tests: written once, run against the mock through all three back ends.

Each check compares what the client reads with the simulated robot's true state (joints, the
kinematics of tool0, the stored tool data), so the same tests can later run against a real
controller by switching the back end's name and address.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.drivers.controller import ControllerRefused, ToolData
from handeye.drivers.controller.types import AT, LATE, READY


ROBOT = load_robot("IRB1400")


def test_identity(controller, server):
    info = controller.info()
    assert info.protocol_version == 1
    assert info.postures == len(server.robot.postures) == 12
    assert controller.ping() > 0
    assert controller.status().state == READY


def test_joints_and_flange_pose_at_home(controller):
    # all axes at 0: tool0 at (955, 0, 1195) mm, quaternion (0.7071, 0, 0.7071, 0) (reference check values)
    assert np.allclose(controller.read_joints(), 0.0, atol=1e-4)
    pose = controller.read_tool0_pose()
    assert np.allclose(pose.position_mm, [955.0, 0.0, 1195.0], atol=1e-3)
    assert np.allclose(pose.quaternion_wxyz, [np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0], atol=2e-6)


@pytest.mark.parametrize("k", [3, 10])
def test_goto_posture_reaches_the_approved_joints(controller, server, k):
    status = controller.goto_posture(k)
    assert status.state == AT and status.posture == k
    truth = server.robot.postures[k - 1]
    assert np.allclose(server.robot.current_joints, truth, atol=1e-9)
    assert np.allclose(controller.read_joints(), truth, atol=1e-4)
    # the flange pose read back is the kinematics of the posture (parallel-arm coupling included)
    p_true, q_true = ROBOT.forward(truth)
    pose = controller.read_tool0_pose()
    assert np.allclose(pose.position_mm, p_true, atol=1e-3)
    assert np.allclose(pose.quaternion_wxyz, q_true, atol=2e-6)
    assert pose.quaternion_wxyz[0] >= 0


def test_goto_returns_when_the_robot_stands_still(protocol, connect_to):
    from handeye.mocks.controller import start_mock_controller

    with start_mock_controller(protocol, time_scale=0.05, ack_timeout_s=None) as server:
        with connect_to(server) as c:
            assert c.goto_posture(11, wait=False) is None  # a move of ~0.9 simulated s, ~45 ms here
            assert c.wait_at_rest(11).at_posture(11)
            assert not server.robot.is_moving and server.robot.current_posture == 11
            c.acknowledge(11)
            status = c.goto_posture(1)
            assert status.state == AT and not server.robot.is_moving
            assert np.allclose(server.robot.current_joints, server.robot.postures[0])


def test_robot_waits_for_acknowledgement(controller, server):
    controller.goto_posture(2)
    with pytest.raises(ControllerRefused) as info:
        controller.goto_posture(5)
    assert info.value.code == 5  # busy
    assert server.robot.current_posture == 2
    # asking again for the posture it stands at is harmless (a retried request)
    assert controller.goto_posture(2).posture == 2
    status = controller.acknowledge(2)
    assert status.state == READY and status.posture == 2
    assert controller.acknowledge(2).posture == 2  # repeated ACK is harmless
    assert controller.goto_posture(5).posture == 5
    assert np.allclose(controller.read_joints(), server.robot.postures[4], atol=1e-4)


def test_acknowledge_of_another_posture_is_refused(controller):
    controller.goto_posture(1)
    with pytest.raises(ControllerRefused):
        controller.acknowledge(4)
    controller.acknowledge(1)


def test_goto_without_waiting_then_wait_at_rest(controller, server):
    controller.goto_posture(7, wait=False)
    status = controller.wait_at_rest(7, timeout=10)
    assert status.at_posture(7)
    assert not server.robot.is_moving


def test_sequence_of_postures_calls_the_arrival_hook(controller, server):
    arrivals = []
    server.robot.arrival_hooks.append(lambda k, joints: arrivals.append((k, joints.copy())))
    for k in (4, 1, 12):
        controller.goto_posture(k)
        controller.acknowledge(k)
    assert [k for k, _ in arrivals] == [4, 1, 12]
    for k, joints in arrivals:
        assert np.allclose(joints, server.robot.postures[k - 1])
    assert server.robot.moves == 3


def test_tool_data_written_and_read_back(controller, server):
    q = np.array([0.9, 0.1, -0.3, 0.2])
    q /= np.linalg.norm(q)
    tool = ToolData((12.345, -67.891, 104.5), tuple(q), 1.25, (0.0, -5.0, 42.0))
    back = controller.set_tool(tool)
    assert back.close_to(tool)
    assert controller.read_tool().close_to(tool)
    stored = server.robot.tool  # the PERS tooldata of the program
    assert np.allclose(stored.position_mm, tool.position_mm, atol=1e-3)
    assert np.allclose(stored.quaternion_wxyz, q, atol=2e-6)
    assert stored.mass_kg == pytest.approx(1.25, abs=1e-3)


def test_tool_from_transform_roundtrip(controller):
    from handeye.geometry.transforms import transform_from_pose

    cam2tool0 = transform_from_pose([30.0, -12.5, 95.25], [0.5, -0.5, 0.5, 0.5])
    back = controller.set_tool(ToolData.from_transform(cam2tool0, mass_kg=0.8))
    assert np.allclose(back.position_mm, [30.0, -12.5, 95.25], atol=1e-3)
    assert np.allclose(back.quaternion_wxyz, [0.5, -0.5, 0.5, 0.5], atol=2e-6)


def test_ack_timeout_turns_the_state_late(protocol, connect_to):
    from handeye.mocks.controller import start_mock_controller

    with start_mock_controller(protocol, time_scale=0.002, ack_timeout_s=0.05) as server:
        with connect_to(server) as c:
            c.goto_posture(6)
            deadline = time.monotonic() + 2.0
            while c.status().state != LATE and time.monotonic() < deadline:
                time.sleep(0.01)
            assert c.status().state == LATE
            assert server.robot.current_posture == 6  # a late PC never makes the robot move on
            c.acknowledge(6)
            assert c.status().state == READY


def test_reconnect_after_close(server, connect_to):
    with connect_to(server) as c:
        c.goto_posture(8)
    with connect_to(server) as c:  # the program keeps its state across PC sessions
        status = c.status()
        assert status.posture == 8 and status.state == AT
        c.acknowledge(8)
