"""Small builders shared by the tests."""

from __future__ import annotations

from functools import lru_cache

from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session


@lru_cache(maxsize=None)
def scene(postures: int = 12, setup: str = "eye_in_hand", seed: int = 0):
    """A synthetic scene (cached: inverse kinematics makes them cost about 0.1 s a posture)."""
    return make_scene(SceneConfig(postures=postures, setup=setup, seed=seed))


def problem(postures=12, setup="eye_in_hand", sigma_cam=0.0, sigma_rob=0.0, seed=0, scene_seed=0):
    """(problem, truth dict, scene) drawn from a cached scene."""
    sc = scene(postures, setup, scene_seed)
    session = sample_session(sc, NoiseConfig(sigma_rob_deg=sigma_rob, sigma_cam_mm=sigma_cam, seed=seed))
    return problem_from_session(session), {"x": sc.x_true, "target2fixed": sc.target2fixed}, sc
