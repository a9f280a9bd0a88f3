"""The hand-eye problem in one frame-neutral form.

Eye-in-hand (camera on the flange): the hand pose is ``tool02base`` and the unknown ``X`` is
``cam2tool0``; the board is fixed in ``base``. Eye-to-hand (camera fixed, board on the flange): the
hand pose is ``base2tool0`` and ``X`` is ``cam2base``; the board is fixed in ``tool0``. In both cases

    fixed_points = hand_i @ X @ points_cam_i          for every posture i,

so one solver serves both; ``world`` below is the frame the board is fixed in.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .compact_points import CompactPoints
from ..geometry import invert_transforms

__all__ = ["EYE_IN_HAND", "EYE_TO_HAND", "SETUPS", "MIN_POSTURES", "HandEyeProblem", "hand_poses"]

EYE_IN_HAND = "eye_in_hand"
EYE_TO_HAND = "eye_to_hand"
SETUPS = (EYE_IN_HAND, EYE_TO_HAND)
#: The fewest postures any method solves from (three give two independent motions).
MIN_POSTURES = 3


def hand_poses(tool02base: ArrayLike, setup: str) -> np.ndarray:
    """Hand poses ``(n, 4, 4)`` of the frame-neutral problem for a setup."""
    if setup == EYE_IN_HAND:
        return np.asarray(tool02base, dtype=float)
    if setup == EYE_TO_HAND:
        return invert_transforms(tool02base)
    raise ValueError(f"unknown setup {setup!r}; use one of {', '.join(SETUPS)}")


@dataclass(frozen=True)
class HandEyeProblem:
    """Everything a solver needs, as arrays.

    Attributes
    ----------
    setup : str
        ``eye_in_hand`` or ``eye_to_hand``.
    hand : ndarray, shape (n, 4, 4)
        Hand poses (``tool02base`` or ``base2tool0``), mm.
    compact : CompactPoints
        Three points per posture in the camera frame and the board poses ``target2cam``.
    points_cam : ndarray, shape (n, m, 3)
        The full measured point set per posture (the compact points when no corners were given).
    posture_ids : ndarray of int, shape (n,)
        Posture indices as written in the session.
    target_points : ndarray, shape (m, 3) or None
        The full point set in the target frame, when known (board grid).
    joints_deg : ndarray, shape (n, k) or None
        Controller angles of every posture when the session holds them and names its robot
        (the ML estimator propagates joint noise through the robot's flange Jacobian).
    robot : str or None
        The robot model of ``joints_deg``.
    excluded : dict
        ``{posture index: reason}`` of gross postures left out before solving
        (``consistency.consistent_majority``); ``solve.calibrate`` solves without them and reports
        them with the outliers.
    """

    setup: str
    hand: np.ndarray
    compact: CompactPoints
    points_cam: np.ndarray
    posture_ids: np.ndarray
    target_points: np.ndarray | None = None
    notes: dict = field(default_factory=dict)
    joints_deg: np.ndarray | None = None
    robot: str | None = None
    excluded: dict = field(default_factory=dict)
    #: ``(n, m)`` bool: which corners each posture saw (partial views of a ChArUco board; the others in
    #: ``points_cam`` are the seen subset's rigid board fit); ``None``: every corner was seen.
    seen: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(self.hand.shape[0])

    @property
    def excluded_mask(self) -> np.ndarray:
        """Boolean mask ``(n,)`` of the postures in :attr:`excluded`."""
        return np.array([int(i) in self.excluded for i in self.posture_ids], dtype=bool)

    @property
    def target2cam(self) -> np.ndarray:
        return self.compact.target2cam

    def subset(self, keep: ArrayLike) -> "HandEyeProblem":
        """The problem restricted to the postures ``keep`` (boolean mask or index array)."""
        keep = np.asarray(keep)
        c = self.compact
        compact = CompactPoints(c.points[keep], c.target_points, c.target2cam[keep], c.plane_rms_mm[keep], c.square_mm)
        joints = None if self.joints_deg is None else self.joints_deg[keep]
        ids = self.posture_ids[keep]
        excluded = {i: reason for i, reason in self.excluded.items() if i in {int(k) for k in ids}}
        return HandEyeProblem(self.setup, self.hand[keep], compact, self.points_cam[keep],
                              ids, self.target_points, dict(self.notes), joints, self.robot, excluded,
                              None if self.seen is None else self.seen[keep])
