"""The workers of one run share deterministic builds (``run_cache.shared_by_workers``): what a later
worker reads is what it would have built, and it does not build it again."""

import numpy as np

from handeye.calibration.synthetic import SceneConfig, make_scene

from run_cache import RUN_CACHE, shared_by_workers


def test_a_later_worker_reads_the_same_scene_without_building_it(tmp_path, monkeypatch):
    monkeypatch.setenv(RUN_CACHE, str(tmp_path))
    config = SceneConfig(postures=4, setup="eye_in_hand", seed=5)
    builds = []

    def build():
        builds.append(1)
        return make_scene(config)

    first = shared_by_workers("scene-test", build)
    again = shared_by_workers("scene-test", build)
    assert len(builds) == 1 and [p.name for p in tmp_path.iterdir()] == ["scene-test.pickle"]
    fresh = make_scene(config)
    for got in (first, again):
        assert np.array_equal(got.joints_deg, fresh.joints_deg) and np.array_equal(got.x_true, fresh.x_true)
        assert np.array_equal(got.target2fixed, fresh.target2fixed) and got.config == fresh.config
        assert np.array_equal(got.tool02base(), fresh.tool02base())


def test_without_the_run_folder_it_builds(tmp_path, monkeypatch):
    monkeypatch.setenv(RUN_CACHE, str(tmp_path / "not-there"))
    assert shared_by_workers("k", lambda: 41) == 41 and shared_by_workers("k", lambda: 42) == 42
