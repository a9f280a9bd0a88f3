"""Planned postures that see part of a ChArUco board, when that spreads the rotations (issue 37).

A ChArUco view holds the corners it saw by id, so the planner need not insist on the whole board in
every camera: a view point aimed further off the board centre (the board near an image edge, a steeper
turn of the flange) may lose some corners and still fix the board's pose. After the whole-board draw,
:func:`widen_with_partial_views` draws such view points (the same cone, distance and roll, the aim
spread :data:`AIM_FACTOR` times wider), keeps those whose seen corners (in every camera of the head)
are at least :data:`MIN_IN_VIEW` of the board and pass :func:`~handeye.geometry.view_refusal` (the
minimum corners, the span that fixes the pose), and swaps one in for a whole-board posture only when
that raises the plan's rotation-axis spread (``calibration.quality_words``, the verdict's figure), the
best swap first, at most :data:`MAX_PARTIAL_SHARE` of the postures. A checkerboard or a circle grid
(``geometry.partial_ok`` false) is never planned partly out of view.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ...calibration import hand_axis_coverage
from ...geometry import partial_ok, view_refusal
from ...geometry import invert_transforms
from ...robot import RobotModel, ViewSampling, corners_in_view, sample_eye_in_hand_postures

__all__ = ["AIM_FACTOR", "MAX_PARTIAL_SHARE", "MIN_IN_VIEW", "PartialPosture", "in_view_fraction",
           "number_partial_postures", "widen_with_partial_views"]

#: Fewest of the board's corners a planned partial view must see in every camera.
MIN_IN_VIEW = 0.5
#: At most this share of the planned postures is partly out of view.
MAX_PARTIAL_SHARE = 0.3
#: The partial view points' aim spread, in multiples of ``plan.aim_mm`` (the board further off centre).
AIM_FACTOR = 3.0
#: A swap must raise the rotation-axis spread by more than this (deg).
MIN_GAIN_DEG = 0.5


@dataclass(frozen=True)
class PartialPosture:
    """A planned posture that sees part of the board.

    Attributes
    ----------
    joints_deg : ndarray, shape (k,)
    in_view : float
        Fraction of the board's corners every camera sees (nominal head), 0..1.
    spread_before_deg, spread_after_deg : float
        The plan's rotation-axis spread before and after this posture was swapped in.
    number : int or None
        Its posture number in the final plan (capture order, 0-based like the session's ``postures/NNN.yaml``
        and the capture's lines), once known.
    """

    joints_deg: np.ndarray
    in_view: float
    spread_before_deg: float
    spread_after_deg: float
    number: int | None = None

    def line(self) -> str:
        """The plan line: ``posture 7: board 70 % in view (ChArUco), widens the rotation spread from X to Y deg``."""
        return (f"posture {self.number}: board {100 * self.in_view:.0f} % in view (ChArUco), widens the rotation "
                f"spread from {self.spread_before_deg:.1f} to {self.spread_after_deg:.1f} deg")


def in_view_fraction(robot: RobotModel, joints, cam2tool0, board2base, corners, views, margin_px: float) -> np.ndarray:
    """Per posture ``(n,)``: the fraction of the board's corners ``(m, 3)`` every view sees."""
    cams = robot.forward_transform(np.atleast_2d(np.asarray(joints, float))) @ np.asarray(cam2tool0, float)
    target2cam = invert_transforms(cams) @ np.asarray(board2base, float)
    return np.array([corners_in_view(t, corners, views, margin_px).mean() for t in target2cam])


def _acceptor(board):
    """``accept_view(seen)``: part of the board in view, at least :data:`MIN_IN_VIEW` of it, enough to fix its pose."""
    ids = np.arange(board.count)

    def accept(seen) -> bool:
        seen = np.asarray(seen, bool)
        return bool(not seen.all() and seen.mean() >= MIN_IN_VIEW and not view_refusal(ids[seen], board))

    return accept


def _coverage_deg(hand) -> float:
    return float(hand_axis_coverage(hand, "tool0").spread_deg)


def widen_with_partial_views(robot: RobotModel, joints: np.ndarray, cam2tool0, board2base, board, corners, rng,
                             sampling: ViewSampling, views, start, veto=None, pose_veto=None,
                             candidates: int | None = None) -> tuple[np.ndarray, list]:
    """Swap whole-board postures for partial views of a ChArUco board where that spreads the rotations.

    Parameters
    ----------
    joints : ndarray, shape (n, k)
        The whole-board postures drawn.
    board : BoardGeometry
        Nothing changes unless it takes partial views (``geometry.partial_ok``).
    corners : ndarray, shape (m, 3)
        The board's corners in the target frame (index order = corner id).
    sampling, views, start, veto, pose_veto
        As the whole-board draw's (``robot.sample_eye_in_hand_postures``); the aim spread is widened.
    candidates : int, optional
        Partial view points to draw (default ``min(n, 12)``).

    Returns
    -------
    joints : ndarray, shape (n, k)
        The postures, some replaced (same order otherwise).
    partial : list of PartialPosture
        The swapped-in postures (``number`` unset), in the order they were swapped in.
    """
    joints = np.array(joints, float)  # a copy: the swaps below do not change the caller's draw
    n = len(joints)
    most = int(np.floor(MAX_PARTIAL_SHARE * n))
    if not partial_ok(board) or most < 1 or n < 3:
        return joints, []
    wide = replace(sampling, aim_mm=AIM_FACTOR * max(sampling.aim_mm, 1.0))
    m = candidates or min(n, 12)
    pool = sample_eye_in_hand_postures(robot, cam2tool0, board2base, corners, m, rng, wide, views, seed_joints=start,
                                       max_attempts=60 * m, veto=veto, min_count=0, pose_veto=pose_veto,
                                       accept_view=_acceptor(board))
    hand = robot.forward_transform(joints)
    pool_hand = robot.forward_transform(pool) if len(pool) else np.zeros((0, 4, 4))
    fractions = in_view_fraction(robot, pool, cam2tool0, board2base, corners, views, sampling.margin_px) if len(pool) else []
    replaced, left, swapped = set(), list(range(len(pool))), []
    spread = _coverage_deg(hand)
    while len(swapped) < most and left:
        best = None
        for c in left:
            for i in range(n):
                if i in replaced:
                    continue
                trial = hand.copy()
                trial[i] = pool_hand[c]
                gain = _coverage_deg(trial) - spread
                if gain > MIN_GAIN_DEG and (best is None or gain > best[0]):
                    best = (gain, c, i)
        if best is None:
            break
        gain, c, i = best
        hand[i], joints[i] = pool_hand[c], pool[c]
        swapped.append(PartialPosture(pool[c].copy(), float(fractions[c]), spread, spread + gain))
        spread += gain
        replaced.add(i)
        left.remove(c)
    return joints, swapped


def number_partial_postures(joints: np.ndarray, partial: list) -> list:
    """``partial`` with their numbers in the final ``joints`` (capture order, 0-based), in the order they were
    swapped in (each line's spread follows on from the last); those the cell's route repair dropped or
    replaced are left out."""
    out = []
    for p in partial:
        hits = np.flatnonzero(np.all(np.abs(np.asarray(joints, float) - p.joints_deg) < 1e-9, axis=1))
        if len(hits):
            out.append(replace(p, number=int(hits[0])))
    return out
