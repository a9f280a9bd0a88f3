"""The cell's geometry (calibration.cell) and the clearance check of postures and moves (calibration.clearance)."""

import numpy as np
import pytest

from handeye.robot.cell import Box, CellModel, Cylinder, Floor, Sphere, board_stand
from handeye.robot.clearance import CellGuard, carried_spheres, link_spheres
from handeye.geometry.board import BoardGeometry
from handeye.robot.kinematics import load_robot
from handeye.mocks.station import DEFAULT_BOARD

ROBOT = load_robot("IRB1400")
CAMERA = Box("camera", (-136.0, 11.0, 58.0), (-94.0, 288.0, 100.0))
BRACKET = Box("bracket", (-140.0, -45.0, 0.0), (45.0, 45.0, 58.0))


def test_signed_distances_of_the_volumes():
    box = Box("b", (0, 0, 0), (100, 200, 300))
    assert box.signed_distance([50, 100, 150]) == pytest.approx(-50)  # nearest face: x
    assert box.signed_distance([[130, 100, 150], [103, 204, 300]]) == pytest.approx([30, 5])
    turned = Box("t", (-10, -10, -10), (10, 10, 10), ((0, -1, 0, 500), (1, 0, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)))
    assert turned.signed_distance([500, 30, 0]) == pytest.approx(20)
    cylinder = Cylinder("c", (100, 0), 50, (0, 1000))
    assert cylinder.signed_distance([[100, 0, 500], [180, 0, 500], [100, 0, 1040], [190, 0, 1030]]) == \
        pytest.approx([-50, 30, 40, 50])
    assert Floor("f", 10.0).signed_distance([[0, 0, 5], [0, 0, 40]]) == pytest.approx([-5, 30])


def test_world_zones_are_axis_aligned_and_cover_the_volume():
    stand = board_stand(DEFAULT_BOARD, BoardGeometry((13, 8), 30.0), 50.0, 100.0, floor_z_mm=-200.0)
    plate = stand[0]
    zone = plate.world_zone()
    assert zone["type"] == "box"
    corners = plate.corners()
    assert np.all(corners >= np.array(zone["min_mm"]) - 1e-9) and np.all(corners <= np.array(zone["max_mm"]) + 1e-9)
    # the plate holds every board corner, grown by the margin; the leg reaches the floor
    from handeye.geometry.board import board_corners

    points = board_corners((13, 8), 30.0) @ DEFAULT_BOARD[:3, :3].T + DEFAULT_BOARD[:3, 3]
    assert np.all(plate.signed_distance(points) <= -50 + 1e-6)
    assert stand[1].min_mm[2] == -200.0 and stand[1].max_mm[2] == pytest.approx(corners[:, 2].min())
    floor = Floor("floor", 0.0).world_zone()
    assert floor["max_mm"][2] == 0.0 and floor["min_mm"][2] < -1000
    cylinder = Cylinder("c", (1, 2), 3, (4, 10)).world_zone()
    assert cylinder == {"type": "cylinder", "name": "c", "base_mm": (1.0, 2.0, 4.0), "radius_mm": 3.0, "height_mm": 6.0}


def test_the_spheres_cover_the_bodies():
    rng = np.random.default_rng(0)
    for body in (CAMERA, BRACKET):
        spheres = [(c, r) for c, r, name in carried_spheres([body]) if name == body.name]
        low, high = np.array(body.min_mm), np.array(body.max_mm)
        points = low + rng.uniform(size=(2000, 3)) * (high - low)
        inside = np.zeros(len(points), bool)
        for centre, radius in spheres:
            inside |= np.linalg.norm(points - centre, axis=1) <= radius + 1e-9
        assert inside.all()
    cable = carried_spheres([Sphere("cable", (1, 2, 3), 40)])
    assert len(cable) == 1 and cable[0][1] == 40
    # each capsule: points within its radius of its axis lie in one of its spheres
    guard = CellGuard(ROBOT, [], [], margin_mm=0)
    joints = np.array([10, -20, 30, 40, -50, 60.0])
    chain = ROBOT.chain_points(joints)
    centres = guard.sphere_centres(joints)[0]
    for body in ROBOT.bodies:
        rows = [i for i, name in enumerate(guard.bodies) if name == body.name]
        axis = chain[body.start] + rng.uniform(size=(3000, 1)) * (chain[body.end] - chain[body.start])
        offset = rng.normal(size=(3000, 3))
        offset *= body.radius_mm * rng.uniform(size=(3000, 1)) ** (1 / 3) / np.linalg.norm(offset, axis=1, keepdims=True)
        points = axis + offset
        gap = np.min(np.linalg.norm(points[:, None] - centres[rows][None], axis=2) - guard.radii[rows][None], axis=1)
        assert np.all(gap <= 1e-9)


