"""The quick update's uncertainty against a known truth: a check whose noise is larger than the
session's noise levels say (the arm's unmodelled errors) must not report the smaller sigmas of those
levels; its own residuals (their reduced chi-square) show how much larger it is."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from handeye.calibration import drift_causes
from handeye.calibration.noise import retract, twist_between
from handeye.geometry.transforms import invert_transforms, rotation_error_deg
from handeye.calibration.verification import Baseline, Discrepancy

K = 5
TRUE_SIGMA = np.r_[np.full(3, 0.05), np.full(3, 5e-4)]  # mm, rad: the revisits' real noise


def _pose(rng, spread_mm: float) -> np.ndarray:
    return retract(np.eye(4), np.r_[rng.normal(0.0, spread_mm, 3), rng.normal(0.0, 1.0, 3)])


def _scene(rng):
    """A new camera pose, the board, K flange poses and the board measured there with TRUE_SIGMA noise."""
    new_x = retract(np.eye(4), np.r_[rng.normal(0.0, 100.0, 3), rng.normal(0.0, 1.0, 3)])
    old_x = retract(new_x, np.r_[rng.normal(0.0, 2.0, 3), rng.normal(0.0, 0.0035, 3)])  # 2 mm / 0.2 deg away
    target = _pose(rng, 800.0)
    hand = np.array([_pose(rng, 600.0) for _ in range(K)])
    board = invert_transforms(hand @ new_x) @ target
    board = retract(board, rng.normal(0.0, 1.0, (K, 6)) * TRUE_SIGMA)
    return new_x, old_x, target, hand, board


def _fake_discrepancy(claimed_sigma):
    """``verification.discrepancy`` of the scene: ``d_j = twist(T^-1 A_j X B_j)``, the noise the session claims."""
    noise = np.diag(np.tile(claimed_sigma ** 2, K))

    def discrepancy(baseline, obs, joints_deg=None):
        d = twist_between(baseline.target[None], obs.hand @ baseline.x @ obs.board).reshape(-1)
        return Discrepancy(d, noise, np.zeros((6 * K, 12)), noise, obs.hand, obs.board, None)

    return discrepancy


def _covered(update, new_x) -> bool:
    err = np.abs(update.x[:3, 3] - new_x[:3, 3])
    return bool(np.all(err <= 3 * update.sigma_translation_mm)
                and rotation_error_deg(update.x, new_x) <= 3 * np.linalg.norm(update.sigma_rotation_deg))


@pytest.mark.parametrize("claimed_fraction, at_least", [(1.0, 0.95), (0.25, 0.93)])
def test_the_update_is_within_three_sigma_even_when_the_noise_levels_claim_too_little(monkeypatch, claimed_fraction,
                                                                                     at_least):
    monkeypatch.setattr(drift_causes, "discrepancy", _fake_discrepancy(TRUE_SIGMA * claimed_fraction))
    rng = np.random.default_rng(23)
    covered, reduced = [], []
    for _ in range(200):
        new_x, old_x, target, hand, board = _scene(rng)
        baseline = Baseline(old_x, target, np.zeros(0), (), np.zeros(0), np.zeros((12, 12)), 100)
        update = drift_causes.quick_update(baseline, SimpleNamespace(hand=hand, board=board))
        covered.append(_covered(update, new_x))
        reduced.append(update.reduced_chi2)
    assert np.mean(covered) >= at_least
    # the residuals see the claimed levels' shortfall: about (1 / fraction)^2
    assert np.median(reduced) == pytest.approx(claimed_fraction ** -2, rel=0.35)


def test_the_scale_never_shrinks_the_covariance(monkeypatch):
    monkeypatch.setattr(drift_causes, "discrepancy", _fake_discrepancy(TRUE_SIGMA * 10.0))  # levels claim too much
    rng = np.random.default_rng(5)
    new_x, old_x, target, hand, board = _scene(rng)
    baseline = Baseline(old_x, target, np.zeros(0), (), np.zeros(0), np.zeros((12, 12)), 100)
    update = drift_causes.quick_update(baseline, SimpleNamespace(hand=hand, board=board))
    assert update.reduced_chi2 < 0.1
    # the levels' own sigmas stand (a scale of 0.01 would bring them to a tenth): at least half the
    # translation noise the levels claim, averaged over the K postures
    assert np.all(update.sigma_translation_mm > 0.5 * 10.0 * TRUE_SIGMA[0] / np.sqrt(K))
