import numpy as np
import pytest

from handeye.robot.kinematics import dh_transforms, inverse_kinematics, known_robots, load_robot


@pytest.fixture(scope="module")
def robot():
    return load_robot("IRB1400")


def test_home_pose_from_reference(robot):
    p, q = robot.forward(np.zeros(6))
    assert np.allclose(p, [955.0, 0.0, 1195.0], atol=1e-9)
    assert np.allclose(q, [np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0], atol=1e-12)


def test_quaternion_chain_matches_dh_product(robot):
    rng = np.random.default_rng(0)
    joints = rng.uniform(robot.joint_limits_deg[:, 0], robot.joint_limits_deg[:, 1], size=(20, 6))
    chain = robot.forward_transform(joints)
    theta = robot.serial_angles_rad(joints) + np.radians(robot.dh[:, 3])
    for k in range(20):
        m = np.eye(4)
        for link in dh_transforms(robot.dh, theta[k]):
            m = m @ link
        assert np.allclose(chain[k], m, atol=1e-9)


def test_parallel_arm_coupling(robot):
    # Moving controller axis 2 alone keeps the forearm's absolute orientation: the wrist rises/moves
    # with the upper arm but the flange orientation does not change.
    _, q0 = robot.forward([0, 0, 0, 0, 0, 0])
    _, q1 = robot.forward([0, 30, 0, 0, 0, 0])
    assert np.allclose(np.abs(q0 @ q1), 1.0, atol=1e-12)
    # Without the coupling the flange would be ~160 mm elsewhere at axis 2 = 30, axis 3 = 0 (reference).
    theta = np.radians([0, 30, 0, 0, 0, 0]) + np.radians(robot.dh[:, 3])
    m = np.eye(4)
    for link in dh_transforms(robot.dh, theta):
        m = m @ link
    p, _ = robot.forward([0, 30, 0, 0, 0, 0])
    assert np.linalg.norm(m[:3, 3] - p) > 100.0


def test_batched_forward_equals_loop(robot):
    joints = np.random.default_rng(2).uniform(-40, 40, size=(3, 4, 6))
    p, q = robot.forward(joints)
    assert p.shape == (3, 4, 3) and q.shape == (3, 4, 4)
    assert np.allclose(p[1, 2], robot.forward(joints[1, 2])[0])


def test_limits(robot):
    assert robot.within_limits([0, 0, 0, 0, 0, 0])
    assert not robot.within_limits([0, 75, 0, 0, 0, 0])
    assert "axis 2" in robot.limit_violations([0, 75, 0, 0, 0, 0])[0]


def test_inverse_kinematics_round_trip(robot):
    target_joints = np.array([10.0, 20.0, 15.0, 30.0, 50.0, -40.0])
    target = robot.forward_transform(target_joints)
    ik = inverse_kinematics(robot, target, target_joints + 5.0)
    assert ik.success
    assert np.allclose(robot.forward_transform(ik.joints_deg), target, atol=1e-6)


def test_load_by_alias_and_path(tmp_path):
    assert "IRB1400" in known_robots()
    assert load_robot("irb 1410").name == "IRB1400"
    custom = tmp_path / "two_link.yaml"
    custom.write_text("name: TWO\ndh: [[0, 100, 0, 0], [0, 50, 0, 0]]\n")
    two = load_robot(str(custom))
    p, _ = two.forward([0.0, 90.0])
    assert np.allclose(p, [100.0, 50.0, 0.0], atol=1e-9)
    with pytest.raises(ValueError, match="unknown robot"):
        load_robot("KR16")


def test_may_reach(robot):
    rng = np.random.default_rng(5)
    joints = rng.uniform(robot.joint_limits_deg[:, 0], robot.joint_limits_deg[:, 1], size=(200, 6))
    positions, _ = robot.forward(joints)
    assert all(robot.may_reach(p) for p in positions)  # never refuses a reachable point
    assert not robot.may_reach([3000.0, 0.0, 500.0]) and not robot.may_reach([0.0, 0.0, 3500.0])
