"""Plans clear of the cell (issue 15): postures and the joint-interpolated moves between them keep the
carried geometry and links 4-6 out of the keep-out volumes; tight cells give fewer postures with the
reasons, or a refusal; the start posture inside a volume is refused."""

from dataclasses import replace

import numpy as np
import pytest

from handeye.robot.cell import Box, CellModel, Cylinder, Floor
from handeye.robot.clearance import Violation
from handeye.geometry.board import BoardGeometry
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.cell.plan import CellCheck, Rejections, clear_route
from handeye.station.config.cell import DEFAULT_CARRIED
from handeye.station.capture.planning import PlanningError, order_for_short_motions, plan_postures
from handeye.station.report.quality import QualityThresholds

from helpers import joint_path

ROBOT = load_robot("IRB1400")
BOARD = BoardGeometry((13, 8), 30.0)
#: The cell of the issue: the floor, the board's stand (from the board pose) and a cabinet beside the board.
CELL = CellModel((Floor("floor", 0.0), Box("cabinet beside the board", (500, 250, 0), (1200, 700, 1400))),
                 DEFAULT_CARRIED, stand_margin_mm=50.0, stand_depth_mm=100.0)
MARGIN, STEP = 30.0, 10.0
#: Two walls that leave a narrow lane around the board (beginning beyond the robot's base and link 1, which
#: the whole-arm check watches: a wall through the robot's own column would refuse every posture).
WALLS = CellModel((Floor("floor", 0.0), Box("left wall", (380, 200, 0), (2000, 1500, 2500)),
                   Box("right wall", (380, -1500, 0), (2000, -250, 2500))), DEFAULT_CARRIED)


def _start_view():
    return invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD


def _plan(cell=None, **options):
    options = {"count": 30, "seed": 1, **options}
    return plan_postures(ROBOT, DEFAULT_START, _start_view(), DEFAULT_MOUNT, BOARD,
                         cell=None if cell is None else CellCheck(cell, MARGIN, STEP), **options)


