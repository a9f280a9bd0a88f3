"""``handeye cell check`` (issue 21): exit codes, the JSON keys, the same verdicts as the planner's and the
mock's check; an unknown self-collision pair name in a robot file is refused at load with one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from handeye.robot.kinematics import ROBOTS_DIR, load_robot
from handeye.mocks.robot import SimulatedRobot, ZoneViolation
from handeye.mocks.station import DEFAULT_START
from handeye.rapid.interpreter import Bindings, Task, load_program
from handeye.mocks.controller.arm import ArmBinding
from handeye.station.cell.plan import cell_check
from handeye.station.cli import main
from handeye.station.config.station import ConfigError, config_from_dict, load_config

ROBOT = load_robot("IRB1400")
#: The wrist folded back (axis 5 at 108 deg): the camera in link 3 (the tube of the upper arm).
CAMERA_IN_LINK_3 = [-33.8, 29.3, 2.3, 19.9, 107.7, -115.3]
#: Leaning over the box of the config below.
INTO_BOX = [0.0, 45.0, 30.0, 0.0, 30.0, 0.0]
CONFIG = """\
robot: IRB1400
controller: {protocol: mock}
camera: {backend: mock}
cell:
  keep_out:
    - {type: floor, name: floor, z_mm: 0}
    - {type: box, name: fixture, min_mm: [900, -300, 0], max_mm: [1300, 300, 700]}
