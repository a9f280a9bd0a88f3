"""The hand-eye numbers: sessions on disk, the calibration methods, their checks and metrics.

It runs on numpy and scipy alone. The names below load on first use (importing the package is cheap)::

    from handeye.calibration import calibrate_session, read_session
    result = calibrate_session(read_session("cal_01"))            # the default method (ml)
    print(result.x, result.metrics["d_org_mm"])

Methods are the rows of :data:`METHODS` (``handeye.calibration.methods``; another package adds one
through the entry-point group ``handeye.methods``, :func:`method_names` lists them all); robots are
the YAML files of ``robot/robots`` (:func:`load_robot`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..base import lazy_exports

_EXPORTS = {
    "calibrate": "solve",
    "calibrate_session": "solve",
    "problem_from_session": "solve",
    "CalibrationResult": "solve",
    "ALL_METHODS": "solve",
    "DEFAULT_METHOD": "methods",
    "METHODS": "methods",
    "Method": "methods",
    "method_names": "methods",
    "register_method": "methods",
    "read_session": "session",
    "create_session": "session",
    "write_posture": "session",
    "Session": "session",
    "Posture": "session",
    "HandEyeProblem": "problem",
    "EYE_IN_HAND": "problem",
    "EYE_TO_HAND": "problem",
    "BoardGeometry": "handeye.geometry.board",
    "RobotModel": "handeye.robot.kinematics",
    "load_robot": "handeye.robot.kinematics",
    "known_robots": "handeye.robot.kinematics",
    "transform_from_pose": "handeye.geometry.transforms",
    "pose_from_transform": "handeye.geometry.transforms",
    "d_org": "metrics",
    "d_back": "metrics",
    "HandEyeError": "handeye.base.errors",
    "ConfigError": "handeye.base.errors",
    "SessionError": "handeye.base.errors",
    "CalibrationError": "handeye.base.errors",
    "OutputError": "handeye.base.errors",
    "compact_points_from_corners": "compact_points",
    "cross_validate": "crossval",
    "diagnose": "diagnostics",
    "find_unit_problems": "diagnostics",
    "explain": "drift_causes",
    "likelihood_ratio": "drift_causes",
    "quick_update": "drift_causes",
    "same_effect": "drift_causes",
    "observations": "eiv",
    "solve_eiv": "eiv",
    "MIN_MOTION_DEG": "invariants",
    "bounded_pairs": "invariants",
    "fit_hand_eye": "invariants",
    "pair_indices": "invariants",
    "pairs_used": "invariants",
    "posture_medians": "invariants",
    "session_joint_mismatch": "joint_match",
    "comparison_methods": "methods",
    "get_method": "methods",
    "errors_against_truth": "metrics",
    "fixed_points": "metrics",
    "session_in_mm": "plausibility",
    "MIN_POSTURES": "problem",
    "SETUPS": "problem",
    "hand_poses": "problem",
    "AXIS_SPREAD_NAME": "quality_words",
    "AxisCoverage": "quality_words",
    "DOrg": "quality_words",
    "D_ORG_ALL_NAME": "quality_words",
    "IMAGE_CELL_NAMES": "quality_words",
    "MAX_AXIS_SPREAD_DEG": "quality_words",
    "MEDIAN_ANGLE_NAME": "quality_words",
    "METRIC_MEANINGS": "quality_words",
    "POSTURE_RESIDUAL_NAME": "quality_words",
    "board_distances_mm": "quality_words",
    "distance_spread_mm": "quality_words",
    "hand_axis_coverage": "quality_words",
    "hand_frame": "quality_words",
    "image_cells": "quality_words",
    "kept_postures": "quality_words",
    "result_d_org": "quality_words",
    "rotation_axis_coverage": "quality_words",
    "MAX_CORNERS": "session",
    "MAX_LENGTH_MM": "session",
    "MAX_LENGTH_WORDS": "session",
    "MAX_POSTURE_INDEX": "session",
    "read_truth": "session",
    "write_postures": "session",
    "write_truth": "session",
    "write_yaml_atomic": "session",
    "bounded_for": "solve",
    "calibrate_within": "solve",
    "method_row": "solve",
    "truth_from_dict": "solve",
    "NoiseConfig": "synthetic",
    "Scene": "synthetic",
    "SceneConfig": "synthetic",
    "make_scene": "synthetic",
    "sample_session": "synthetic",
    "truth_dict": "synthetic",
    "opencv_test_problem": "synthetic_poses",
    "DEFAULT_LEVEL": "verification",
    "LEVEL_RANGE": "verification",
    "MIN_VERIFY_POSTURES": "verification",
    "baseline_from_solution": "verification",
    "discrepancy": "verification",
    "drift_test": "verification",
    "informative_postures": "verify_postures",
    "board_arrays": "partial_views",
    "compact_points_from_fit": "partial_views",
    "corrected_robot": "arm_parameters",
    "twist_between": "noise",
    "identify_arm": "arm_identification",
    "predicted_standoff": "standoff",
    "working_volume_joints": "standoff",
    "flange_standoff_points": "standoff",
    "CrossValidation": "crossval",
    "EivSolution": "eiv",
    "Explanation": "drift_causes",
    "QuickUpdate": "drift_causes",
    "Baseline": "verification",
    "DriftTest": "verification",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .partial_views import board_arrays, compact_points_from_fit  # noqa: F401
    from .arm_parameters import corrected_robot  # noqa: F401
    from .noise import twist_between  # noqa: F401
    from .arm_identification import identify_arm  # noqa: F401
    from .standoff import flange_standoff_points, predicted_standoff, working_volume_joints  # noqa: F401
    from .compact_points import compact_points_from_corners  # noqa: F401
    from .crossval import CrossValidation, cross_validate  # noqa: F401
    from .diagnostics import diagnose, find_unit_problems  # noqa: F401
    from .drift_causes import Explanation, QuickUpdate, explain, likelihood_ratio, quick_update, same_effect  # noqa: F401
    from .eiv import EivSolution, observations, solve_eiv  # noqa: F401
    from handeye.base import CalibrationError, ConfigError, HandEyeError, OutputError, SessionError  # noqa: F401
    from handeye.geometry import BoardGeometry  # noqa: F401
    from handeye.geometry import pose_from_transform, transform_from_pose  # noqa: F401
    from handeye.robot import RobotModel, known_robots, load_robot  # noqa: F401
    from .invariants import MIN_MOTION_DEG, bounded_pairs, fit_hand_eye, pair_indices, pairs_used, posture_medians  # noqa: F401
    from .joint_match import session_joint_mismatch  # noqa: F401
    from .methods import DEFAULT_METHOD, METHODS, Method, comparison_methods, get_method, method_names, register_method  # noqa: F401
    from .metrics import d_back, d_org, errors_against_truth, fixed_points  # noqa: F401
    from .plausibility import session_in_mm  # noqa: F401
    from .problem import EYE_IN_HAND, EYE_TO_HAND, HandEyeProblem, MIN_POSTURES, SETUPS, hand_poses  # noqa: F401
    from .quality_words import AXIS_SPREAD_NAME, AxisCoverage, DOrg, D_ORG_ALL_NAME, IMAGE_CELL_NAMES, MAX_AXIS_SPREAD_DEG, MEDIAN_ANGLE_NAME, METRIC_MEANINGS, POSTURE_RESIDUAL_NAME, board_distances_mm, distance_spread_mm, hand_axis_coverage, hand_frame, image_cells, kept_postures, result_d_org, rotation_axis_coverage  # noqa: F401
    from .session import MAX_CORNERS, MAX_LENGTH_MM, MAX_LENGTH_WORDS, MAX_POSTURE_INDEX, Posture, Session, create_session, read_session, read_truth, write_posture, write_postures, write_truth, write_yaml_atomic  # noqa: F401
    from .solve import ALL_METHODS, CalibrationResult, bounded_for, calibrate, calibrate_session, calibrate_within, method_row, problem_from_session, truth_from_dict  # noqa: F401
    from .synthetic import NoiseConfig, Scene, SceneConfig, make_scene, sample_session, truth_dict  # noqa: F401
    from .synthetic_poses import opencv_test_problem  # noqa: F401
    from .verification import Baseline, DriftTest, DEFAULT_LEVEL, LEVEL_RANGE, MIN_VERIFY_POSTURES, baseline_from_solution, discrepancy, drift_test  # noqa: F401
    from .verify_postures import informative_postures  # noqa: F401
