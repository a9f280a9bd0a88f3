"""The arm's kinematic identification against a known truth (synthetic sessions of a deviated arm)."""

from pathlib import Path

import numpy as np
import pytest

from handeye.calibration.arm_identification import identify_arm
from handeye.calibration.arm_parameters import corrected_robot, parameter_names
from handeye.calibration.arm_synthetic import deviated_session, random_deviation
from handeye.calibration.noise import twist_between
from handeye.calibration.solve import problem_from_session
from handeye.calibration.standoff import measured_standoff, predicted_standoff
from handeye.calibration.synthetic import SceneConfig, make_scene
from handeye.station.kinematics_step import kinematics_json, kinematics_lines

NAMES = parameter_names()


@pytest.fixture(scope="module")
def scene():
    return make_scene(SceneConfig(postures=30, seed=3))


def _identify(scene, deviation, seed=5):
    return identify_arm(problem_from_session(deviated_session(scene, deviation, seed=seed)))


@pytest.mark.parametrize("seed", [11, 12])
def test_injected_joint_zeros_are_recovered_within_three_sigma(scene, seed):
    deviation = random_deviation(np.random.default_rng(seed))
    ident = _identify(scene, deviation, seed)
    for axis in (2, 3, 4, 5):
        j = NAMES.index(f"zero{axis}")
        assert ident.status[j] == "identified"
        assert abs(ident.values[j] - deviation[j]) < 3.0 * ident.sigma[j], NAMES[j]
        assert ident.sigma[j] < 0.02  # the data see a zero far better than the 0.1 deg prior
    for j in np.flatnonzero([s == "identified" for s in ident.status]):
        assert abs(ident.values[j] - deviation[j]) < 4.0 * ident.sigma[j], NAMES[j]


@pytest.mark.parametrize("seed", [3, 4, 5, 6])
def test_exact_arm_offsets_consistent_with_zero_and_camera_unchanged(seed):
    """An exact arm (no deviations), several plans and noise draws: the offsets are consistent with zero
    (chi-square over the identified ones) and the camera pose moves by less than its one-sigma."""
    ident = _identify(make_scene(SceneConfig(postures=30, seed=seed)), np.zeros(len(NAMES)), seed + 100)
    identified = np.array([s == "identified" for s in ident.status])
    z = ident.values[identified] / ident.sigma[identified]
    assert np.all(np.abs(z) < 3.5) and np.sqrt(np.mean(z ** 2)) < 1.6
    entry = kinematics_json(ident)
    test = entry["consistent_with_zero"]
    assert test["consistent"] and test["statistic"] <= test["limit"] and test["parameters"] == identified.sum()
    assert test["statement"].startswith("consistent with zero: chi-square")
    assert any(line.strip().startswith("offsets consistent with zero") for line in kinematics_lines(ident))
    change = twist_between(ident.camera_only.fit.x, ident.x)
    sigma = np.sqrt(np.diag(ident.covariance)[:6])
    # the two estimates differ by noise only, by less than the pose's one-sigma (RMS over the six
    # components) and within its uncertainty (Mahalanobis, chi-square with 6 degrees of freedom, 1 %)
    assert np.sqrt(np.mean((change / sigma) ** 2)) < 1.0
    assert entry["camera_pose_change"]["rms_in_sigmas"] == pytest.approx(np.sqrt(np.mean((change / sigma) ** 2)))
    distance = change @ np.linalg.solve(ident.covariance[:6, :6], change)
    assert distance < 16.8 and entry["camera_pose_change"]["within_uncertainty"]


def test_a_deviated_arm_is_not_consistent_with_zero(scene):
    ident = _identify(scene, random_deviation(np.random.default_rng(7)))
    assert not kinematics_json(ident)["consistent_with_zero"]["consistent"]


def test_the_always_hidden_ones_are_named_with_why(scene):
    ident = _identify(scene, random_deviation(np.random.default_rng(1)))
    status = dict(zip(NAMES, ident.status))
    for name in ("zero1", "d1", "zero6", "d6", "a6", "alpha6"):
        assert status[name] == "absorbed", name
    assert status["d3"] == "degenerate" and "d2" in ident.reasons["d3"]  # axes 2 and 3 parallel
    assert "board about base z" in ident.reasons["zero1"]
    assert "camera about the flange axis" in ident.reasons["zero6"]
    assert "tool frame" in ident.reasons["d6"]


