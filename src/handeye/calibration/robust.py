"""The ``robust`` estimator (the default before ``ml``): the paper's mcb start on the postures that
keep the rotation-angle invariant, then robust refinement of the point consistency alternated with
outlier detection until the inlier set is stable, and a one-sigma uncertainty.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass

import numpy as np

from ..base import CalibrationError
from .paper import solve_paper
from .problem import MIN_POSTURES, HandEyeProblem
from .refine import (
    ANGLE_GAP_FLOOR_DEG,
    RESIDUAL_FLOOR_MM,
    compact_point_angle_gaps_deg,
    at_most_half,
    keep_majority,
    posture_residuals_to,
    refine_point_consistency,
    robust_outliers,
)
from .selection import least_d_back
from .triplets import relative_motions

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["MAX_OUTLIER_ROUNDS", "RobustSolution", "solve_robust"]

MAX_OUTLIER_ROUNDS = 5


@dataclass(frozen=True)
class RobustSolution:
    """What :func:`solve_robust` returns (the attributes every ``estimator`` method returns).

    Attributes
    ----------
    x : ndarray, shape (4, 4)
    outliers : ndarray of bool, shape (n,)
    residuals_mm : ndarray, shape (n,)
        The fit residual the outliers are judged on, per posture: mean distance of its three compact
        board points, carried into the fixed frame, from the refined fixed points (all postures,
        outliers too). Not reported as the posture residual (``quality_words.posture_residuals``).
    uncertainty : dict
        One-sigma ``translation_mm`` and ``rotation_deg`` of X.
    details : dict
    cross_validation : None
        Not estimated.
    """

    x: np.ndarray
    outliers: np.ndarray
    residuals_mm: np.ndarray
    uncertainty: dict
    details: dict
    cross_validation: dict | None = None


def solve_robust(problem: HandEyeProblem, progress: Callable[[int, int, str], object] | None = None) -> RobustSolution:
    """mcb on the postures that keep the rotation-angle invariant, then alternate robust refinement
    and outlier detection until the inlier set is stable; never drops more than half the postures.
    ``progress`` is accepted for the estimator signature and not called."""
    n = problem.n
    gaps = compact_point_angle_gaps_deg(relative_motions(problem))
    gap_flags = keep_majority(robust_outliers(gaps, ANGLE_GAP_FLOOR_DEG), MIN_POSTURES)
    start_problem = problem.subset(~gap_flags)
    try:
        x, start_details = solve_paper(start_problem, least_d_back)
    except CalibrationError:
        x, start_details = solve_paper(problem, least_d_back)
    flags = gap_flags.copy()
    for rounds in range(1, MAX_OUTLIER_ROUNDS + 1):
        keep = ~flags
        refinement = refine_point_consistency(problem.hand[keep], problem.compact.points[keep], x)
        x = refinement.x
        residuals = posture_residuals_to(problem.hand, x, problem.compact.points, refinement.fixed_points)
        new_flags = at_most_half(robust_outliers(residuals, RESIDUAL_FLOOR_MM) | gap_flags, residuals)
        if n - new_flags.sum() < MIN_POSTURES or np.array_equal(new_flags, flags):
            break
        flags = new_flags
    else:  # the inlier set kept changing: the answer is the refinement over the last one
        refinement = refine_point_consistency(problem.hand[~flags], problem.compact.points[~flags], x)
        x = refinement.x
        residuals = posture_residuals_to(problem.hand, x, problem.compact.points, refinement.fixed_points)
    details = {
        "start": {"method": "mcb", **start_details},
        "outlier_rounds": rounds,
        "refinement": {"loss": "soft_l1", "evaluations": refinement.iterations, "converged": refinement.success},
        "angle_gap_deg": {str(int(i)): float(g) for i, g in zip(problem.posture_ids, gaps)},
    }
    uncertainty = {
        "translation_mm": [float(v) for v in refinement.sigma_translation_mm],
        "rotation_deg": [float(v) for v in refinement.sigma_rotation_deg],
        "level": "one sigma of the random errors (sandwich covariance of the refinement); "
                 "systematic robot errors are not included",
    }
    return RobustSolution(x, flags, residuals, uncertainty, details)
