"""The robot's base against the cell's keep-out volumes: checked once, since the base never moves.

The base's capsules (:attr:`RobotModel.link_bodies` on part 0) stand where the robot stands, so a
keep-out volume within the margin of them would refuse every posture, or, left out of the check as the
posture check leaves the base out, would hide a cabinet standing in the robot's foot. Volumes that lie
wholly at or below the robot's mounting plane (base z 0: the floor, a foundation, a pedestal's top)
carry the robot and are not measured (the base's envelope reaches below its foot).

Each capsule's axis is sampled at most :data:`BASE_STEP_MM` apart; a volume's signed distance is
1-Lipschitz, so the least sampled distance is at most half the spacing above the true one, and the
distance returned (the sampled one less half the spacing) is never above it. Lengths in mm.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np

from .cell import KeepOut
from .kinematics import RobotModel

__all__ = ["BASE_STEP_MM", "base_capsules", "base_clearances", "base_envelope", "carries_the_robot"]

#: Largest spacing of the samples along a base capsule's axis, mm.
BASE_STEP_MM = 0.5


def base_capsules(robot: RobotModel) -> list:
    """The base's capsules as ``(start (3,), end (3,), radius)`` in base, mm (empty when the robot file has none)."""
    return [(np.asarray(b.start_mm, float), np.asarray(b.end_mm, float), float(b.radius_mm))
            for b in robot.link_bodies if b.link == 0]


def base_envelope(robot: RobotModel) -> tuple[np.ndarray, np.ndarray] | None:
    """The axis-aligned box ``(low (3,), high (3,))`` around the base's capsules, mm, or None without any."""
    capsules = base_capsules(robot)
    if not capsules:
        return None
    low = np.min([np.minimum(a, b) - r for a, b, r in capsules], axis=0)
    high = np.max([np.maximum(a, b) + r for a, b, r in capsules], axis=0)
    return low, high


def carries_the_robot(volume: KeepOut) -> bool:
    """True for a volume wholly at or below the robot's mounting plane (base z 0): the floor, a foundation."""
    return volume.top_mm <= 0.0


def base_clearances(robot: RobotModel, volumes: Sequence[KeepOut]) -> list:
    """``[(volume, distance_mm)]``: how far the base is from each volume that does not carry the robot.

    Parameters
    ----------
    robot : RobotModel
    volumes : sequence
        Keep-out volumes in base (``robot.cell``).

    Returns
    -------
    list of (volume, float)
        In the order given; the distance (negative: the volume reaches into the base's envelope) is the
        sampled one less half the sample spacing, so never above the true distance. Empty without base
        capsules.
    """
    capsules = base_capsules(robot)
    if not capsules:
        return []
    samples = []
    for a, b, r in capsules:
        count = max(2, math.ceil(float(np.linalg.norm(b - a)) / BASE_STEP_MM) + 1)
        t = np.linspace(0.0, 1.0, count)[:, None]
        samples.append((a + t * (b - a), r, float(np.linalg.norm(b - a)) / (count - 1) / 2))
    out = []
    for volume in volumes:
        if carries_the_robot(volume):
            continue
        gap = min(float(np.min(volume.signed_distance(points))) - r - half for points, r, half in samples)
        out.append((volume, gap))
    return out
