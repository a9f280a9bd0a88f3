"""The mock arm's kinematic truth from the station file (``mock.arm``)."""

import numpy as np
import pytest

from handeye.base.errors import ConfigError
from handeye.robot.kinematics import load_robot
from handeye.mocks.arm_truth import ArmDeviations, true_arm
from handeye.mocks.station import MockStationSpec, flange_camera
from handeye.station.config.station import config_from_dict
from handeye.station.runtime import mock_spec


def _config(arm):
    return config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"},
                             "mock": {"arm": arm}}, "test")


def test_explicit_joint_zeros_move_the_flange_as_turned_axes():
    nominal = load_robot("IRB1400")
    zero = (0.0, 0.05, -0.03, 0.04, -0.05, 0.0)
    arm = true_arm(nominal, ArmDeviations(zero))
    joints = np.array([10.0, 20.0, -15.0, 30.0, 40.0, 50.0])
    # the true arm at the controller angle is the nominal arm at controller angle + offset
    np.testing.assert_allclose(arm.forward_transform(joints), nominal.forward_transform(joints + np.array(zero)),
                               atol=1e-9)


def test_station_file_arm_reaches_the_mock_truth():
    config = _config({"joint_zero_deg": [0, 0.05, -0.03, 0.04, -0.05, 0], "link_mm": {"a2": 0.3, "d4": -0.2}})
    spec = mock_spec(config)
    assert spec.arm.joint_zero_deg[1] == pytest.approx(0.05)

    class Arm:
        current_joints = np.zeros(6)

    camera, truth = flange_camera(spec, Arm())
    camera.close()
    delta = truth["dh_deviation"]
    assert delta[1, 1] == pytest.approx(0.3) and delta[3, 0] == pytest.approx(-0.2)
    assert delta[2, 3] == pytest.approx(-0.08)  # serial axis 3 = controller 3 - controller 2
    assert np.count_nonzero(delta) == 6  # nothing random on top


def test_without_arm_the_errors_stay_random():
    config = config_from_dict({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}, "test")
    spec = mock_spec(config)
    assert spec.arm is None
    camera, truth = flange_camera(spec, type("A", (), {"current_joints": np.zeros(6)})())
    camera.close()
    assert np.count_nonzero(truth["dh_deviation"]) > 12


@pytest.mark.parametrize("arm, words", [({"link_mm": {"b2": 1.0}}, "not a DH length"),
                                        ({"joint_zero_deg": [0, 1]}, "joint_zero_deg"),
                                        ({"link_mm": [1, 2]}, "mapping")])
def test_bad_arm_is_one_line(arm, words):
    with pytest.raises(ConfigError, match=words):
        _config(arm)


def test_standalone_mock_controller_takes_the_arm():
    from handeye.mocks.controller.service import MockControllerOptions, _cell_spec

    arm = ArmDeviations((0.0, 0.05, 0.0, 0.0, 0.0, 0.0), {"a2": 0.1})
    assert _cell_spec(MockControllerOptions(arm=arm)).arm is arm
    assert _cell_spec(MockControllerOptions()).arm is None
