"""Do a session's joint angles reproduce its flange poses?

A posture holds both the controller's joint angles (``joints_deg``) and its flange pose
(``tool0_in_base``). The default estimator models the robot's noise through the joints (the flange
Jacobian, the arm's DH deviations) only when the robot model's forward kinematics of the joints land
on the flange poses (:data:`JOINT_MATCH_MM`, :data:`JOINT_MATCH_DEG`); ``handeye verify`` revisits
postures by their joint angles and compares under that same model. A posture whose two readings
disagree (an edited file, the joints of another posture, another robot model) is named here, so
``calibrate`` can warn and ``verify`` refuse instead of either silently changing its noise model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .noise import twist_between

if TYPE_CHECKING:
    from ..robot import RobotModel
    from .session import Session

__all__ = ["JOINT_MATCH_DEG", "JOINT_MATCH_MM", "JointMismatch", "joint_mismatch", "session_joint_mismatch"]

#: FK(joints) must match the session's flange pose this well (position, mm) for the joint model.
JOINT_MATCH_MM = 5.0
#: ... and this well (rotation, deg).
JOINT_MATCH_DEG = 0.5


@dataclass(frozen=True)
class JointMismatch:
    """The postures whose joint angles do not reproduce their flange poses.

    Attributes
    ----------
    postures : tuple of int
        Their posture numbers.
    gap_mm, gap_deg : ndarray, shape (k,)
        How far FK(joints) is from each one's flange pose (position, rotation).
    total : int
        Postures compared.
    robot : str
        The robot model whose kinematics were used.
    """

    postures: tuple
    gap_mm: np.ndarray
    gap_deg: np.ndarray
    total: int
    robot: str

    def line(self) -> str:
        """One phrase naming the postures and the largest gap."""
        which = "posture" if len(self.postures) == 1 else "postures"
        return (f"the joint angles of {which} {', '.join(map(str, self.postures))} ({len(self.postures)} of "
                f"{self.total}) do not reproduce their flange poses (tool0_in_base) with the {self.robot} kinematics: "
                f"up to {float(np.max(self.gap_mm)):.1f} mm / {float(np.max(self.gap_deg)):.2f} deg apart "
                f"(at most {JOINT_MATCH_MM:g} mm / {JOINT_MATCH_DEG:g} deg)")


def joint_mismatch(robot: RobotModel, joints_deg: ArrayLike, tool02base: ArrayLike, posture_ids: ArrayLike | None = None) -> JointMismatch | None:
    """The postures whose ``robot.forward_transform(joints_deg)`` is off their flange pose, or None.

    Parameters
    ----------
    robot : RobotModel
    joints_deg : array_like, shape (n, dof)
    tool02base : ndarray, shape (n, 4, 4)
        The flange poses (mm).
    posture_ids : array_like of int, shape (n,), optional
        Their numbers (default 0 .. n-1).
    """
    joints = np.asarray(joints_deg, float)
    gap = twist_between(robot.forward_transform(joints), np.asarray(tool02base, float))
    gap_mm = np.linalg.norm(gap[:, :3], axis=1)
    gap_deg = np.degrees(np.linalg.norm(gap[:, 3:], axis=1))
    bad = (gap_mm > JOINT_MATCH_MM) | (gap_deg > JOINT_MATCH_DEG)
    if not bad.any():
        return None
    ids = np.arange(len(joints)) if posture_ids is None else np.asarray(posture_ids)
    return JointMismatch(tuple(int(i) for i in ids[bad]), gap_mm[bad], gap_deg[bad], len(joints), robot.name)


def session_joint_mismatch(session: Session) -> JointMismatch | None:
    """:func:`joint_mismatch` over a session's postures that hold both readings (None when the session
    names no robot model that loads, or no posture holds both)."""
    from ..robot import load_robot  # noqa: PLC0415

    if not session.robot:
        return None
    try:
        robot = load_robot(session.robot)
    except ValueError:
        return None
    both = [p for p in session.postures if p.joints_deg is not None and p.tool0_in_base is not None
            and np.shape(p.joints_deg) == (robot.dof,)]
    if not both:
        return None
    return joint_mismatch(robot, [p.joints_deg for p in both], np.array([p.tool0_in_base for p in both]),
                          [p.index for p in both])
