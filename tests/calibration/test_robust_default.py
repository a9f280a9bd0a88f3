import numpy as np

from handeye.calibration.refine import compact_point_angle_gaps_deg, refine_point_consistency, robust_outliers
from handeye.calibration.solve import ROBUST_METHOD, calibrate
from handeye.calibration.triplets import relative_motions

from helpers import flipped_board, problem


# The robust pipeline was the default until the maximum-likelihood estimator (tests/calibration/test_ml_default.py);
# these tests pin its behaviour under its name.


def test_robust_is_the_robust_pipeline():
    prob, truth, _ = problem(12, sigma_cam=2.0, seed=1)
    r = calibrate(prob, "robust", truth)
    assert r.method == ROBUST_METHOD == "robust"
    assert r.uncertainty is not None
    assert all(np.isfinite(r.uncertainty["translation_mm"])) and all(np.isfinite(r.uncertainty["rotation_deg"]))
    assert set(map(int, r.residuals_mm)) == set(map(int, prob.posture_ids))


def test_refinement_exact_without_noise():
    prob, truth, _ = problem(10)
    start = truth["x"].copy()
    start[:3, 3] += [3.0, -2.0, 1.0]  # a poor start
    ref = refine_point_consistency(prob.hand, prob.compact.points, start)
    assert np.allclose(ref.x, truth["x"], atol=1e-6)
    assert ref.residuals_mm.max() < 1e-6


def _corrupt(prob, postures, shift_mm=40.0, turn_deg=4.0):
    """Gross board errors at some postures (misdetection): move and turn their points."""
    from scipy.spatial.transform import Rotation

    pts = prob.compact.points.copy()
    turn = Rotation.from_rotvec(np.radians([turn_deg, 0, 0])).as_matrix()
    for k in postures:
        centre = pts[k].mean(axis=0)
        pts[k] = (pts[k] - centre) @ turn.T + centre + shift_mm
    from handeye.calibration.compact_points import CompactPoints
    from handeye.calibration.problem import HandEyeProblem

    c = prob.compact
    compact = CompactPoints(pts, c.target_points, c.target2cam, c.plane_rms_mm, c.square_mm)
    return HandEyeProblem(prob.setup, prob.hand, compact, pts, prob.posture_ids, c.target_points)


def test_gross_outliers_are_found_and_excluded():
    prob, truth, _ = problem(20, sigma_cam=2.0, seed=3)
    bad = _corrupt(prob, [4, 13])
    plain = calibrate(bad, "mc", truth)
    robust = calibrate(bad, "robust", truth)
    assert robust.outliers == [4, 13]
    assert robust.residuals_mm[4] > 5 * np.median(list(robust.residuals_mm.values()))
    # excluding them restores an accurate answer; the all-postures solution is pulled away
    assert robust.truth_errors["translation_error_mm"] < 2.0
    assert robust.truth_errors["translation_error_mm"] < plain.truth_errors["translation_error_mm"]


def test_no_outliers_in_clean_data():
    prob, _, _ = problem(20, sigma_cam=3.0, seed=5)
    assert calibrate(prob, "robust").outliers == []


def test_at_least_as_accurate_as_mcb_on_camera_noise():
    errs = []
    for seed in range(4):
        prob, truth, _ = problem(20, sigma_cam=5.0, seed=40 + seed)
        a = calibrate(prob, "mcb", truth).truth_errors
        b = calibrate(prob, "robust", truth).truth_errors
        errs.append([a["rotation_error_deg"], a["translation_error_mm"], b["rotation_error_deg"], b["translation_error_mm"]])
    errs = np.median(np.array(errs), axis=0)
    assert errs[2] <= errs[0] * 1.05 and errs[3] <= errs[1] * 1.05


def test_angle_gap_invariant_flags_a_flipped_board():
    # flip posture 6's board by 180 deg about its normal: the X-free angle invariant breaks
    prob, _, _ = problem(12, sigma_cam=1.0, seed=2)
    flipped = flipped_board(prob, 6)
    gaps = compact_point_angle_gaps_deg(relative_motions(flipped))
    assert np.argmax(gaps) == 6 and robust_outliers(gaps)[6]
    assert calibrate(flipped, "robust").outliers == [6]


def test_uncertainty_is_calibrated_on_synthetic_data():
    """One-sigma values should match the spread of the actual errors (z-scores of RMS ~1)."""
    from scipy.spatial.transform import Rotation

    z = []
    for seed in range(12):
        prob, truth, _ = problem(20, sigma_cam=5.0, seed=300 + seed)
        r = calibrate(prob, "robust", truth)
        et = r.x[:3, 3] - truth["x"][:3, 3]
        er = np.degrees(Rotation.from_matrix(r.x[:3, :3] @ truth["x"][:3, :3].T).as_rotvec())
        z.append(np.concatenate([et / r.uncertainty["translation_mm"], er / r.uncertainty["rotation_deg"]]))
    rms = np.sqrt(np.mean(np.square(z)))
    assert 0.5 < rms < 2.0
