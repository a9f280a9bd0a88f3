import numpy as np
import pytest

from handeye.geometry.board import BoardGeometry, board_corners
from handeye.robot.kinematics import load_robot
from handeye.calibration.quality_words import MAX_AXIS_SPREAD_DEG
from handeye.geometry.transforms import invert_transforms
from handeye.robot.views import NOMINAL_XB3, ViewSampling, board_visible
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.capture.planning import PlanningError, motion_time_s, order_for_short_motions, plan_postures

ROBOT = load_robot("IRB1400")
BOARD = BoardGeometry((13, 8), 30.0)


def _start_view():
    return invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD


@pytest.fixture(scope="module")
def plan():
    return plan_postures(ROBOT, DEFAULT_START, _start_view(), DEFAULT_MOUNT, BOARD, count=12, seed=3)


def test_postures_are_reachable_with_margin_and_see_the_board(plan):
    assert plan.joints_deg.shape == (12, 6)
    assert np.all(ROBOT.within_limits(plan.joints_deg, margin_deg=5.0 - 1e-6))
    corners = board_corners(BOARD.corners, BOARD.square_mm)
    for joints in plan.joints_deg:
        target2cam = invert_transforms(ROBOT.forward_transform(joints) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
        assert board_visible(target2cam, corners, NOMINAL_XB3)  # both cameras of the head
    assert np.allclose(plan.board2base, DEFAULT_BOARD, atol=1e-6)  # estimated from the start view


def test_plan_is_scored(plan):
    s = plan.score
    assert 0 < s.rotation_axis_spread_deg <= MAX_AXIS_SPREAD_DEG and s.median_pair_angle_deg > 15
    assert 0 < s.predicted_sigma_mm < 2 and 0 < s.predicted_sigma_deg < 0.2
    assert s.motion_time_s > 0 and plan.notes == []


def test_order_is_shorter_than_the_drawn_order():
    rng = np.random.default_rng(1)
    joints = rng.uniform(-40, 40, size=(15, 6))
    start = np.zeros(6)

    def length(order):
        nodes = np.vstack([start, joints[order]])
        return motion_time_s(ROBOT, nodes[:-1], nodes[1:]).sum()

    order = order_for_short_motions(ROBOT, joints, start)
    assert sorted(order) == list(range(15))
    assert length(order) < 0.8 * length(np.arange(15))


def test_impossible_geometry_is_reported():
    far = _start_view()
    with pytest.raises(PlanningError, match="postures found"):
        plan_postures(ROBOT, DEFAULT_START, far, DEFAULT_MOUNT, BOARD, count=5, seed=1,
                      sampling=ViewSampling(distance_mm=(3000.0, 3200.0)), max_attempts=20)
