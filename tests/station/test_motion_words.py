"""The plan, guided capture and the verdict make the same motion check, under the same names.

Before, the rotation-axis spread and the median relative rotation angle were checked in three
places (``quality.py``, ``planning.py``, ``guided.py``) with three labels each ("small rotations
between postures", "median relative rotation angle between two postures", "relative rotation angle
(median)"). Now one function decides, and the names come from ``calibration.quality_words``.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.calibration.quality_words import AXIS_SPREAD_NAME, MEDIAN_ANGLE_NAME, hand_axis_coverage
from handeye.station.guided import capture as guided
from handeye.station.capture.planning import PlanScore
from handeye.station.report.quality import CHECK_LABELS, QualityThresholds, meets, motion_shortfalls

THRESHOLDS = QualityThresholds()


def _flange_poses(rotvecs_deg) -> np.ndarray:
    poses = np.tile(np.eye(4), (len(rotvecs_deg), 1, 1))
    poses[:, :3, :3] = Rotation.from_rotvec(np.radians(rotvecs_deg)).as_matrix()
    poses[:, :3, 3] = np.arange(len(rotvecs_deg))[:, None] * [100.0, 0.0, 0.0] + [900.0, 0.0, 800.0]
    return poses


#: Flange poses turning about z only (no axis spread) by small angles (a small median angle).
NARROW = _flange_poses([[0, 0, 0], [0, 0, 5], [0, 0, 10], [0, 0, 6], [0, 0, 2]])
#: Flange poses turning about every direction by 30-40 deg.
WIDE = _flange_poses([[0, 0, 0], [35, 0, 0], [0, 35, 0], [0, 0, 35], [-30, 20, 0], [0, -25, 30]])


@pytest.mark.parametrize("poses, expected", [(NARROW, [AXIS_SPREAD_NAME, MEDIAN_ANGLE_NAME]), (WIDE, [])])
def test_the_three_places_find_the_same_shortfalls_under_the_same_names(poses, expected):
    coverage = hand_axis_coverage(poses, "tool0")
    found = [s.word for s in motion_shortfalls(coverage, THRESHOLDS)]
    assert found == expected
    plan = PlanScore(coverage.spread_deg, coverage.min_angle_deg, coverage.median_angle_deg, 0.0, 0.0, 0.0)
    plan_words = [line.split(" deg")[0].rsplit(" ", 1)[0] for line in plan.verdict(THRESHOLDS)]
    assert plan_words == expected
    guided_words = [m.word for m in guided._rotation_missing(poses, THRESHOLDS)]  # noqa: SLF001
    assert guided_words == expected
    labels = [CHECK_LABELS[s.key][0] for s in motion_shortfalls(coverage, THRESHOLDS)]
    assert labels == expected


def test_the_rule_is_at_least_a_min_threshold_and_at_most_a_max_one():
    assert meets("min_median_rotation_deg", 15.0, 15.0) and not meets("min_median_rotation_deg", 14.9, 15.0)
    assert meets("max_d_org_mm", 1.0, 1.0) and not meets("max_d_org_mm", 1.1, 1.0)
    edge = SimpleNamespace(spread_deg=THRESHOLDS.min_rotation_axis_spread_deg,
                           median_angle_deg=THRESHOLDS.min_median_rotation_deg - 1e-9)
    assert [s.key for s in motion_shortfalls(edge, THRESHOLDS)] == ["min_median_rotation_deg"]
