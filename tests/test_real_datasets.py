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


@pytest.mark.parametrize("name", ["moveit-calibration", "visp-eye-in-hand"])
def test_default_at_least_as_consistent_as_opencv(name):
    problem = _problem(name)
    result = calibrate(problem)
    assert _score(problem, result.x) <= _best_opencv(problem)


def test_camodocal_outliers_found_and_default_beats_opencv():
    problem = _problem("camodocal-ar-tag")
    result = calibrate(problem)
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
