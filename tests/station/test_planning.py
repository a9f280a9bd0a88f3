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


def _plan_of(board, seed=3, count=12, cone=15.0):
    return plan_postures(ROBOT, DEFAULT_START, _start_view(), DEFAULT_MOUNT, board, count=count, seed=seed,
                         sampling=ViewSampling(cone_deg=cone, roll_deg=40.0))


def _spread(joints):
    from handeye.calibration.quality_words import hand_axis_coverage

    return hand_axis_coverage(ROBOT.forward_transform(joints), "tool0").spread_deg


def test_a_charuco_plan_takes_partial_views_where_they_widen_the_rotation_spread():
    """Issue 37: a narrow cone leaves the rotations in nearly one plane; views aimed off the board centre
    (part of the ChArUco board out of view) lift the spread; each such posture is said in the plan line,
    sees enough of the board to fix its pose, and the checkerboard plan of the same seed stays whole."""
    from handeye.geometry.targets import STATION_CHARUCO, view_refusal
    from handeye.robot.views import corners_in_view
    from handeye.station.capture.partial_plan import MAX_PARTIAL_SHARE, MIN_IN_VIEW

    whole = _plan_of(BOARD)
    charuco = _plan_of(STATION_CHARUCO)
    assert whole.partial == [] and charuco.partial
    assert len(charuco.partial) <= MAX_PARTIAL_SHARE * 12
    assert charuco.score.rotation_axis_spread_deg > whole.score.rotation_axis_spread_deg + 3.0
    assert charuco.score.rotation_axis_spread_deg == pytest.approx(_spread(charuco.joints_deg))
    corners = board_corners(BOARD.corners, BOARD.square_mm)
    numbers = {p.number for p in charuco.partial}
    for k, joints in enumerate(charuco.joints_deg):
        target2cam = invert_transforms(ROBOT.forward_transform(joints) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
        seen = corners_in_view(target2cam, corners, NOMINAL_XB3)
        if k in numbers:  # partly out of view, yet enough corners with the span to fix the pose
            assert MIN_IN_VIEW <= seen.mean() < 1.0 and view_refusal(np.flatnonzero(seen), STATION_CHARUCO) == ""
        else:
            assert seen.all()
    previous = whole.score.rotation_axis_spread_deg
    for p in charuco.partial:  # swapped in one after the other, each widening the spread
        assert p.spread_after_deg > p.spread_before_deg == pytest.approx(previous, abs=1e-6)
        previous = p.spread_after_deg
        line = p.line()
        assert line.startswith(f"posture {p.number}: board ") and "% in view (ChArUco), widens the rotation spread from" in line
        assert f"{100 * p.in_view:.0f} % in view" in line


def test_a_checkerboard_is_never_planned_partly_out_of_view_nor_a_charuco_board_when_turned_off():
    from handeye.geometry.targets import STATION_CHARUCO, STATION_CIRCLES
    from handeye.station.capture.partial_plan import widen_with_partial_views

    whole = _plan_of(BOARD)
    corners = board_corners(BOARD.corners, BOARD.square_mm)
    for board in (BOARD, STATION_CIRCLES):  # the grids must be seen whole: nothing is swapped
        joints, partial = widen_with_partial_views(ROBOT, whole.joints_deg, DEFAULT_MOUNT, DEFAULT_BOARD, board, corners,
                                                   np.random.default_rng(1), ViewSampling(cone_deg=15.0), NOMINAL_XB3,
                                                   DEFAULT_START)
        assert partial == [] and np.array_equal(joints, whole.joints_deg)
    off = plan_postures(ROBOT, DEFAULT_START, _start_view(), DEFAULT_MOUNT, STATION_CHARUCO, count=12, seed=3,
                        sampling=ViewSampling(cone_deg=15.0, roll_deg=40.0), partial_views=False)
    assert off.partial == [] and np.allclose(off.joints_deg, whole.joints_deg)
