"""The outlier step on partial views (issue 37): a gross posture among ChArUco views that saw part of the
board (board points by id) is named and left out, and the solution stays at the synthetic truth; no clean
partial view is lost to the step."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.calibration.solve import calibrate, problem_from_session
from handeye.geometry.transforms import rotation_error_deg, translation_error_mm

from test_partial_views import _partial_session


def _spoiled(seed: int):
    scene, session = _partial_session(seed=seed)
    k = next(p.index for p in session.postures if p.corner_ids is not None)
    p = session.postures[k]
    turn = np.eye(4)
    turn[:3, :3] = Rotation.from_euler("xyz", [12.0, -8.0, 5.0], degrees=True).as_matrix()
    turn[:3, 3] = [40.0, -25.0, 30.0]
    p.tool0_in_base = np.asarray(p.tool0_in_base, float) @ turn  # a posture of another moment (a gross error)
    return scene, session, k


def test_a_gross_partial_posture_is_named_and_left_out():
    for seed in (1, 2):
        scene, session, k = _spoiled(seed)
        assert len(session.postures[k].corner_ids) < 104
        problem = problem_from_session(session)
        for method in (None, "robust"):  # the default and the robust pipeline (the classic methods have no outlier step)
            result = calibrate(problem, method)
            assert k in result.outliers, (seed, method, result.outliers)
            assert translation_error_mm(result.x, scene.x_true) < 0.8
            assert rotation_error_deg(result.x, scene.x_true) < 0.08


def test_clean_partial_views_lose_no_posture_to_the_outlier_step():
    for seed in (1, 2, 3):
        _, session = _partial_session(seed=seed)
        result = calibrate(problem_from_session(session))
        assert result.outliers == [] or len(result.outliers) == 0, (seed, result.outliers)
