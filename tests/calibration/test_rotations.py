import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.geometry import rotations as rot


@pytest.fixture
def quats():
    return Rotation.random(50, random_state=3).as_quat(scalar_first=True)


def test_multiply_matches_scipy_composition(quats):
    p, q = quats[:25], quats[25:]
    expected = (Rotation.from_quat(p, scalar_first=True) * Rotation.from_quat(q, scalar_first=True)).as_matrix()
    assert np.allclose(rot.matrix_from_quaternion(rot.quaternion_multiply(p, q)), expected, atol=1e-12)


def test_rotate_vectors_is_q_p_qbar(quats):
    v = np.random.default_rng(0).normal(size=(50, 3))
    pure = np.concatenate([np.zeros((50, 1)), v], axis=1)
    sandwich = rot.quaternion_multiply(rot.quaternion_multiply(quats, pure), rot.quaternion_conjugate(quats))
    assert np.allclose(rot.rotate_vectors(quats, v), sandwich[:, 1:], atol=1e-12)
    assert np.allclose(sandwich[:, 0], 0, atol=1e-12)


def test_matrix_round_trip_and_sign(quats):
    back = rot.quaternion_from_matrix(rot.matrix_from_quaternion(quats))
    assert np.all(back[:, 0] >= 0)
    assert np.allclose(np.abs(np.sum(back * quats, axis=1)), 1.0, atol=1e-12)


def test_axis_angle_eq9_round_trip():
    axis = np.array([[1.0, 2.0, -2.0], [0.0, 0.0, 5.0]])
    angle = np.array([0.7, 2.5])
    q = rot.quaternion_from_axis_angle(axis, angle)
    expected = Rotation.from_rotvec(axis / np.linalg.norm(axis, axis=1, keepdims=True) * angle[:, None])
    assert np.allclose(rot.matrix_from_quaternion(q), expected.as_matrix(), atol=1e-12)
    got_axis, got_angle = rot.axis_angle_from_quaternion(q)
    assert np.allclose(got_angle, angle)
    assert np.allclose(got_axis, axis / np.linalg.norm(axis, axis=1, keepdims=True))
    assert np.allclose(rot.rotation_angle(q), angle)


def test_batched_shapes_broadcast():
    q = Rotation.random(6, random_state=1).as_quat(scalar_first=True).reshape(2, 3, 4)
    v = np.ones((2, 3, 3))
    out = rot.rotate_vectors(q, v)
    loop = np.array([[rot.rotate_vectors(q[i, j], v[i, j]) for j in range(3)] for i in range(2)])
    assert out.shape == (2, 3, 3)
    assert np.allclose(out, loop)


@pytest.mark.parametrize("bad, message", [
    ([1.0, 0.0, 0.0], "4 values"),
    ([1.0, 0.1, 0.0, 0.0], "not unit"),
    ([np.nan, 0.0, 0.0, 1.0], "NaN"),
])
def test_check_quaternions_rejects(bad, message):
    with pytest.raises(ValueError, match=message):
        rot.check_quaternions(bad)


def test_check_quaternions_renormalises_within_tolerance():
    q = rot.check_quaternions([1.0 + 1e-5, 0.0, 0.0, 0.0])
    assert np.isclose(np.linalg.norm(q), 1.0)
