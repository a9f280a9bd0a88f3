"""The arm's kinematic parameters as the identification sees them: names, Jacobian columns, prior.

The deviations of a real arm from its DH table are, per axis ``i``, ``d_i`` and ``a_i`` (mm),
``alpha_i`` (deg) and the zero offset of controller axis ``i`` (deg: the axis stands this much
further than its controller angle). A zero offset enters the serial DH angles through the
controller's coupling (``serial = C @ controller``, the IRB 1400's parallel arm), so its Jacobian
column is the DH theta columns times ``C`` (``noise.kinematic_jacobian`` gives the DH columns).

The prior (the robot file's ``kinematic_prior: {length_mm, angle_deg}``: how far from its table an
arm of this kind may be, one sigma) makes the deviations fixed effects with a Gaussian prior, centred
on the table (deviation 0). Without the key: :data:`DEFAULT_PRIOR`.

Some deviations cannot be seen from hand-eye data at all, whatever the postures: those between the
base and axis 1 (``zero1``, ``d1``: a turn about and a shift along base z, the same as moving the
board, whose pose is unknown) and those after axis 6 (``zero6``, ``d6``, ``a6``, ``alpha6``: a
constant transform of the flange, the same as moving the camera on it, whose pose is unknown).
:data:`ABSORBED` says so in words; the identification finds them again numerically.
"""

from __future__ import annotations

import numpy as np

from ..base import parse_yaml, read_text_file
from ..robot import RobotModel

__all__ = ["KINDS", "DEFAULT_PRIOR", "parameter_names", "parameter_kinds", "parameter_jacobian", "robot_prior",
           "why_absorbed", "dh_deviation", "corrected_robot"]

#: The four parameters of each axis, in the order of the columns.
KINDS = ("d", "a", "alpha", "zero")

#: One-sigma prior of an arm's deviations from its table when its robot file says nothing:
#: lengths 0.5 mm, angles 0.1 deg (an uncalibrated arm of the IRB 1400's class).
DEFAULT_PRIOR = {"length_mm": 0.5, "angle_deg": 0.1}


def parameter_names(dof: int = 6) -> list[str]:
    """``d1, a1, alpha1, zero1, d2, ...``: ``4 dof`` names."""
    return [f"{kind}{axis}" for axis in range(1, dof + 1) for kind in KINDS]


def parameter_kinds(dof: int = 6) -> np.ndarray:
    """0 for a length (mm), 1 for an angle (deg), per parameter; ``(4 dof,)``."""
    return np.tile([0, 0, 1, 1], dof)


def parameter_jacobian(robot: RobotModel, joints_deg, dh_columns: np.ndarray | None = None) -> np.ndarray:
    """Local twist of the flange per unit of every parameter.

    Parameters
    ----------
    robot : RobotModel
    joints_deg : array-like, shape (n, k)
        Controller angles.
    dh_columns : ndarray, shape (n, 6, 4k), optional
        The DH columns already computed (``noise.kinematic_jacobian``, or that carried to another
        frame); default: computed here.

    Returns
    -------
    ndarray, shape (n, 6, 4k)
        Columns in :func:`parameter_names` order; the zero columns are ``theta`` columns times ``C``.
    """
    if dh_columns is None:
        from .noise import kinematic_jacobian  # noqa: PLC0415

        dh_columns = kinematic_jacobian(robot, joints_deg)[0]
    k = robot.dof
    out = np.array(dh_columns, float, copy=True)
    theta = dh_columns[:, :, 3::4]                    # (n, 6, k) per serial angle
    out[:, :, 3::4] = theta @ robot.coupling          # per controller zero: d serial / d controller = C
    return out


def robot_prior(robot_name: str | None) -> dict:
    """``kinematic_prior`` of the robot file (``length_mm``, ``angle_deg``), else :data:`DEFAULT_PRIOR`."""
    if robot_name is None:
        return dict(DEFAULT_PRIOR)
    from ..robot import robot_file  # noqa: PLC0415

    path = robot_file(str(robot_name))
    if path is None:
        return dict(DEFAULT_PRIOR)
    data = parse_yaml(read_text_file(path, "robot file", ValueError), path, ValueError) or {}
    prior = dict(DEFAULT_PRIOR)
    prior.update({key: float(value) for key, value in (data.get("kinematic_prior") or {}).items() if key in prior})
    return prior


#: Why a parameter can never be seen from hand-eye data (the camera pose ``X`` and the board pose ``T``
#: are unknowns of the fit).
ABSORBED = {
    "zero1": "a turn of axis 1's zero turns the whole arm about base z: the same as turning the board about base z",
    "d1": "a shift along axis 1 moves the whole arm along base z: the same as moving the board",
    "zero6": "a turn of axis 6's zero turns the flange about its own axis: the same as turning the camera about the "
             "flange axis",
    "d6": "a shift along the flange axis is absorbed by the tool frame (the camera pose)",
    "a6": "a shift of the flange across its axis is absorbed by the tool frame (the camera pose)",
    "alpha6": "a tilt of the flange is absorbed by the tool frame (the camera pose)",
}


def why_absorbed(name: str, partners: list[str] | None = None) -> str:
    """The words for a parameter the data cannot see; ``partners``: those it is degenerate with."""
    if name in ABSORBED:
        return ABSORBED[name]
    if partners:
        return (f"moves the flange exactly as a combination of {', '.join(partners)} and of the camera and board "
                "poses does at these postures (only that combination is seen)")
    return "moves the flange as a change of the camera and board poses does at these postures"


def dh_deviation(robot: RobotModel, values) -> np.ndarray:
    """The change of the DH table ``(k, 4)`` (d, a mm; alpha, theta deg) of parameter values ``(4k,)``."""
    v = np.asarray(values, float).reshape(robot.dof, 4)
    delta = v.copy()
    delta[:, 3] = robot.coupling @ v[:, 3]
    return delta


def corrected_robot(robot: RobotModel, values) -> RobotModel:
    """``robot`` with its DH table changed by the parameter values ``(4k,)`` (the identified arm)."""
    dh = robot.dh + dh_deviation(robot, values)
    rows = [(i + 1, j + 1, robot.coupling[i, j]) for i in range(robot.dof) for j in range(robot.dof)
            if i != j and robot.coupling[i, j] != 0]
    return RobotModel.from_dh(f"{robot.name} (identified)", dh, rows, robot.joint_limits_deg, robot.max_speed_deg_s)
