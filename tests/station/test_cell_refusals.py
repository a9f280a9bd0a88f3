"""Cell settings that cannot be meant are refused with one line that names the volume (issue 25, finding
7c): a keep-out box around the board, a floor above the robot's foot, a cell written in metres."""

import numpy as np
import pytest

from handeye.robot.cell import Box, CellModel, Floor
from handeye.geometry.board import BoardGeometry, board_corners
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.cell.plan import CellCheck
from handeye.station.config.cell import DEFAULT_CARRIED
from handeye.station.config.station import ConfigError, config_from_dict
from handeye.station.capture.planning import PlanningError, plan_postures

ROBOT = load_robot("IRB1400")
BOARD = BoardGeometry((13, 8), 30.0)
MOCK = {"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}


def _board_box(grow_mm: float) -> Box:
    """An axis-aligned box in base around the default board's corners, grown by ``grow_mm``."""
    corners = board_corners(BOARD.corners, BOARD.square_mm) @ DEFAULT_BOARD[:3, :3].T + DEFAULT_BOARD[:3, 3]
    return Box("inspection table guard", tuple(corners.min(axis=0) - grow_mm), tuple(corners.max(axis=0) + grow_mm))


def test_a_keep_out_box_around_the_board_is_refused_naming_it():
    """A box around the board and the space above it (a guard around the inspection table): every view
    point is inside it. On main the plan failed on the start posture: 'jog the robot out of it'."""
    cell = CellModel((Floor("floor", 0.0), _board_box(1300.0)), DEFAULT_CARRIED)
    view = invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    with pytest.raises(PlanningError) as refused:
        plan_postures(ROBOT, DEFAULT_START, view, DEFAULT_MOUNT, BOARD, count=12, seed=1, cell=CellCheck(cell))
    message = str(refused.value)
    assert message.startswith("the keep-out volume 'inspection table guard' (box, cell.keep_out) holds the board and "
                              "fills the space the camera must view the board from (700-1200 mm in front of it")
    assert "block every view" in message and "jog" not in message and "\n" not in message


def test_volumes_that_leave_some_views_are_no_board_problem():
    from handeye.station.cell.plan import board_problem, view_points

    points = view_points(DEFAULT_BOARD, BOARD, (700.0, 1200.0), 35.0)
    centre = DEFAULT_BOARD[:3, :3] @ board_corners(BOARD.corners, BOARD.square_mm).mean(axis=0) + DEFAULT_BOARD[:3, 3]
    assert np.allclose(np.linalg.norm(points[:9] - centre, axis=1), 700.0)  # on the spheres about the board centre
    assert np.allclose(np.linalg.norm(points[9:] - centre, axis=1), 1200.0)
    tilt = np.degrees(np.arccos((points - centre) @ -DEFAULT_BOARD[:3, 2] / np.linalg.norm(points - centre, axis=1)))
    assert np.allclose(np.sort(tilt)[[0, 1, 2, -1]], [0, 0, 35, 35], atol=1e-5)  # in front, up to the cone's rim
    thin = _board_box(40.0)  # a box just around the board, like its stand: the views are outside it
    wall = Box("left wall", (0, 200, 0), (2000, 1500, 2500))  # holds a few corners, leaves most views
    assert board_problem(CellModel((Floor("floor", 0.0), thin, wall)), DEFAULT_BOARD, BOARD) is None
    above = Box("hood", (0, -1500, 500), (2500, 1500, 3000))  # every view point, not the board
    assert "'hood' (box, cell.keep_out) fills the space" in board_problem(CellModel((above,)), DEFAULT_BOARD, BOARD)


@pytest.mark.parametrize("volume, words", [
    ({"type": "floor", "name": "table", "z_mm": 300},
     ["cell.keep_out[0].z_mm is 300", "robot's foot (base z 0) would stand inside 'table'", "0 or below"]),
    ({"type": "box", "name": "fixture", "min_mm": [1.15, -0.6, 0], "max_mm": [1.6, -0.25, 0.7]},
     ["cell.keep_out[0] ('fixture')", "looks like metres", "mm (e.g. 1.15 m -> 1150)"]),
    ({"type": "cylinder", "name": "column", "centre_mm": [-0.4, 0.7], "radius_mm": 0.12, "z_mm": [0, 2.2]},
     ["cell.keep_out[0] ('column')", "looks like metres"]),
])
def test_a_floor_above_the_foot_and_a_cell_in_metres_are_refused(volume, words):
    with pytest.raises(ConfigError) as refused:
        config_from_dict({**MOCK, "cell": {"keep_out": [volume]}})
    assert all(w in str(refused.value) for w in words), str(refused.value)
    assert "\n" not in str(refused.value)


def test_a_carried_box_in_metres_is_refused():
    with pytest.raises(ConfigError, match=r"cell.carried\[0\] \('camera'\).*looks like metres"):
        config_from_dict({**MOCK, "cell": {"carried": [{"type": "box", "name": "camera", "min_mm": [-0.136, 0.011, 0.058],
                                                        "max_mm": [-0.094, 0.288, 0.1]}]}})


def test_plausible_cells_still_load():
    config = config_from_dict({**MOCK, "cell": {"keep_out": [
        {"type": "floor", "z_mm": -250}, {"type": "box", "name": "fixture", "min_mm": [1150, -600, 0], "max_mm": [1600, -250, 700]},
        {"type": "cylinder", "name": "column", "centre_mm": [-400, 700], "radius_mm": 120, "z_mm": [0, 2200]}]}})
    assert [v.name for v in config.cell.keep_out] == ["floor", "fixture", "column"]


# ---------------------------------------------------------------- the base against the keep-out volumes
#: The robot file's base capsules (fitted to the meshes, issue 41): how far they reach in front (+x) and behind
#: (-x), each from a capsule's end whose y and z lie inside the boxes below (y within +-250, z within 0..800),
#: so a box's face that far plus a gap is that gap from the base.
BASE = [(np.asarray(b.start_mm), np.asarray(b.end_mm), b.radius_mm) for b in ROBOT.link_bodies if b.link == 0]
FRONT = max(max(a[0], b[0]) + r for a, b, r in BASE)
BACK = min(min(a[0], b[0]) - r for a, b, r in BASE)
#: The capsules' end farthest to -y and its reach there (x, y - r): a vertical post's nearest point of the base.
SIDE_X, SIDE_Y = min(((e[0], e[1] - r) for a, b, r in BASE for e in (a, b)), key=lambda e: e[1])


def test_the_base_distance_is_the_capsule_geometry():
    """A box beside the base, its face 20 mm in front of the base capsules' reach: 20 mm from the base, to
    within half a sample spacing below (never above); one behind: 20 mm from the capsules' rear reach."""
    from handeye.robot.base_clearance import BASE_STEP_MM, base_clearances

    assert all(abs(e[1]) < 250 and 0 < e[2] < 800 for a, b, _ in BASE for e in (a, b))
    beside = Box("beside", (FRONT + 20.0, -250.0, 0.0), (900.0, 250.0, 800.0))
    behind = Box("behind", (-900.0, -250.0, 0.0), (BACK - 20.0, 250.0, 800.0))
    gaps = dict((v.name, d) for v, d in base_clearances(ROBOT, [beside, behind, Floor("floor", 0.0)]))
    assert set(gaps) == {"beside", "behind"}  # the floor carries the robot: not measured
    for gap in gaps.values():
        assert 20.0 - BASE_STEP_MM / 2 - 1e-9 <= gap <= 20.0


@pytest.mark.parametrize("volume, words", [
    ({"type": "box", "name": "cabinet", "min_mm": [FRONT - 120, -250, 0], "max_mm": [600, 250, 900]},
     ["the keep-out volume 'cabinet' (box, cell.keep_out) reaches 120 mm into the robot's base", "cell.margin_mm (30 mm)",
      "move or shrink the volume", "wholly at or below base z 0"]),
    ({"type": "box", "name": "tool rack", "min_mm": [FRONT + 20, -250, -50], "max_mm": [700, 250, 900]},
     ["'tool rack' (box, cell.keep_out) is 20 mm from the robot's base", "within cell.margin_mm (30 mm)"]),
    ({"type": "cylinder", "name": "post", "centre_mm": [SIDE_X, SIDE_Y - 70], "radius_mm": 50, "z_mm": [-200, 1500]},
     ["'post' (cylinder, cell.keep_out) is 20 mm from the robot's base"]),
])
def test_a_volume_within_the_margin_of_the_base_is_refused_at_load(volume, words):
    """The base never moves: a volume at (or within the margin of) it is refused once, when the config loads,
    naming the volume and the distance (a post reaching below the foot is no floor: its top is above z 0)."""
    with pytest.raises(ConfigError) as refused:
        config_from_dict({**MOCK, "cell": {"keep_out": [{"type": "floor", "z_mm": 0}, volume]}})
    message = str(refused.value)
    assert all(w in message for w in words), message
    assert "\n" not in message


def test_volumes_the_robot_stands_on_and_volumes_clear_of_the_base_load():
    """The floor, a foundation box and a pedestal cylinder wholly at or below base z 0 overlap the base's
    envelope (it reaches below the foot) and are accepted; so is a cabinet 40 mm from the base."""
    config = config_from_dict({**MOCK, "cell": {"keep_out": [
        {"type": "floor", "name": "floor", "z_mm": -400},
        {"type": "box", "name": "foundation", "min_mm": [-600, -600, -400], "max_mm": [600, 600, 0]},
        {"type": "cylinder", "name": "pedestal", "centre_mm": [0, 0], "radius_mm": 300, "z_mm": [-400, 0]},
        {"type": "box", "name": "cabinet", "min_mm": [FRONT + 40, -250, 0], "max_mm": [900, 250, 700]}]}})
    assert [v.name for v in config.cell.keep_out] == ["floor", "foundation", "pedestal", "cabinet"]


def test_the_planner_refuses_a_cell_built_in_code_with_a_volume_in_the_base():
    """A CellCheck built without a config (a script, a benchmark) gets the same line from the planner, and
    the board's stand is checked against the base too."""
    from handeye.station.cell.plan import base_problem

    cell = CellModel((Floor("floor", 0.0), Box("cabinet", (FRONT - 120, -250, 0), (600, 250, 900))), DEFAULT_CARRIED)
    view = invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    with pytest.raises(PlanningError) as refused:
        plan_postures(ROBOT, DEFAULT_START, view, DEFAULT_MOUNT, BOARD, count=12, seed=1, cell=CellCheck(cell))
    assert str(refused.value).startswith("the keep-out volume 'cabinet' (box, cell.keep_out) reaches 120 mm into the "
                                         "robot's base")
    stand = Box("board stand", (FRONT - 20, -250, 0), (FRONT + 180, 250, 600))  # not configured; 20 mm into the base
    message = base_problem(ROBOT, [Floor("floor", 0.0), stand], 30.0, keep_out=(Floor("floor", 0.0),))
    assert message.startswith("the board's stand 'board stand' reaches 20 mm into the robot's base")
    assert "place the board farther" in message
    assert base_problem(ROBOT, list(cell.keep_out[:1]), 30.0) is None