def test_link_spheres_follow_the_chain():
    rows = link_spheres(ROBOT)
    assert {name for *_, name in rows} == {"link 4", "link 5", "link 6"}
    home = ROBOT.chain_points(np.zeros(6))
    assert home[-1] == pytest.approx([955.0, 0.0, 1195.0])  # tool0 at home, as the reference says
    assert home[4] == pytest.approx([870.0, 0.0, 1195.0])  # the wrist centre


def _sweeping_move():
    """Two postures clear of a box that the straight joint-space move between them sweeps through."""
    a = np.array([-40.0, 10, 10, 0, 60, 0])
    b = np.array([40.0, 10, 10, 0, 60, 0])
    mid = ROBOT.forward_transform((a + b) / 2)[:3, 3]
    return a, b, Box("post", tuple(mid + [-60, -60, -60]), tuple(mid + [60, 60, 60]))


def test_a_move_sweeping_through_a_volume_is_caught_between_clear_ends():
    a, b, post = _sweeping_move()
    guard = CellGuard(ROBOT, [post], [CAMERA, BRACKET], margin_mm=30, step_mm=10)
    assert guard.posture_violation(a) is None and guard.posture_violation(b) is None
    violation = guard.path_violation(a, b)
    assert violation is not None and violation.volume == "post" and 0 < violation.at < 1
    assert guard.path_violation(b, a) is not None
    assert CellGuard(ROBOT, [Floor("floor", 0.0)], [CAMERA, BRACKET]).path_violation(a, b) is None


def test_batched_moves_agree_with_single_moves():
    a, b, post = _sweeping_move()
    guard = CellGuard(ROBOT, [post, Floor("floor", 0.0)], [CAMERA, BRACKET], margin_mm=30, step_mm=10)
    rng = np.random.default_rng(2)
    nodes = np.vstack([a, b, rng.uniform(-30, 30, (4, 6)) + [0, 0, 0, 0, 60, 0]])
    pairs = guard.pairwise_violations(nodes)
    for i in range(len(nodes)):
        for j in range(i + 1, len(nodes)):
            assert ((i, j) in pairs) == (guard.path_violation(nodes[i], nodes[j]) is not None)
    assert (0, 1) in pairs


def test_the_samples_of_a_move_are_close_enough():
    a, b, _ = _sweeping_move()
    guard = CellGuard(ROBOT, [], [CAMERA, BRACKET], step_mm=10)
    samples = guard.path_samples(a, b)
    centres = guard.sphere_centres(samples)
    assert np.max(np.linalg.norm(np.diff(centres, axis=0), axis=2)) <= 10.0 + 1e-9


def test_the_tcp_is_held_to_the_world_zones_only():
    stand = Box("stand", (0, 0, 0), (1, 1, 1), ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)))
    cell = CellModel((Floor("floor", 0.0),), (CAMERA,), None)
    joints = np.array([0.0, 10, 10, 0, 60, 0])
    camera_point = ROBOT.forward_transform(joints) @ np.array([-115.0, 30.0, 95.0, 1.0])
    zone = Box("zone", tuple(camera_point[:3] - 5), tuple(camera_point[:3] + 5))
    guard = CellGuard(ROBOT, cell.volumes(), cell.carried, margin_mm=0, tcp_zones=((-115.0, 30.0, 95.0), [zone]))
    violation = guard.posture_violation(joints)
    assert violation is not None and violation.body == "TCP" and violation.volume == "zone"
    assert stand.kind == "box"
