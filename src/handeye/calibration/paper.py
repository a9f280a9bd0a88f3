"""Algorithm 1 of Deniz & Cakir (2018): the paper's variants on a problem.

A candidate ``X`` from every posture triplet (``triplets``) and the one a selection criterion picks
(``selection``); without a criterion, all postures at once (``mc``). Which criterion a variant uses is
its row of the methods table (``calibration.methods``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import numpy as np

from ..base import CalibrationError
from .problem import HandEyeProblem
from .selection import CandidateScorer, select_candidate
from .triplets import all_postures_solution, relative_motions, triplet_candidates

if TYPE_CHECKING:
    from .selection import Criterion

__all__ = ["solve_paper", "truth_board_points"]


def truth_board_points(problem: HandEyeProblem, truth: dict | None) -> np.ndarray | None:
    """The compact board points ``(3, 3)`` where the truth puts them in the fixed frame, mm (None without truth)."""
    if truth is None:
        return None
    t = truth["target2fixed"]
    return problem.compact.target_points @ t[:3, :3].T + t[:3, 3]


def solve_paper(problem: HandEyeProblem, criterion: str | Criterion | None = None, truth_points: np.ndarray | None = None) -> tuple[np.ndarray, dict]:
    """``X`` by Algorithm 1 and what the result reports of it.

    Parameters
    ----------
    problem : HandEyeProblem
    criterion : callable or str, optional
        A selection criterion (:func:`handeye.calibration.selection.select_candidate`); None: all
        postures at once, no selection (``mc``).
    truth_points : ndarray, shape (3, 3), optional
        The compact points' true fixed-frame positions (:func:`truth_board_points`), for ``mcy``.

    Returns
    -------
    x : ndarray, shape (4, 4)
    details : dict
        Candidate counts, the selected triplet (posture indices) and its criterion value.

    Raises
    ------
    CalibrationError
        When no triplet gives a well-posed candidate.
    """
    motions = relative_motions(problem)
    if criterion is None:
        return all_postures_solution(problem, motions), {"candidates": 0}
    candidates = triplet_candidates(problem, motions)
    scorer = CandidateScorer(problem.hand, problem.compact.points)
    try:
        selection = select_candidate(criterion, candidates, scorer, motions, problem.compact.points[:, 0, :], truth_points)
    except ValueError as exc:
        raise CalibrationError(f"{exc}: rotate the flange about different axes between postures") from None
    triplet = candidates.triplets[selection.index]
    details = {
        "candidates": int(len(candidates)),
        "valid_candidates": int(candidates.valid.sum()),
        "exact_evaluations": int(selection.exact_evaluations),
        "selected_triplet": [int(problem.posture_ids[i]) for i in triplet],
        "criterion_value": selection.score,
    }
    return candidates.transform(selection.index), details
