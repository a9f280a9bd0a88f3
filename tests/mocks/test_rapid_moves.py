"""The moves a station engineer adds, run by the interpreter on the simulated arm: Offs and RelTool
against hand-computed poses, MoveL straight in the TCP and checked along it, MoveJ and the
configuration rules (confdata), the cell stopping a move at its line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from handeye.robot.cell import Box, Sphere
from handeye.robot.clearance import CellGuard
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import transform_from_pose
from handeye.mocks.controller.arm import ArmBinding
from handeye.mocks.robot import SimulatedRobot
from handeye.rapid.interpreter import Bindings, FixedArm, Task, load_program
from handeye.rapid.interpreter.configuration import confdata

ROBOT = load_robot("IRB1400")
START = [10.0, 10.0, 10.0, 60.0, 50.0, 30.0]
TOOL = "PERS tooldata tPen := [TRUE, [[0, 0, 100], [1, 0, 0, 0]], [1, [0, 0, 50], [1, 0, 0, 0], 0, 0, 0]];"


def _program(body: str, data: str = "") -> str:
    return (f"MODULE T\n  {TOOL}\n  VAR robtarget p;\n  VAR robtarget q;\n  VAR jointtarget j;\n{data}\n"
            f"  PROC main()\n{body}\n    EXIT;\n  ENDPROC\nENDMODULE\n")


def _run(body: str, data: str = "", robot=None, expect="exited"):
    robot = robot or SimulatedRobot([START], start_joints=START, time_scale=1e-4)
    program = load_program([(_program(body, data), "T.mod")])
    task = Task(program, Bindings(motion=ArmBinding(robot))).start()
    assert task.finished.wait(60), "the program did not end"
    assert task.state == expect, task.error
    return task, program, robot


def _datum(program, name):
    return program.datum(name, "T").box[0]


def _xyz(record):
    return np.array([record.fields["trans"].fields[c] for c in "xyz"])


def _quat(record):
    return np.array([record.fields["rot"].fields[c] for c in ("q1", "q2", "q3", "q4")])


def test_offs_and_reltool_against_hand_computed_poses():
    body = """    p := [[100, 200, 300], [0.70710678, 0, 0.70710678, 0], [0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];
    q := Offs(p, 10, -20, 30);
    p := RelTool(p, 10, 20, 30 \\Rz:=90);"""
    task = Task(load_program([(_program(body), "T.mod")]), Bindings(motion=FixedArm())).start()
    assert task.finished.wait(10) and task.state == "exited", task.error
    program = task.program
    assert np.allclose(_xyz(_datum(program, "q")), [110, 180, 330])
    assert np.allclose(_quat(_datum(program, "q")), [0.70710678, 0, 0.70710678, 0], atol=1e-6)
    # the tool frame is turned 90 deg about base y: its x is base -z, its y base y, its z base x
    moved = _datum(program, "p")
    assert np.allclose(_xyz(moved), [100 + 30, 200 + 20, 300 - 10], atol=1e-3)
    # then turned 90 deg about its own z: q * (cos 45, 0, 0, sin 45)
    h = math.sqrt(0.5)  # (h, 0, h, 0) * (h, 0, 0, h) by the Hamilton product
    expected = np.array([h * h, h * h, h * h, h * h])
    assert np.allclose(_quat(moved), expected, atol=1e-6)


def test_movel_moves_the_tcp_on_the_straight_line_and_ends_at_the_target():
    robot = SimulatedRobot([START], start_joints=START, time_scale=1e-4)
    paths = []
    original = robot.start_path
    robot.start_path = lambda configurations, posture=0: (paths.append(np.array(configurations)),
                                                          original(configurations, posture))[1]
    body = """    p := CRobT(\\Tool:=tPen \\WObj:=wobj0);
    q := Offs(p, -150, 200, -120);
    MoveL q, v200, fine, tPen;
    p := CRobT(\\Tool:=tPen \\WObj:=wobj0);"""
    task, program, robot = _run(body, robot=robot)
    (path,) = paths
    start_tcp = (ROBOT.forward_transform(START) @ transform_from_pose([0, 0, 100], [1, 0, 0, 0]))[:3, 3]
    tcps = (ROBOT.forward_transform(path) @ transform_from_pose([0, 0, 100], [1, 0, 0, 0]))[:, :3, 3]
    end = start_tcp + [-150, 200, -120]
    direction = (end - start_tcp) / np.linalg.norm(end - start_tcp)
    off_line = tcps - start_tcp - np.outer((tcps - start_tcp) @ direction, direction)
    assert np.abs(off_line).max() < 0.01  # every sample on the line (mm)
    steps = np.linalg.norm(np.diff(np.vstack([start_tcp, tcps]), axis=0), axis=1)
    assert steps.max() <= 5.0 + 1e-6 and len(path) >= 55  # 291 mm in steps of at most 5 mm
    assert np.allclose(_xyz(_datum(program, "p")), end, atol=0.01)
    # the orientation did not change along the line
    rotations = ROBOT.forward_transform(path)[:, :3, :3]
    assert np.allclose(rotations, ROBOT.forward_transform(START)[:3, :3], atol=1e-6)


def test_movej_goes_to_the_solution_of_the_robtargets_configuration():
    flipped = [10.0, 10.0, 10.0, 60.0 - 180.0, -50.0, 30.0 - 180.0]
    assert confdata(ROBOT, START) == (0, 0, 0, 0) and confdata(ROBOT, flipped) == (0, -2, -2, 1)
    body = """    p := CRobT(\\Tool:=tPen);
    p.robconf := [0, -2, -2, 1];
    MoveJ Offs(p, 0, 0, -50), v500, z10, tPen;
    j := CJointT();
    ConfJ \\Off;
    MoveJ Offs(p, 0, 0, -80), v500, fine, tPen;
    q := CRobT(\\Tool:=tPen);"""
    task, program, robot = _run(body)
    joints = [_datum(program, "j").fields["robax"].fields[f"rax_{i}"] for i in range(1, 7)]
    assert confdata(ROBOT, joints) == (0, -2, -2, 1)  # the programmed configuration: the wrist flipped
    # ConfJ \Off: the nearest solution, so the wrist stays as it is (the robconf asks for nothing)
    assert confdata(ROBOT, robot.current_joints) == (0, -2, -2, 1)
    assert _datum(program, "q").fields["robconf"].fields["cfx"] == 1


def test_a_configuration_no_solution_has_stops_the_program_at_the_line():
    body = """    p := CRobT(\\Tool:=tPen);
    p.robconf := [2, 0, 0, 0];
    MoveJ p, v500, fine, tPen;"""
    task, _, robot = _run(body, expect="error")
    assert "T.mod:10: MoveJ: no solution with the robtarget's configuration [2, 0, 0, 0]" in task.error
    assert np.allclose(robot.current_joints, START)


def test_movel_across_a_keep_out_box_stops_at_its_line_naming_the_box():
    start_tcp = (ROBOT.forward_transform(START) @ transform_from_pose([0, 0, 100], [1, 0, 0, 0]))[:3, 3]
    # a box across the middle of the line, away from where the arm stands and where it goes
    middle = start_tcp + [0, 150, 0]
    box = Box("fixture", tuple(middle + [-40, -20, -300]), tuple(middle + [40, 20, 20]))
    pen = Sphere("pen", (0.0, 0.0, 100.0), 5.0)  # what the tool carries, at its TCP
    guard = CellGuard(ROBOT, [box], carried=[pen], margin_mm=0.0, step_mm=5.0)
    robot = SimulatedRobot([START], start_joints=START, time_scale=1e-4, guard=guard)
    assert guard.posture_violation(START) is None
    body = """    p := CRobT(\\Tool:=tPen);
    MoveL Offs(p, 0, 300, 0), v200, fine, tPen;"""
    task, _, robot = _run(body, robot=robot, expect="error")
    assert task.error.startswith("T.mod:9: MoveL: world zone: ") and "'fixture'" in task.error
    assert np.allclose(robot.current_joints, START)  # stopped before it moved
    # the check followed the TCP line: the pen's straight path crosses the box
    assert robot.refusals[-1].violation.volume == "fixture"


@pytest.mark.parametrize("body, message", [
    ("    ConfL \\On \\Off;", "ConfL takes one of \\On and \\Off"),
    ("    SingArea \\LockAxis4;", "SingArea \\LockAxis4 is not supported"),
    ("    p := CRobT(\\Tool:=tPen);\n    MoveL Offs(p, 0, 0, 5000), v200, fine, tPen;", "leaves the reach"),
])
def test_what_a_move_cannot_do_stops_the_program_naming_it(body, message):
    task, _, _ = _run(body, expect="error")
    assert message in task.error
