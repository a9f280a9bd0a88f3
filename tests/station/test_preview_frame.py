"""The plan preview frames the robot, the board and the postures (issue 25, finding 7d): a huge keep-out
volume is clipped to that view instead of shrinking the postures to a dot cluster."""

import numpy as np
import pytest

from handeye.robot.cell import Box, CellModel, Cylinder, Floor
from handeye.geometry.board import BoardGeometry
from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import invert_transforms
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.cell.plan import CellCheck
from handeye.station.config.cell import DEFAULT_CARRIED
from handeye.station.capture.planning import plan_postures
from handeye.station.cell.preview import plan_preview_figure

ROBOT = load_robot("IRB1400")
BOARD = BoardGeometry((13, 8), 30.0)
CABINET = Box("cabinet", (500, 250, 0), (1200, 700, 1400))


def _plan(*volumes):
    view = invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    return plan_postures(ROBOT, DEFAULT_START, view, DEFAULT_MOUNT, BOARD, count=12, seed=1,
                         cell=CellCheck(CellModel((Floor("floor", -10000.0), CABINET) + volumes, DEFAULT_CARRIED)))


def _limits(plan):
    fig = plan_preview_figure(ROBOT, plan)
    return [(ax.get_xlim(), ax.get_ylim()) for ax in fig.axes]


def _scene(plan) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the base, the board's centre, the flange at the start and at every posture."""
    flanges = ROBOT.forward_transform(np.vstack([plan.start_joints_deg[None], plan.joints_deg]))[:, :3, 3]
    points = np.vstack([flanges, plan.board2base[:3, 3], [0.0, 0.0, 0.0]])
    return points.min(axis=0), points.max(axis=0)


@pytest.fixture(scope="module")
def plans():
    hall = Box("hall wall", (2500.0, -20000.0, -5000.0), (30000.0, 20000.0, 15000.0))
    column = Cylinder("far column", (-15000.0, 9000.0), 500.0, (-3000.0, 9000.0))
    return _plan(), _plan(hall, column)


def test_huge_volumes_do_not_widen_the_view(plans):
    plain, huge = plans
    for (hx, hy), (px, py) in zip(_limits(huge), _limits(plain)):
        assert hx[1] - hx[0] < 1.5 * (px[1] - px[0]) + 1e-9 and hy[1] - hy[0] < 1.5 * (py[1] - py[0]) + 1e-9


def test_the_view_frames_the_robot_the_board_and_the_postures(plans):
    for plan in plans:
        low, high = _scene(plan)
        for (x, y), (h, v) in zip(_limits(plan), ((0, 1), (0, 2))):
            # aspect "equal" with adjustable "box" keeps the limits as computed: every point inside, a border
            assert x[0] <= low[h] - 100 and x[1] >= high[h] + 100 and y[0] <= low[v] - 100 and y[1] >= high[v] + 100
            # and no more than the flange path, the clipped volumes' reach (300 mm) and the border (150 mm) beyond
            assert x[0] >= low[h] - 800 and x[1] <= high[h] + 800 and y[0] >= low[v] - 800 and y[1] <= high[v] + 800