"""


def _files(tmp_path: Path, rows) -> tuple[Path, Path]:
    config = tmp_path / "station.yaml"
    config.write_text(CONFIG, encoding="utf-8")
    joints = tmp_path / "targets.csv"
    joints.write_text("a1,a2,a3,a4,a5,a6\n" + "".join(",".join(f"{v:g}" for v in row) + "\n" for row in rows),
                      encoding="utf-8")
    return config, joints


def test_all_clear_exits_0(tmp_path, capsys):
    config, joints = _files(tmp_path, [DEFAULT_START, [0, 0, 0, 0, 30, 0]])
    assert main(["cell", "check", "--config", str(config), str(joints), "--moves"]) == 0
    assert "all clear (2 postures, 1 moves, margin 30 mm)" in capsys.readouterr().out


def test_targets_in_the_arm_or_the_cell_exit_3_with_the_pair_and_the_distance(tmp_path, capsys):
    rows = [DEFAULT_START, CAMERA_IN_LINK_3, INTO_BOX, [0, 80, 0, 0, 0, 0]]
    config, joints = _files(tmp_path, rows)
    out = tmp_path / "check.json"
    assert main(["cell", "check", "--config", str(config), str(joints), "--moves", "--json", str(out)]) == 3
    text = capsys.readouterr().out
    assert "row 1 (line 3): NOT CLEAR: camera against link 3" in text
    data = json.loads(out.read_text())
    postures, moves = data["postures"], data["moves"]
    assert [p["row"] for p in postures] == [0, 1, 2, 3] and [p["clear"] for p in postures] == [True, False, False, False]
    assert {"row", "clear", "closest", "distance_mm"} <= set(postures[0])
    assert postures[1]["closest"] == "camera - link 3" and postures[1]["distance_mm"] < 0
    assert postures[2]["closest"].endswith(" - fixture") and postures[2]["kind"] == "cell"
    assert postures[3]["closest"] == "joint limits"
    assert [(m["from_row"], m["to_row"], m["clear"]) for m in moves] == [(0, 1, False), (1, 2, False), (2, 3, False)]
    assert moves[0]["closest"] == "camera - link 3" and 0 < moves[0]["at"] <= 1
    # the planner's check says the same of every posture
    guard = cell_check(load_config(config)).guard(ROBOT)
    for p, row in zip(postures[:3], rows):
        found = guard.posture_violation(row)
        assert (found is None) == p["clear"] and (found is None or found.pair == p["closest"])


def test_moves_whose_ends_are_all_outside_the_limits_are_reported_not_a_traceback(tmp_path, capsys):
    config, joints = _files(tmp_path, [DEFAULT_START, [0, 0, 0, 0, 170, 0]])  # axis 5 beyond its limit
    assert main(["cell", "check", "--config", str(config), str(joints), "--moves"]) == 3
    out = capsys.readouterr().out
    assert "move row 0 -> 1: NOT CLEAR: an end is outside the joint limits" in out


def test_a_bad_joints_file_is_refused_in_one_line(tmp_path, capsys):
    config, joints = _files(tmp_path, [[1, 2, 3, 4, 5]])
    assert main(["cell", "check", "--config", str(config), str(joints)]) == 1
    err = capsys.readouterr().err
    assert "line 2: expected 6 axis angles (deg), got 5 values" in err and err.count("\n") == 1


def test_the_mock_refuses_the_move_into_the_arm_without_a_cell_naming_the_pair():
    arm = SimulatedRobot([DEFAULT_START], start_joints=DEFAULT_START, time_scale=1e-4)  # no cell: self-collision only
    with pytest.raises(ZoneViolation, match="self-collision: camera against link 3 on the way to the target"):
        arm.start_move(CAMERA_IN_LINK_3)
    assert np.allclose(arm.current_joints, DEFAULT_START) and arm.refusals[-1].violation.kind == "self"
    program = load_program([("MODULE T\n  PROC main()\n    MoveAbsJ [[" + ",".join(f"{v:g}" for v in CAMERA_IN_LINK_3)
                             + "],[9E9,9E9,9E9,9E9,9E9,9E9]], v200, fine, tool0;\n  ENDPROC\nENDMODULE\n", "T.mod")])
    task = Task(program, Bindings(motion=ArmBinding(arm))).start()
    assert task.finished.wait(30) and task.state == "error"
    assert task.error.startswith("T.mod:3: MoveAbsJ: self-collision: camera against link 3"), task.error
    assert np.allclose(arm.current_joints, DEFAULT_START)


def test_the_standalone_mock_controller_arm_checks_self_collision():
    from handeye.mocks.controller import start_mock_controller

    server = start_mock_controller("socket", port=0, start=False)
    assert server.robot.guard is not None and server.robot.guard.self_check
    assert server.robot.path_violation([DEFAULT_START, CAMERA_IN_LINK_3]).reason == "camera against link 3"


def _robot_file(tmp_path: Path, pair: str) -> Path:
    text = (ROBOTS_DIR / "irb1400.yaml").read_text(encoding="utf-8").replace("name: IRB1400", "name: IRB1400 test")
    path = tmp_path / "arm.yaml"
    path.write_text(text.replace("    - [link 3, base]\n", f"    - [link 3, base]\n    - [{pair}]\n"), encoding="utf-8")
    return path


def test_an_unknown_name_in_the_self_collision_pairs_is_refused_at_load(tmp_path):
    path = _robot_file(tmp_path, "carried, link 9")
    with pytest.raises(ValueError) as refused:
        load_robot(str(path))
    message = str(refused.value)
    assert "'link 9'" in message and "self_collision.pairs" in message and "\n" not in message
    with pytest.raises(ConfigError) as config:
        config_from_dict({"robot": str(path), "controller": {"protocol": "mock"}, "camera": {"backend": "mock"}})
    assert "'link 9'" in str(config.value) and "\n" not in str(config.value)
    assert load_robot(str(_robot_file(tmp_path, "link 6, link 3"))).self_pairs[-1] == ("link 6", "link 3")


# ------------------------------------------------------------------ the joints file read by the CSV rules (issue 42.1)
def _check(tmp_path, text, *extra):
    config = tmp_path / "station.yaml"
    config.write_text(CONFIG, encoding="utf-8")
    joints = tmp_path / "t.csv"
    joints.write_text(text, encoding="utf-8")
    return main(["cell", "check", "--config", str(config), str(joints), "--moves", *extra])


#: The wrist folded down onto the lower arm: the row of the issue, which is not clear (the closest pair is link 5
#: against link 2 with the capsules fitted to the meshes' surface, issue 41; link 6 against link 2 with the
#: vertex-only fit; link 4 against link 1 with the estimated ones).
COLLIDING = "0,-30,60,0,90,0"


@pytest.mark.parametrize("first, why", [
    ("0,-30,6O,0,90,0", "not a number: '6O'"),                      # a letter O for a zero
    ("0 -30 60 0 90 0", "not one number: '0 -30 60 0 90 0' (separate the values by commas)"),
    ("0,-30,60,0,90,0 # the colliding one", "not a number: '0 # the colliding one' (a comment is a line of its own"),
    ("0,-30,nan,0,90,0", "not finite: 'nan'"),
    ("0,-30,inf,0,90,0", "not finite: 'inf'"),
    ("0,-30,1e400,0,90,0", "not finite: '1e400' is beyond the float range"),
    ("0,-30,60,0,90,1_000", "not a number: '1_000' (write it without digit separators"),
])
def test_a_bad_first_row_is_refused_never_taken_as_a_header(tmp_path, capsys, first, why):
    assert _check(tmp_path, first + "\n0,10,0,0,0,0\n") == 1
    captured = capsys.readouterr()
    assert "all clear" not in captured.out
    assert f"t.csv line 1: {why}" in captured.err and captured.err.count("\n") == 1, captured.err


def test_the_same_bad_value_on_a_later_row_says_what_is_wrong(tmp_path, capsys):
    assert _check(tmp_path, "a1,a2,a3,a4,a5,a6\n0,10,0,0,0,0\n0,-30,nan,0,90,0\n") == 1
    err = capsys.readouterr().err
    assert "t.csv line 3: not finite: 'nan'" in err and "got 6 values" not in err


def test_a_header_is_a_line_without_numbers_and_the_output_names_it(tmp_path, capsys):
    assert _check(tmp_path, "# targets of HeCal\naxis 1,a2,a3,a4,a5,a6\n" + COLLIDING + "\n0,10,0,0,0,0\n") == 3
    out = capsys.readouterr().out
    assert "line 2 taken as a header (no number in it), not checked: 'axis 1,a2,a3,a4,a5,a6'" in out
    assert "row 0 (line 3): NOT CLEAR: link 5 against link 2" in out
    assert _check(tmp_path, COLLIDING + "\n0,10,0,0,0,0\n") == 3  # no header: none named
    assert "taken as a header" not in capsys.readouterr().out


def test_the_json_names_the_header_line_and_stdout_stays_json(tmp_path, capsys):
    assert _check(tmp_path, "a1,a2,a3,a4,a5,a6\n" + COLLIDING + "\n", "--json", "-") == 3
    captured = capsys.readouterr()
    assert json.loads(captured.out)["header_line"] == 1 and "taken as a header" in captured.err


# ------------------------------------------------------------------ the capsules fitted to the meshes (issue 41)
#: The robot file's link_bodies before issue 41: estimated from the outline, padded by 30 mm.
ESTIMATED_BODIES = """\
  - {name: base, link: 0, from_mm: [-90, 0, 110], to_mm: [90, 0, 110], radius_mm: 230}
  - {name: link 1, link: 1, from_mm: [0, 0, 330], to_mm: [150, 0, 475], radius_mm: 160}
  - {name: link 1, link: 1, from_mm: [150, -160, 475], to_mm: [150, 160, 475], radius_mm: 125}
  - {name: link 2, link: 2, from_mm: [150, 0, 475], to_mm: [150, 0, 1075], radius_mm: 105}
  - {name: link 3, link: 3, from_mm: [-100, 0, 1180], to_mm: [330, 0, 1180], radius_mm: 125}
  - {name: link 3, link: 3, from_mm: [150, 0, 1195], to_mm: [670, 0, 1195], radius_mm: 75}
