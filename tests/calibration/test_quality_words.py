"""The quality words (calibration/quality_words.py): one definition each, and the same number wherever
the operator reads the word (capture plan, calibrate refusal, verdict, report)."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.calibration.classic import CLASSIC_METHODS
from handeye.geometry.board import BoardGeometry
from handeye.base.errors import CalibrationError
from handeye.robot.kinematics import load_robot
from handeye.calibration.quality_words import (
    MAX_AXIS_SPREAD_DEG,
    hand_axis_coverage,
    relative_rotation_angles_deg,
    relative_rotation_quaternions,
    result_d_org,
    rotation_axis_divergence_deg,
    rotation_axis_spread,
    usable_axes,
)
from handeye.calibration.solve import calibrate, check_motion, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, Scene, SceneConfig, sample_session
from handeye.geometry.transforms import invert_transforms, transform_from_rotation_translation
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.capture.loop import plan_line
from handeye.station.capture.planning import plan_postures
from handeye.station.report.quality import verdict

from helpers import problem as make_problem

REPO = Path(__file__).resolve().parents[2]


def _hand(rotvecs_deg):
    """Hand poses ``(n, 4, 4)``: the first at identity, each other one turned by a rotation vector (deg)."""
    poses = [np.eye(4)]
    for k, v in enumerate(rotvecs_deg):
        poses.append(transform_from_rotation_translation(Rotation.from_rotvec(v, degrees=True).as_matrix(),
                                                         [10.0 * k, 5.0, 0.0]))
    return np.array(poses)


def test_relative_rotation_angles_are_the_angles_between_postures():
    hand = _hand([[0, 0, 30], [40, 0, 0]])
    angles = relative_rotation_angles_deg(relative_rotation_quaternions(hand))
    between = math.degrees(Rotation.from_rotvec([0, 0, 30], degrees=True).inv()
                           .__mul__(Rotation.from_rotvec([40, 0, 0], degrees=True)).magnitude())
    assert np.allclose(angles, [30.0, 40.0, between])


def test_relative_rotations_are_algorithm_1_step_2():
    from handeye.calibration.triplets import relative_motions

    problem, _, _ = make_problem(8, sigma_rob=0.01)
    assert np.array_equal(relative_rotation_quaternions(problem.hand), relative_motions(problem).q_a)


def test_spread_is_zero_for_axes_in_one_plane_and_maximal_for_even_axes():
    planar = _hand([[a, b, 0] for a, b in [(30, 0), (0, 30), (25, 20), (-20, 25), (35, -10)]])
    q = relative_rotation_quaternions(planar)
    spread, weakest = rotation_axis_spread(q)
    # the relative rotations of rotations about in-plane axes leave the plane a little; still small
    assert spread < 8.0 and abs(weakest[2]) > 0.95
    even = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    even[1:, 0] = math.cos(math.radians(20))
    even[1:, 1:] *= math.sin(math.radians(20))
    spread, _ = rotation_axis_spread(even[1:])
    assert spread == pytest.approx(MAX_AXIS_SPREAD_DEG, abs=1e-9)
    assert MAX_AXIS_SPREAD_DEG == pytest.approx(35.26, abs=0.01)


def test_spread_weighs_small_rotations_little_and_ignores_those_below_two_degrees():
    big = np.array([[math.cos(math.radians(20)), math.sin(math.radians(20)), 0, 0],
                    [math.cos(math.radians(20)), 0, math.sin(math.radians(20)), 0]])
    tiny_z = np.array([[math.cos(math.radians(0.5)), 0, 0, math.sin(math.radians(0.5))]])  # 1 deg about z
    assert rotation_axis_spread(np.vstack([big, tiny_z]))[0] == 0.0
    small_z = np.array([[math.cos(math.radians(2.5)), 0, 0, math.sin(math.radians(2.5))]])  # 5 deg about z
    spread, weakest = rotation_axis_spread(np.vstack([big, small_z]))
    assert 0.0 < spread < 10.0 and abs(weakest[2]) > 0.99


def test_divergence_is_zero_for_parallel_axes():
    assert rotation_axis_divergence_deg([[0, 0, 1], [0, 0, -1], [0, 0, 1]]) == 0.0
    assert rotation_axis_divergence_deg([[1, 0, 0], [0, 1, 0]]) == pytest.approx(45.0)
    assert rotation_axis_divergence_deg(np.zeros((0, 3))) == 0.0


def test_calibrate_and_the_classic_solvers_refuse_parallel_axes_by_the_divergence():
    hand = _hand([[0, 0, a] for a in (20, 45, 70, 95)])
    assert rotation_axis_divergence_deg(usable_axes(relative_rotation_quaternions(hand))) < 1e-6
    x = transform_from_rotation_translation(Rotation.from_euler("xyz", [3, -2, 85], degrees=True).as_matrix(),
                                            [60.0, -110.0, 95.0])
    target2cam = invert_transforms(hand @ x) @ transform_from_rotation_translation(np.eye(3), [900.0, 0.0, 0.0])
    with pytest.raises(CalibrationError, match="rotation-axis divergence"):
        CLASSIC_METHODS["tsai"](hand, target2cam)
    problem, _, _ = make_problem(8)
    check_motion(problem)  # a real plan passes


def test_the_plan_shows_the_spread_and_angles_the_verdict_judges():
    """One word, one number: the capture plan's score is the verdict's figure on the same postures."""
    robot = load_robot("IRB1400")
    board = BoardGeometry((13, 8), 30.0)
    start_view = invert_transforms(robot.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    plan = plan_postures(robot, DEFAULT_START, start_view, DEFAULT_MOUNT, board, count=12, seed=3)
    scene = Scene(SceneConfig(postures=12, corners=board.corners, square_mm=board.square_mm, robot=robot.name),
                  robot, DEFAULT_MOUNT, DEFAULT_BOARD, plan.joints_deg, board)
    problem = problem_from_session(sample_session(scene, NoiseConfig(seed=1)))
    result = calibrate(problem)
    assert result.outliers == []
    checks = {c.name: c for c in verdict(result, problem).checks}
    assert checks["min_rotation_axis_spread_deg"].value == pytest.approx(plan.score.rotation_axis_spread_deg, abs=1e-6)
    assert checks["min_median_rotation_deg"].value == pytest.approx(plan.score.median_pair_angle_deg, abs=1e-6)
    coverage = hand_axis_coverage(robot.forward_transform(plan.joints_deg))
    assert coverage.min_angle_deg == pytest.approx(plan.score.min_pair_angle_deg)
    line = plan_line(plan.score, 12)
    assert f"rotation-axis spread {plan.score.rotation_axis_spread_deg:.1f} deg" in line
    assert "relative rotation angle" in line


def test_d_org_is_over_the_kept_postures_and_every_board_point():
    problem, _, _ = make_problem(10, sigma_cam=0.1)
    result = calibrate(problem)
    scatter = result_d_org(problem, result)
    assert scatter.corners and scatter.points_per_posture == 104 and scatter.postures == problem.n - len(result.outliers)
    assert scatter.mm == pytest.approx(result.metrics["d_org_mm"])  # the robust metrics use the kept postures too


def test_each_quality_word_is_defined_in_one_module():
    """No function outside calibration/quality_words.py computes a spread or a divergence of rotation
    axes, and the retired names of the old definitions are gone."""
    retired = {"station_d_org", "_axis_statistics", "_axis_spread_deg", "axis_spread"}
    offenders = []
    for room in ("geometry", "robot", "calibration", "station"):
        for path in sorted((REPO / "src" / "handeye" / room).rglob("*.py")):
            if path.name == "quality_words.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                name = getattr(node, "name", None) or getattr(node, "attr", None) or getattr(node, "id", None)
                if not isinstance(name, str):
                    continue
                defines = isinstance(node, (ast.FunctionDef, ast.ClassDef)) and ("spread" in name or "divergence" in name)
                if defines or name in retired:
                    offenders.append(f"{path.relative_to(REPO)}:{node.lineno} {name}")
    assert not offenders, offenders


def test_the_text_summary_and_the_report_give_each_figure_the_same_meaning(tmp_path, capsys):
    """d_org, d_back, dR and dt were explained twice in different words (text and HTML)."""
    from handeye.calibration.quality_words import METRIC_MEANINGS
    from handeye.station.cli import main

    session = tmp_path / "s"
    assert main(["simulate", "-o", str(session), "--postures", "8", "--sigma-cam", "1"]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(session), "--method", "mcb", "--report", str(tmp_path / "r.html")]) == 0
    text = capsys.readouterr().out
    html = (tmp_path / "r.html").read_text()
    for name in ("d_org", "d_back", "dR", "dt"):
        meaning = METRIC_MEANINGS[name]
        assert meaning in text, name
        assert meaning.replace("||", "||").replace("&", "&amp;") in html.replace("&#x27;", "'"), name
