"""The recommended default on data measured on real robots (../shared/datasets), against OpenCV.

Every method is scored the same way: d_org (eq. 22) of the same three target-frame points over all
postures of the set, so the comparison does not depend on what each method minimises.
"""

import numpy as np
import pytest

from handeye.calibration.metrics import d_org, fixed_points
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.station.opencv_reference import OPENCV_METHODS, solve_opencv
from handeye.station.importers import read_any

from helpers import shared_dataset

cv2 = pytest.importorskip("cv2")
if not hasattr(cv2, "calibrateHandEye"):  # pragma: no cover
    pytest.skip("this OpenCV build has no calibrateHandEye (5.0 wheels)", allow_module_level=True)



FILES = {"moveit-calibration": "pose_samples.json", "camodocal-ar-tag": "TransformPairsInput.yml", "visp-eye-in-hand": ""}


def _problem(name):
    folder = shared_dataset(name)
    return problem_from_session(read_any(folder / FILES[name] if FILES[name] else folder))


def _score(problem, x):
    return d_org(fixed_points(problem.hand, x, problem.compact.points))


def _best_opencv(problem):
    scores = []
    for name in OPENCV_METHODS:
        x = solve_opencv(problem.hand, problem.target2cam, name)
        if np.all(np.isfinite(x)):
            scores.append(_score(problem, x))
    return min(scores)


# The robust pipeline (the default until the maximum-likelihood estimator) minimises the point
# consistency these tests score; its assertions stay, under its name. The ML default weighs the
# rotations as their noise says and is checked below for what it does: d_org within 1 % of the best
# OpenCV method, the AX = XB rotation residual within 1.2 x the best classic, and the best or
# within 1 % of the best held-out (5-fold) prediction (benchmarks/real_data/README.md).


@pytest.mark.parametrize("name", ["moveit-calibration", "visp-eye-in-hand"])
def test_robust_at_least_as_consistent_as_opencv(name):
    problem = _problem(name)
    result = calibrate(problem, "robust")
    assert _score(problem, result.x) <= _best_opencv(problem)


def _rotation_residual_deg(problem, x):
    from handeye.geometry.transforms import invert_transforms

    i, j = np.triu_indices(problem.n, 1)
    a = invert_transforms(problem.hand[i]) @ problem.hand[j]
    b = problem.target2cam[i] @ invert_transforms(problem.target2cam[j])
    m = np.swapaxes(a[:, :3, :3] @ x[:3, :3], 1, 2) @ (x[:3, :3] @ b[:, :3, :3])
    return float(np.sqrt(np.mean(np.degrees(np.arccos(np.clip((np.trace(m, axis1=1, axis2=2) - 1) / 2, -1, 1))) ** 2)))


@pytest.mark.parametrize("name", ["moveit-calibration", "visp-eye-in-hand"])
def test_default_balances_point_consistency_and_the_rotation_residual(name):
    from handeye.calibration.classic import CLASSIC_METHODS
    from handeye.calibration.crossval import cross_validate

    problem = _problem(name)
    result = calibrate(problem)
    assert result.method == "ml"
    assert _score(problem, result.x) <= 1.01 * _best_opencv(problem)
    classic = {m: calibrate(problem, m).x for m in CLASSIC_METHODS if m != "andreff"}
    assert _rotation_residual_deg(problem, result.x) <= 1.2 * min(_rotation_residual_deg(problem, x) for x in classic.values())
    if name == "moveit-calibration":  # 50 postures: a held-out figure worth comparing (8 postures is noise)
        ml = cross_validate(problem, lambda p: calibrate(p).x).mean_mm
        others = [cross_validate(problem, lambda p, m=m: calibrate(p, m).x).mean_mm for m in ("robust", "mcb", "park", "daniilidis", "lu")]
        assert ml <= 1.01 * min(others)


def test_camodocal_outliers_found_and_default_beats_opencv():
    problem = _problem("camodocal-ar-tag")
    for method in ("robust", None):
        result = calibrate(problem, method)
        assert {21, 36} <= set(result.outliers)
        assert len(result.outliers) <= 4
        assert _score(problem, result.x) <= 0.8 * _best_opencv(problem)


def test_visp_reference_is_close():
    """ViSP's published eMc is another tool's estimate, not truth: we stay within a few mm / a degree."""
    from scipy.spatial.transform import Rotation

    problem = _problem("visp-eye-in-hand")
    x = calibrate(problem).x
    reference_t = np.array([0.05346, -0.00952, -0.04510]) * 1000
    reference_r = Rotation.from_rotvec([-0.02347, -0.07939, 1.57459])
    assert np.linalg.norm(x[:3, 3] - reference_t) < 10.0
    assert (Rotation.from_matrix(x[:3, :3]) * reference_r.inv()).magnitude() < np.radians(2.0)
