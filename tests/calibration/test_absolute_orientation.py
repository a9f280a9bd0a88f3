import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.absolute_orientation import absolute_orientation, rotation_between_vectors
from handeye.geometry.rotations import matrix_from_quaternion


def test_matches_scipy_align_vectors_with_noise():
    rng = np.random.default_rng(4)
    source = rng.normal(size=(10, 3))
    truth = Rotation.random(random_state=5)
    target = truth.apply(source) + 0.05 * rng.normal(size=source.shape)
    ours = rotation_between_vectors(source, target)
    ref, _ = Rotation.align_vectors(target, source)
    assert np.allclose(matrix_from_quaternion(ours.quaternion), ref.as_matrix(), atol=1e-10)


def test_exact_rigid_motion_recovered_eq29():
    rng = np.random.default_rng(1)
    source = rng.normal(size=(3, 3)) * 100
    truth = Rotation.random(random_state=2)
    t = np.array([10.0, -20.0, 30.0])
    target = truth.apply(source) + t
    fit = absolute_orientation(source, target)
    assert np.allclose(matrix_from_quaternion(fit.quaternion), truth.as_matrix(), atol=1e-12)
    assert np.allclose(fit.translation, t, atol=1e-9)
    assert fit.rms_residual < 1e-9


def test_batched_equals_loop():
    rng = np.random.default_rng(7)
    source = rng.normal(size=(20, 3, 3))
    target = rng.normal(size=(20, 3, 3))
    batch = absolute_orientation(source, target)
    for i in range(20):
        single = absolute_orientation(source[i], target[i])
        assert np.allclose(batch.quaternion[i], single.quaternion, atol=1e-12)
        assert np.allclose(batch.translation[i], single.translation, atol=1e-9)


def test_parallel_vectors_have_no_eigen_gap():
    v = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [-1.0, -2.0, -3.0]])
    assert rotation_between_vectors(v, v).eigen_gap < 1e-9
    w = np.eye(3)
    assert rotation_between_vectors(w, w).eigen_gap > 0.1
