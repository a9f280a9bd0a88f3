"""The mock arm's kinematic truth given explicitly (``mock.arm`` of the station file).

Without it the true arm of the mock station is the nominal DH table with random errors
(``mock.kinematic_error_mm`` / ``_deg``, :func:`~handeye.mocks.station.perturbed_robot`). With it the
true arm is the nominal table changed by exactly these deviations and nothing else, so an
identification (``handeye calibrate --kinematics``) has a truth to compare with:

- ``joint_zero_deg`` (6 values, controller axes 1-6): each axis stands this much further than its
  controller angle says (a zero offset of the revolution counter / fine calibration). Through the
  coupling (``serial = C @ controller``) they change the DH theta offsets by ``C @ joint_zero_deg``.
- ``link_mm`` (``{d1: .., a3: .., ...}``): added to the DH table's ``d_i`` / ``a_i`` (mm).

This is the arm as it is, not what changed since the calibration (``mock.faults``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..robot import RobotModel

__all__ = ["ArmDeviations", "LINK_NAMES", "true_arm"]

#: The DH lengths ``link_mm`` may name: ``d1..d6`` and ``a1..a6``.
LINK_NAMES = tuple(f"{p}{i}" for i in range(1, 7) for p in ("d", "a"))


@dataclass(frozen=True)
class ArmDeviations:
    """Explicit deviations of the mock arm from its DH table.

    Attributes
    ----------
    joint_zero_deg : tuple of float, shape (k,)
        Controller-axis zero offsets, degrees (the arm is at ``controller angle + offset``).
    link_mm : dict of str to float
        DH length deviations by name (``d1``..``d6``, ``a1``..``a6``), mm.
    """

    joint_zero_deg: tuple = (0.0,) * 6
    link_mm: dict = field(default_factory=dict)

    def dh_deviation(self, nominal: RobotModel) -> np.ndarray:
        """The change of the DH table ``(k, 4)`` (d, a mm; alpha, theta deg)."""
        k = nominal.dof
        zero = np.zeros(k)
        zero[:len(self.joint_zero_deg)] = np.asarray(self.joint_zero_deg, float)[:k]
        delta = np.zeros((k, 4))
        delta[:, 3] = nominal.coupling @ zero
        for name, value in self.link_mm.items():
            column = {"d": 0, "a": 1}[name[0]]
            delta[int(name[1:]) - 1, column] += float(value)
        return delta


def true_arm(nominal: RobotModel, deviations: ArmDeviations) -> RobotModel:
    """The nominal robot changed by exactly ``deviations``."""
    dh = nominal.dh + deviations.dh_deviation(nominal)
    rows = [(i + 1, j + 1, nominal.coupling[i, j]) for i in range(nominal.dof) for j in range(nominal.dof)
            if i != j and nominal.coupling[i, j] != 0]
    return RobotModel.from_dh(f"{nominal.name} (true arm)", dh, rows, nominal.joint_limits_deg, nominal.max_speed_deg_s)
