"""World zones the program defines (WZBoxDef, WZLimSup ...) are recorded on the simulated arm and
supervise its moves: a MoveAbsJ into a forbidden zone does not move the robot and stops the program."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.mocks.controller.arm import ArmBinding
from handeye.mocks.robot import SimulatedRobot
from handeye.rapid.interpreter import Bindings, Task, load_program

TARGET = [30.0, 0.0, 0.0, 0.0, 30.0, 0.0]
PROGRAM = """MODULE Z
  CONST jointtarget jtHome := [[0,0,0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jtAway := [[30,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  VAR wztemporary wzKeepOut;
  VAR shapedata shape;
  VAR num reached := 0;
  PROC main()
    {zone}
    MoveAbsJ jtAway, v100, fine, tool0;
    reached := 1;
    EXIT;
  ENDPROC
ENDMODULE
"""


def _run(zone: str):
    robot = SimulatedRobot([np.zeros(6), TARGET], time_scale=0.001)
    program = load_program([(PROGRAM.replace("{zone}", zone), "Z.mod")])
    task = Task(program, Bindings(motion=ArmBinding(robot))).start()
    assert task.finished.wait(10)
    return task, robot


def test_a_move_into_a_forbidden_box_is_refused_and_the_robot_stays():
    p, _ = SimulatedRobot([TARGET]).model.forward(TARGET)  # where tool0 ends up
    low = ", ".join(f"{v - 50:.1f}" for v in p)
    high = ", ".join(f"{v + 50:.1f}" for v in p)
    task, robot = _run(f"WZBoxDef \\Inside, shape, [{low}], [{high}];\n    WZLimSup \\Temp, wzKeepOut, shape;")
    assert task.state == "error" and "world zone 1 (box, inside)" in task.error and task.error.startswith("Z.mod:10:")
    assert robot.moves == 0 and np.allclose(robot.current_joints, 0.0)
    assert robot.world_zones[1]["shape"]["type"] == "box"
    assert task.program.datum("wzKeepOut", "Z").box[0].fields["wz"] == 1


@pytest.mark.parametrize("zone", [
    "WZCylDef \\Inside, shape, [0, 0, -500], 100, 200;\n    WZLimSup \\Temp, wzKeepOut, shape;",
    "WZHomeJointDef \\Outside, shape, jtHome, [[60,5,5,5,60,5],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    "    WZLimSup \\Temp, wzKeepOut, shape;",
])
def test_a_move_that_keeps_out_of_the_zones_runs(zone):
    task, robot = _run(zone)
    assert task.state == "exited", task.error
    assert robot.moves == 1 and np.allclose(robot.current_joints, TARGET)
    assert task.program.datum("reached", "Z").box[0] == 1


def test_joint_zone_outside_stops_a_move_beyond_it():
    task, robot = _run("WZHomeJointDef \\Outside, shape, jtHome, [[10,5,5,5,10,5],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
                       "    WZLimSup \\Temp, wzKeepOut, shape;")
    assert task.state == "error" and "world zone 1 (joints, outside)" in task.error
    assert robot.moves == 0
