"""The check's statistic when nothing changed (issue 42.7): over fresh calibrations and fresh revisits
of a synthetic station, ``q = d^T Σ^-1 d`` must follow its reference distribution, so that the level is
the false-alarm rate and a DRIFT is "beyond the noise" (what matters is ``station.verify.tolerance``'s).

Each sample draws a calibration (16 postures) and a revisit of K = 5 of its postures with the same
noise, solves the calibration with the default estimator (its noise levels estimated, as on a
station) and tests the revisit against it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import kstest

from handeye.calibration.eiv import observations, solve_eiv
from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from handeye.calibration.verification import baseline_from_solution, discrepancy, drift_test

K = 5
NOISE = {"sigma_rob_deg": 0.003, "sigma_cam_mm": 0.1, "camera_model": "gaussian"}


@pytest.fixture(scope="module")
def no_change_samples():
    scene = make_scene(SceneConfig(postures=16, seed=3))
    revisit = replace(scene, joints_deg=scene.joints_deg[:K], config=replace(scene.config, postures=K))
    tests = []
    for c in range(12):
        calibration = sample_session(scene, NoiseConfig(**NOISE, seed=100 + c))
        baseline = baseline_from_solution(solve_eiv(problem_from_session(calibration), folds=0))
        for r in range(3):
            problem = problem_from_session(sample_session(revisit, NoiseConfig(**NOISE, seed=1000 * c + r)),
                                           check_consistency=False)
            tests.append(drift_test(discrepancy(baseline, observations(problem), problem.joints_deg), baseline))
    return tests


def test_the_no_change_statistic_follows_its_distribution(no_change_samples):
    tests = no_change_samples
    q = np.array([t.statistic for t in tests])
    p = np.array([t.p_value for t in tests])
    m = tests[0].degrees
    assert m == 6 * K
    assert 0.75 * m < q.mean() < 1.3 * m  # E[q] = m
    assert kstest(p, "uniform").pvalue > 0.001  # p-values uniform: the level is the false-alarm rate
    assert np.mean(p < 0.01) <= 2 / len(p)

