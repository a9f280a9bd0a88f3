import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.calibration import metrics


def test_d_org_and_d_back_on_known_points():
    # one point seen at three positions on a line: 0, 1, 3 (mm)
    fixed = np.array([[[0.0, 0, 0]], [[1.0, 0, 0]], [[3.0, 0, 0]]])
    mean = 4.0 / 3.0
    assert metrics.d_org(fixed) == pytest.approx((mean + abs(1 - mean) + abs(3 - mean)) / 3)
    assert metrics.d_back(fixed) == pytest.approx((1 + 3 + 2) / 3)
    assert np.allclose(metrics.posture_residuals(fixed), [mean, abs(1 - mean), 3 - mean])


def test_d_back_bounds_from_d_org():
    rng = np.random.default_rng(0)
    fixed = rng.normal(size=(15, 4, 3))
    n = 15
    assert n / (n - 1) * metrics.d_org(fixed) <= metrics.d_back(fixed) <= 2 * metrics.d_org(fixed)


def test_rotation_metrics_agree():
    a = Rotation.random(10, random_state=1)
    b = Rotation.random(10, random_state=2)
    geod = metrics.d_geod_matrix(a.as_matrix(), b.as_matrix())
    assert np.allclose(geod, (a.inv() * b).magnitude())
    qa, qb = a.as_quat(scalar_first=True), b.as_quat(scalar_first=True)
    assert np.allclose(metrics.d_geod_quaternion(qa, qb), geod)
    assert np.allclose(metrics.d_geod_quaternion(qa, -qb), geod)  # sign-blind
    assert np.all((metrics.d_1(qa, qb) >= 0) & (metrics.d_1(qa, qb) <= 1))
    assert np.all(metrics.d_2(qa, qb) <= np.sqrt(2) + 1e-12)
    assert np.allclose(metrics.d_frob(a.as_matrix(), b.as_matrix()), 2 * np.sqrt(2) * np.sin(geod / 2))
    assert np.allclose(metrics.d_hyper(a.as_matrix(), a.as_matrix()), 0)


def test_lp_distance():
    assert metrics.lp_distance([0, 0, 0], [3, 4, 0]) == pytest.approx(5.0)
    assert metrics.lp_distance([0, 0, 0], [3, 4, 0], p=1) == pytest.approx(7.0)
    assert metrics.lp_distance([0, 0, 0], [3, -4, 0], p=np.inf) == pytest.approx(4.0)


def test_axxb_residuals_zero_at_truth():
    from helpers import problem

    prob, truth, _ = problem(6)
    pairs = np.array([[0, 1], [2, 5], [3, 4]])
    dr, dt = metrics.axxb_residuals(prob.hand, prob.target2cam, truth["x"], pairs)
    assert np.all(dr < 1e-9) and np.all(dt < 1e-6)
