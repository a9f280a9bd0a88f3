"""The built-in station's 12 postures are collision-free with the arm's fitted bodies (issue 41).

Every posture keeps the camera, its bracket and the arm's links 30 mm apart (the robot file's self-collision
pairs), and every joint move from all axes at 0 or between any two postures stays clear of touching, as the
mock controller's motion supervision samples it (5 mm): the programme may visit them in any order. They are
what ``make_scene(SceneConfig(postures=12, self_clear_mm=30))`` draws, rounded to 0.01 deg.
"""

import numpy as np

from handeye.robot.cell import DEFAULT_CARRIED
from handeye.robot.clearance import CellGuard
from handeye.robot.kinematics import load_robot
from handeye.calibration.synthetic import SceneConfig, make_scene
from handeye.mocks.robot import self_guard
from handeye.rapid.station import default_station

ROBOT = load_robot("IRB1400")
POSTURES = np.array(default_station().postures, float)


def test_the_file_holds_the_scene_s_postures():
    scene = make_scene(SceneConfig(postures=12, self_clear_mm=30.0))
    assert np.abs(np.round(scene.joints_deg, 2) - POSTURES).max() < 1e-9


def test_every_posture_keeps_the_margin_and_every_move_between_them_is_clear():
    guard = CellGuard(ROBOT, [], DEFAULT_CARRIED, margin_mm=30.0)
    assert [guard.posture_violation(p) for p in POSTURES] == [None] * len(POSTURES)
    moves = self_guard(ROBOT)
    nodes = np.vstack([np.zeros(ROBOT.dof), POSTURES])
    touching = [(a, b) for a in range(len(nodes)) for b in range(a + 1, len(nodes))
                if moves.path_violation(nodes[a], nodes[b]) is not None]
    assert touching == []


def test_the_check_refuses_the_postures_used_before():
    """Not vacuous: the old posture 5 (drawn without the check) has the camera 17 mm into link 3."""
    old = np.array([-33.21, -18.21, -0.3, 27.28, 99.97, -125.98])
    found = CellGuard(ROBOT, [], DEFAULT_CARRIED, margin_mm=0.0).posture_violation(old)
    assert found is not None and found.reason == "camera against link 3"