def _surface_points(box: Box, spacing: float = 20.0) -> np.ndarray:
    """Points on the faces of a box (its own frame = tool0), at most ``spacing`` apart."""
    low, high = np.array(box.min_mm), np.array(box.max_mm)
    axes = [np.linspace(lo, hi, max(2, int(np.ceil((hi - lo) / spacing)) + 1)) for lo, hi in zip(low, high)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    on_face = np.any(np.isclose(grid, low) | np.isclose(grid, high), axis=1)
    return grid[on_face]


def _true_clearance(joints: np.ndarray, volumes) -> np.ndarray:
    """Least distance of the real bodies (the carried boxes' faces, the links' capsules) from the volumes,
    per configuration ``(n, 6)``: computed on the bodies themselves, not on the spheres the check uses."""
    carried = np.concatenate([_surface_points(b) for b in DEFAULT_CARRIED])
    out = np.full(len(joints), np.inf)
    for start in range(0, len(joints), 500):
        chunk = joints[start:start + 500]
        tool = ROBOT.forward_transform(chunk)
        points = np.einsum("nij,mj->nmi", tool[:, :3, :3], carried) + tool[:, None, :3, 3]
        chain = ROBOT.chain_points(chunk)
        t = np.linspace(0, 1, 40)[None, :, None]
        for volume in volumes:
            gap = volume.signed_distance(points).min(axis=1)
            for body in ROBOT.bodies:
                axis = chain[:, None, body.start] + t * (chain[:, None, body.end] - chain[:, None, body.start])
                gap = np.minimum(gap, volume.signed_distance(axis).min(axis=1) - body.radius_mm)
            out[start:start + len(chunk)] = np.minimum(out[start:start + len(chunk)], gap)
    return out



@pytest.fixture(scope="module")
def cell_plan():
    return _plan(CELL)


def test_no_posture_and_no_point_of_any_move_enters_the_cell(cell_plan):
    volumes = CELL.volumes(cell_plan.board2base, BOARD)
    assert [v.name for v in volumes] == ["floor", "cabinet beside the board", "board stand"]  # on the floor: no leg
    assert len(cell_plan.joints_deg) == 30
    assert np.all(_true_clearance(cell_plan.joints_deg, volumes) >= MARGIN)
    path = joint_path(np.vstack([DEFAULT_START, cell_plan.joints_deg]), 0.25)  # the start's move included
    assert np.all(_true_clearance(path, volumes) >= MARGIN - STEP / 2)


def test_the_cell_mattered_and_the_score_says_why(cell_plan):
    score = cell_plan.score
    assert score.rejected_postures > 0 and score.rejections
    assert any("cabinet beside the board" in line for line in score.rejections)
    assert sum(int(line.split()[0]) for line in score.rejections) == score.rejected_postures + score.rejected_moves
    # the same plan without the cell would have taken the arm into it
    plain = _plan()
    volumes = CELL.volumes(plain.board2base, BOARD)
    path = joint_path(np.vstack([DEFAULT_START, plain.joints_deg]), 0.25)
    assert np.min(_true_clearance(path, volumes)) < 0


def test_the_default_cell_leaves_the_demo_plan_as_it_was():
    """The default cell's floor changes nothing: the plan is the one of the self-collision check alone (the
    camera against the arm's own links, issue 21, is what the default cell rejects)."""
    from handeye.station.config.cell import DEFAULT_KEEP_OUT

    with_cell = _plan(CellModel(DEFAULT_KEEP_OUT, DEFAULT_CARRIED), count=12)
    self_only = _plan(CellModel((), DEFAULT_CARRIED), count=12)
    assert np.array_equal(with_cell.joints_deg, self_only.joints_deg)
    assert with_cell.score.rejections == self_only.score.rejections
    assert all(" against " in line for line in with_cell.score.rejections)


def test_a_tight_cell_gives_fewer_postures_and_the_reasons():
    plan = _plan(WALLS, max_attempts=300)
    assert 12 <= len(plan.joints_deg) < 30
    assert any(note.startswith(f"only {len(plan.joints_deg)} of 30 postures keep clear of the cell") for note in plan.notes)
    assert any("left wall" in line for line in plan.score.rejections)
    assert any("right wall" in line for line in plan.score.rejections)


def test_a_cell_too_tight_for_the_verdict_is_refused_with_the_reasons():
    with pytest.raises(PlanningError, match=r"fewer than the 29 the verdict needs \(min_inlier_postures\): \d+ postures "
                                            r"and \d+ moves rejected \(.*wall"):
        _plan(WALLS, max_attempts=300, thresholds=QualityThresholds(min_inlier_postures=29))


@pytest.mark.parametrize("cell, words", [
    (CellModel((Cylinder("pillar", (500, 150), 80, (0, 2000)),), DEFAULT_CARRIED), "mm inside 'pillar': jog the robot out"),
    (CellModel((Box("wall", (450, 150, 0), (2000, 1500, 2500)),), DEFAULT_CARRIED), r"mm from 'wall', within the margin"),
])
def test_a_start_posture_in_or_near_a_volume_is_refused(cell, words):
    with pytest.raises(PlanningError, match=f"at the start posture, .*{words}"):
        _plan(cell, count=5)


class _WallAtAxis1:
    """A guard whose only obstacle is a wall at axis 1 = 0: a move crossing it is blocked."""

    margin_mm = 30.0

    def __init__(self):
        self.checked = 0

    def moves_violations(self, moves):
        self.checked += len(moves)
        return [Violation("camera", "wall", -5.0, 0.5) if np.sign(a[0]) != np.sign(b[0]) else None for a, b in moves]


def _joints(axis1):
    return np.array([[a, 0, 0, 0, 60, 0] for a in axis1], float)


def test_postures_behind_a_blocked_move_are_replaced_then_dropped():
    start = np.array([-10.0, 0, 0, 0, 60, 0])
    fresh = iter([_joints([-35, -45]), _joints([]), _joints([]), _joints([]), _joints([])])
    rejections = Rejections()
    route = clear_route(ROBOT, _WallAtAxis1(), start, _joints([-20, 30, -30, 40]), lambda m: next(fresh), rejections,
                        order_for_short_motions)
    assert np.all(route[:, 0] < 0) and len(route) == 4  # the two across the wall replaced by two on this side
    assert rejections.moves == {"camera inside 'wall'": 2}
    nothing = iter([_joints([])] * 10)
    route = clear_route(ROBOT, _WallAtAxis1(), start, _joints([-20, 30, 40]), lambda m: next(nothing), Rejections(),
                        order_for_short_motions)
    assert route[:, 0].tolist() == [-20.0]


def test_the_order_avoids_a_blocked_move_when_it_can():
    start = np.zeros(6)
    joints = _joints([10, 20, 30])
    blocked = np.zeros((4, 4), bool)
    blocked[1, 2] = blocked[2, 1] = True  # 10 <-> 20 blocked: go 10, 30, 20 or 20, 30, 10
    order = order_for_short_motions(ROBOT, joints, start, blocked)
    route = [0] + [int(i) + 1 for i in order]
    assert not any(blocked[a, b] for a, b in zip(route[:-1], route[1:]))
    assert list(order_for_short_motions(ROBOT, joints, start)) == [0, 1, 2]


def test_the_plan_record_keeps_the_reasons(cell_plan):
    record = cell_plan.score.to_dict()
    assert record["rejected_postures"] == cell_plan.score.rejected_postures
    assert record["rejections"] == list(cell_plan.score.rejections)
    assert isinstance(record["rotation_axis_spread_deg"], float)
    assert replace(cell_plan.score, rejections=()).to_dict()["rejections"] == []


def test_with_world_zones_the_camera_tcp_keeps_clear_of_the_zones_as_the_controller_sees_them():
    check = CellCheck(CELL, MARGIN, STEP, zone_tcp_mm=(-115.0, 30.0, 95.0))
    guard = check.guard(ROBOT, DEFAULT_BOARD, BOARD)
    assert guard.bodies.count("TCP") == 1
    zones = guard.volumes[len(CELL.volumes(DEFAULT_BOARD, BOARD)):]
    assert [z.name for z in zones] == ["floor", "cabinet beside the board", "board stand"]
    assert zones[2].box2parent is None  # the stand as its bounding box in base, as WZBoxDef declares it
    stand = CELL.volumes(DEFAULT_BOARD, BOARD)[2]
    assert np.all(zones[2].signed_distance(stand.corners()) <= 1e-6)
