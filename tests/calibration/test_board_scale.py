"""The square-size check from a grid fit with a free scale: unbiased under noise, refuses only what it can judge."""

from dataclasses import replace

import numpy as np
import pytest

from handeye.geometry.board_scale import board_scale, grid_scales, judge_square_size
from handeye.calibration.plausibility import implausibilities
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session


@pytest.fixture(scope="module")
def scene():
    return make_scene(SceneConfig(postures=30, seed=11))


def _points(scene, sigma, seed=0):
    session = sample_session(scene, NoiseConfig(sigma_cam_mm=sigma, seed=seed))
    return session, np.array([p.points_mm for p in session.postures])


def test_a_noise_free_board_gives_its_square_size(scene):
    _, points = _points(scene, 0.0)
    assert np.allclose(grid_scales(points, scene.board.corners), scene.board.square_mm, atol=1e-9)


@pytest.mark.parametrize("sigma", [2.5, 10.0, 20.0])
def test_paper_regime_noise_does_not_refuse_the_right_square_size(scene, sigma):
    for seed in range(4):  # the old neighbour-distance check refused two of four at 10 mm
        session, points = _points(scene, sigma, seed)
        scale = board_scale(points, scene.board.corners)
        assert abs(scale.square_mm - 30.0) < 4 * scale.stderr_mm + 0.3  # unbiased: within its own error
        tool0 = np.array([p.tool0_in_base for p in session.postures])
        assert not [f for f in implausibilities(session, tool0) if f.kind == "square_size"]


@pytest.mark.parametrize("sigma", [0.0, 1.0, 2.5, 5.0])
@pytest.mark.parametrize("factor", [1.1, 1 / 1.1])
def test_a_square_size_off_by_ten_percent_is_refused_up_to_5_mm_noise(scene, sigma, factor):
    session, _ = _points(scene, sigma, seed=3)
    wrong = replace(session, target=replace(session.target, square_mm=30.0 * factor))
    found = [f for f in implausibilities(wrong, np.array([p.tool0_in_base for p in session.postures]))
             if f.kind == "square_size"]
    assert found and "correct the square size" in found[0].message
    assert "standard error" in found[0].message


def test_the_message_says_units_or_noise(scene):
    _, points = _points(scene, 1.0)
    judged = judge_square_size(points, scene.board.corners, 0.03)  # square size in metres
    assert judged.verdict == "units" and "a unit (m for mm)" in judged.message
    _, noisy = _points(scene, 400.0)  # far beyond any camera: the scale cannot be judged
    judged = judge_square_size(noisy[:3], scene.board.corners, 33.0)
    assert judged.verdict in ("noise", "ok")
    if judged.verdict == "noise":
        assert "too noisy to judge" in judged.message
