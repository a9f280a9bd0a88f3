"""The simulated IRB 1400: synchronised motion timing, kinematics, limits, hooks."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.mocks.robot import SimulatedRobot

ROBOT = load_robot("IRB1400")
POSTURES = [[30.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, -20.0, 10.0, 90.0, 45.0, -120.0]]


class FakeClock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_motion_time_is_the_slowest_axis_at_its_speed_fraction():
    robot = SimulatedRobot(POSTURES, speed_fraction=0.5, clock=FakeClock())
    # axis 1: 30 deg at 0.5 * 120 deg/s = 0.5 s; axis 6: 120 deg at 0.5 * 280 = 0.857 s -> the move lasts 0.857 s
    assert robot.motion_time(POSTURES[0]) == pytest.approx(0.5)
    assert robot.motion_time(POSTURES[1]) == pytest.approx(120.0 / 140.0)


def test_synchronised_interpolation_and_arrival():
    clock = FakeClock()
    robot = SimulatedRobot(POSTURES, speed_fraction=0.5, time_scale=2.0, clock=clock)
    arrivals = []
    robot.arrival_hooks.append(lambda k, j: arrivals.append(k))
    duration = robot.start_posture(2)
    assert duration == pytest.approx(2.0 * 120.0 / 140.0)  # time_scale stretches wall-clock time
    clock.t += duration / 2
    assert robot.is_moving and robot.current_posture == 0
    assert np.allclose(robot.current_joints, np.array(POSTURES[1]) / 2)  # every axis half-way together
    assert arrivals == []
    clock.t += duration / 2 + 1e-9
    assert not robot.is_moving
    assert np.allclose(robot.current_joints, POSTURES[1])
    assert robot.current_posture == 2 and arrivals == [2]
    robot.update()
    assert arrivals == [2]  # reported once


def test_flange_pose_comes_from_the_kinematics_with_the_parallel_arm_coupling():
    robot = SimulatedRobot(POSTURES, time_scale=1e-6)
    pose = robot.tool0_pose()
    assert np.allclose(pose.position_mm, [955.0, 0.0, 1195.0], atol=1e-9)
    robot.start_posture(2)
    robot.wait_until_stopped(timeout=1)
    p, q = ROBOT.forward(POSTURES[1])
    pose = robot.tool0_pose()
    assert np.allclose(pose.position_mm, p) and np.allclose(pose.quaternion_wxyz, q)
    # without the coupling (axis 3 taken as the serial angle) the flange would be elsewhere
    serial = np.array(POSTURES[1])
    serial[2] += serial[1]
    assert np.linalg.norm(ROBOT.forward(serial)[0] - p) > 50


def test_a_guard_that_is_no_cell_is_refused_at_once():
    # a string other than SELF_ONLY used to be kept as the guard and fail at the first move (AttributeError)
    with pytest.raises(ValueError, match="guard must be a CellGuard"):
        SimulatedRobot(POSTURES, guard="self only")
    assert SimulatedRobot(POSTURES, guard=None).guard is None


def test_limits_are_enforced():
    with pytest.raises(ValueError, match="axis 2"):
        SimulatedRobot([[0, 80, 0, 0, 0, 0]])
    robot = SimulatedRobot(POSTURES)
    with pytest.raises(ValueError, match="axis 5"):
        robot.start_move([0, 0, 0, 0, 120, 0])
    with pytest.raises(ValueError, match="not one of"):
        robot.start_posture(3)