@pytest.mark.parametrize("change", [{"zero1": 0.3}, {"d1": 2.0}, {"zero6": 0.3}, {"d6": 2.0}, {"a6": 2.0},
                                    {"alpha6": 0.3}, {"d2": 1.5, "d3": -1.5}])
def test_not_identifiable_really_are(scene, change):
    """The same noise, the arm changed by a large amount in what is called not identifiable: every
    identified value stays where it was (the camera and board poses take the change)."""
    base = random_deviation(np.random.default_rng(2))
    moved = base.copy()
    for name, value in change.items():
        moved[NAMES.index(name)] += value
    a, b = _identify(scene, base, 9), _identify(scene, moved, 9)
    assert a.status == b.status
    ok = np.array([s == "identified" for s in a.status])
    assert np.all(np.abs(b.values[ok] - a.values[ok]) < 0.05 * a.sigma[ok])
    # and the change itself is large: it moves the flange by millimetres or more than 1 mrad
    assert max(abs(v) for v in change.values()) >= 0.3


def test_an_identified_change_is_seen(scene):
    """The contrast: the same size of change on an identified zero moves its estimate by that much."""
    base = random_deviation(np.random.default_rng(2))
    moved = base.copy()
    j = NAMES.index("zero3")
    moved[j] += 0.05
    a, b = _identify(scene, base, 9), _identify(scene, moved, 9)
    assert b.values[j] - a.values[j] == pytest.approx(0.05, abs=3 * a.sigma[j])


def test_predicted_standoff_error_matches_held_out_truth(scene):
    deviation = random_deviation(np.random.default_rng(4))
    ident = _identify(scene, deviation, 4)
    held = make_scene(SceneConfig(postures=60, seed=104)).joints_deg
    predicted = predicted_standoff(ident, held)
    true_arm = corrected_robot(scene.robot, deviation)
    with_, without = measured_standoff(true_arm, scene.x_true, scene.target2fixed, scene.robot, ident, held)
    rms_with, rms_without = np.sqrt(np.mean(with_ ** 2)), np.sqrt(np.mean(without ** 2))
    assert rms_with < 0.6 * rms_without
    assert 0.5 < predicted.corrected_rms_mm / rms_with < 2.0
    assert 0.7 < predicted.uncorrected_rms_mm / rms_without < 1.5


def test_prior_comes_from_the_robot_file(tmp_path):
    from handeye.calibration.arm_parameters import robot_prior

    assert robot_prior("IRB1400") == {"length_mm": 0.5, "angle_deg": 0.1}
    text = (Path(__file__).parents[2] / "src/handeye/robot/robots/irb1400.yaml").read_text()
    other = tmp_path / "arm.yaml"
    other.write_text(text.replace("kinematic_prior: {length_mm: 0.5, angle_deg: 0.1}",
                                  "kinematic_prior: {length_mm: 0.2, angle_deg: 0.03}"))
    assert robot_prior(str(other)) == {"length_mm": 0.2, "angle_deg": 0.03}


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_uncorrected_prediction_is_the_known_offset_plus_the_corrected_spread(scene, seed):
    """Without the correction the error is the known difference b plus the corrected point's own error:
    predicted within 10 % of the measured RMS (the camera-only covariance, which already holds the arm's
    errors, added to b over-predicted by up to 2x)."""
    deviation = random_deviation(np.random.default_rng(seed))
    ident = _identify(scene, deviation, seed)
    held = make_scene(SceneConfig(postures=60, seed=100 + seed)).joints_deg
    predicted = predicted_standoff(ident, held)
    true_arm = corrected_robot(scene.robot, deviation)
    _, without = measured_standoff(true_arm, scene.x_true, scene.target2fixed, scene.robot, ident, held)
    assert predicted.uncorrected_rms_mm / np.sqrt(np.mean(without ** 2)) == pytest.approx(1.0, abs=0.1)
    # the drawn RMS of one calibration: its mean square is the prediction's, and the interval brackets it
    for draws, rms in ((predicted.corrected_draws_mm, predicted.corrected_rms_mm),
                       (predicted.uncorrected_draws_mm, predicted.uncorrected_rms_mm)):
        assert np.sqrt(np.mean(draws ** 2)) == pytest.approx(rms, rel=0.03)
    low, high = predicted.interval(0.9)
    assert low < predicted.corrected_rms_mm < high
    assert predicted.quantile(low) == pytest.approx(0.05, abs=0.01) and predicted.quantile(high) == pytest.approx(0.95, abs=0.01)