"""
#: The base's rear cable box reaches x -398 (the mesh, y +-182, z 12..64): a box 7 mm behind it.
REAR_BOX = "{type: box, name: cable duct, min_mm: [-600, -100, 0], max_mm: [-405, 100, 300]}"
#: Link 1's side motors reach |y| 341 (the mesh, x -82..71, z 242..395 at axis 1 = 0): a post 20 mm beside them.
MOTOR_POST = "{type: cylinder, name: post, centre_mm: [0, 401], radius_mm: 40, z_mm: [0, 600]}"
#: Axis 1 at 0, the wrist far in front: only the base and link 1 are near either volume.
FACING_FRONT = [0, 0, 0, 0, 30, 0]


def _estimated_robot(tmp_path: Path) -> Path:
    text = (ROBOTS_DIR / "irb1400.yaml").read_text(encoding="utf-8").replace("name: IRB1400", "name: IRB1400 estimated")
    head, rest = text.split("# fitted: begin\n", 1)
    path = tmp_path / "estimated.yaml"
    path.write_text(head + "# fitted: begin\n" + ESTIMATED_BODIES + "# fitted: end" + rest.split("# fitted: end", 1)[1],
                    encoding="utf-8")
    return path


def _cell_check(tmp_path, robot: str, volume: str) -> int:
    config = tmp_path / f"{robot.replace('/', '_')}.yaml"
    config.write_text(CONFIG.replace("robot: IRB1400", f"robot: {robot}").replace(
        "    - {type: box, name: fixture", f"    - {volume}\n    - {{type: box, name: fixture"), encoding="utf-8")
    joints = tmp_path / "targets.csv"
    joints.write_text(",".join(f"{v:g}" for v in FACING_FRONT) + "\n", encoding="utf-8")
    return main(["cell", "check", "--config", str(config), str(joints)])


def test_a_box_at_the_base_rear_is_refused_now_and_passed_the_estimated_base(tmp_path, capsys):
    assert _cell_check(tmp_path, str(_estimated_robot(tmp_path)), REAR_BOX) == 0
    assert "all clear" in capsys.readouterr().out
    assert _cell_check(tmp_path, "IRB1400", REAR_BOX) == 1  # the base never moves: refused when the cell loads
    err = capsys.readouterr().err
    assert "'cable duct' (box, cell.keep_out)" in err and "robot's base" in err and err.count("\n") == 1, err


def test_a_post_beside_link_1s_motors_is_refused_now_and_passed_the_estimated_link_1(tmp_path, capsys):
    assert _cell_check(tmp_path, str(_estimated_robot(tmp_path)), MOTOR_POST) == 0
    assert "all clear" in capsys.readouterr().out
    assert _cell_check(tmp_path, "IRB1400", MOTOR_POST) == 3
    assert "row 0 (line 1): NOT CLEAR: link 1 " in capsys.readouterr().out
