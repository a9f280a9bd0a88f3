"""The posture residual (calibration/quality_words.py): one word, one number for every method."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.calibration.compact_points import CompactPoints
from handeye.calibration.problem import HandEyeProblem
from handeye.calibration.quality_words import (
    RESIDUAL_POINTS,
    kept_postures,
    posture_residual_meaning,
    posture_residuals,
    result_d_org,
)
from handeye.calibration.solve import calibrate

from helpers import problem


def _shifted(prob: HandEyeProblem, posture: int, shift_mm) -> HandEyeProblem:
    """``prob`` with one posture's board points (corners and compact points) moved in the camera frame."""
    points = prob.points_cam.copy()
    points[posture] += shift_mm
    c = prob.compact
    compact_points = c.points.copy()
    compact_points[posture] += shift_mm
    compact = CompactPoints(compact_points, c.target_points, c.target2cam, c.plane_rms_mm, c.square_mm)
    return HandEyeProblem(prob.setup, prob.hand, compact, points, prob.posture_ids, c.target_points)


def test_the_residual_is_each_postures_distance_from_the_kept_postures_mean_points():
    # known truth: exact data and the true X put every board point on the true board, so a posture whose
    # points are moved by v in the camera frame is |v| from the kept postures' mean, the others 0
    prob, truth, _ = problem(8)
    bad = _shifted(prob, 3, np.array([3.0, -4.0, 12.0]))
    kept = np.arange(8) != 3
    r = posture_residuals(bad, truth["x"], kept)
    assert r.shape == (8,) and abs(r[3] - 13.0) < 1e-9 and np.max(r[kept]) < 1e-9
    everyone = posture_residuals(bad, truth["x"])  # the reference is the mean over every posture
    assert abs(everyone[3] - 13.0 * 7 / 8) < 1e-9 and np.allclose(everyone[kept], 13.0 / 8)


@pytest.mark.parametrize("method", ["mc", "mcb", "tsai", "robust", "ml"])
def test_every_method_reports_the_same_word_on_the_same_points(method):
    # a gross posture: the estimators leave it out; every method's residuals are THE posture residual
    # of its own X and kept postures, their mean over the kept postures is its d_org, and the text is one
    prob, truth, _ = problem(12, sigma_cam=0.5, seed=3)
    bad = _shifted(prob, 4, np.array([0.0, 30.0, 0.0]))
    result = calibrate(bad, method, truth)
    kept = kept_postures(bad, result)
    expected = posture_residuals(bad, result.x, kept)
    assert list(result.residuals_mm) == [int(i) for i in bad.posture_ids]
    assert np.allclose(list(result.residuals_mm.values()), expected, rtol=0, atol=1e-12)
    assert abs(np.mean(expected[kept]) - result_d_org(bad, result).mm) < 1e-9
    assert result.residuals_on == "corners" and result.metrics["points"] == "corners"
    assert result.residuals_meaning == posture_residual_meaning("corners")
    assert result.to_json()["posture_residuals_meaning"] == result.residuals_meaning
    if method in ("robust", "ml"):
        assert result.outliers == [4] and result.residuals_mm[4] > 10 * np.median(expected[kept])


def test_a_session_of_board_poses_measures_it_on_the_compact_points():
    prob, truth, _ = problem(8, sigma_cam=0.5, seed=2)
    poses_only = HandEyeProblem(prob.setup, prob.hand, prob.compact, prob.compact.points, prob.posture_ids,
                                prob.compact.target_points)
    result = calibrate(poses_only, "mcb", truth)
    assert result.residuals_on == "compact" and result.metrics["points"] == "compact"
    assert RESIDUAL_POINTS["compact"] in result.residuals_meaning
    assert np.allclose(list(result.residuals_mm.values()), posture_residuals(poses_only, result.x))
