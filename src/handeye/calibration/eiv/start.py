"""The start of the maximum-likelihood fit: the paper's mcb (Algorithm 1, selection by d_back,
eq. 23) on postures that keep the X-free angle invariant (eq. 30), spread over the hand rotations.
"""

from __future__ import annotations

import numpy as np

from ..invariants import bounded_pairs, posture_medians
from ..metrics import fixed_points
from ..problem import HandEyeProblem
from ...geometry import quaternion_from_matrix
from .model import Observations


#: Above this many (invariant-consistent) postures, mcb starts from a subset of this size.
START_POSTURES = 20


def board_pose_angle_gaps_deg(hand: np.ndarray, board: np.ndarray) -> np.ndarray:
    """Per posture: median over the others of ``|angle(A_ij) - angle(B_ij)|`` (eq. 30, X-free), degrees,
    with ``B_ij`` from the board poses' rotations (``refine.compact_point_angle_gaps_deg``: the same
    invariant on the compact points' relative rotations).

    ``A_ij = A_i^-1 A_j`` and ``B_ij = B_i B_j^-1`` rotate by the same angle for the true motion
    whatever ``X`` is; the angles come from quaternion dot products. Over every pair of a small set,
    over ``invariants.bounded_pairs`` (neighbours in time and random partners) of a large one.
    """
    qa = quaternion_from_matrix(hand[:, :3, :3])
    qb = quaternion_from_matrix(board[:, :3, :3])
    pairs = bounded_pairs(len(qa))
    i, j = pairs[:, 0], pairs[:, 1]
    angle_a = 2.0 * np.arccos(np.clip(np.abs(np.einsum("pi,pi->p", qa[i], qa[j])), 0.0, 1.0))
    # the angle of B_i B_j^-1 is the angle between R_Bi and R_Bj, as for A_i^-1 A_j
    angle_b = 2.0 * np.arccos(np.clip(np.abs(np.einsum("pi,pi->p", qb[i], qb[j])), 0.0, 1.0))
    return np.degrees(posture_medians(np.abs(angle_a - angle_b), pairs, len(qa)))


def varied_rotation_subset(hand: np.ndarray, candidates: np.ndarray, size: int) -> np.ndarray:
    """Indices (sorted) of ``size`` postures among ``candidates`` spread over the hand rotations.

    Farthest-point sampling on the rotation angle between hand orientations, from the posture
    nearest the mean orientation: relative motions between the chosen postures are then large and
    about varied axes, as mcb needs.
    """
    candidates = np.asarray(candidates)
    if len(candidates) <= size:
        return np.sort(candidates)
    q = quaternion_from_matrix(hand[candidates, :3, :3])
    mean = np.linalg.eigh(q.T @ q)[1][:, -1]
    chosen = [int(np.argmax(np.abs(q @ mean)))]
    dist = 2.0 * np.arccos(np.clip(np.abs(q @ q[chosen[0]]), 0.0, 1.0))
    while len(chosen) < size:
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, 2.0 * np.arccos(np.clip(np.abs(q @ q[nxt]), 0.0, 1.0)))
    return np.sort(candidates[chosen])


def _mcb_start(problem: HandEyeProblem, subset: np.ndarray) -> tuple[np.ndarray, dict]:
    """Algorithm 1 with selection by d_back (eq. 23), the paper's mcb, on the postures ``subset``."""
    from ..paper import solve_paper  # noqa: PLC0415
    from ..selection import least_d_back  # noqa: PLC0415

    x, details = solve_paper(problem.subset(subset), least_d_back)
    return x, {"method": "mcb", "postures": int(len(subset)), "candidates": details["candidates"],
               "selected_triplet": details["selected_triplet"], "criterion_value": float(details["criterion_value"])}


def _compact_residuals(problem: HandEyeProblem, x: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Mean distance per posture of ``A_i X c_ik`` from ``T c_k`` over the three compact points, mm."""
    c = problem.compact
    model = c.target_points @ target[:3, :3].T + target[:3, 3]
    return np.linalg.norm(fixed_points(problem.hand, x, c.points) - model[None], axis=-1).mean(axis=1)


def _start(problem: HandEyeProblem, obs: Observations, gap_flags: np.ndarray) -> tuple[np.ndarray, dict]:
    """mcb on (a spread subset of) the invariant-consistent postures; mcb on all of them, then the
    paper's MC, when that subset is degenerate."""
    from ...base import CalibrationError  # noqa: PLC0415
    from ..triplets import all_postures_solution  # noqa: PLC0415

    candidates = np.flatnonzero(~gap_flags)
    attempts = [varied_rotation_subset(obs.hand, candidates, START_POSTURES)]
    if len(candidates) > START_POSTURES:
        attempts.append(varied_rotation_subset(obs.hand, np.arange(problem.n), START_POSTURES))
    for subset in attempts:
        try:
            return _mcb_start(problem, subset)
        except (ValueError, CalibrationError, np.linalg.LinAlgError):
            continue
    return all_postures_solution(problem), {"method": "mc", "postures": problem.n}
