"""Robot configuration of a robtarget (``confdata``) and the inverse kinematics that respects it.

RAPID's ``confdata`` (RAPID reference, "Basic Characteristics", Robot configuration; data type
``confdata``) names which of the arm's solutions a robtarget means:

- ``cf1``, ``cf4``, ``cf6``: the quadrant of axes 1, 4 and 6, ``floor(angle / 90 deg)`` (0 is 0..90 deg,
  -1 is -90..0 deg);
- ``cfx`` (IRC5, serial six-axis robots): ``4 * behind + 2 * below + negative`` from the wrist centre
  behind axis 1 (in the plane axis 1 turns, the wrist centre on the far side of axis 1 from where the
  arm points), the wrist centre behind the lower arm (on the far side of the line through axes 2
  and 3), and axis 5 negative. 0 is the usual configuration (all axes at 0 deg).

:func:`solve_robtarget` finds the solutions of a flange pose from several seeds with the project's
forward kinematics (:class:`handeye.robot.kinematics.RobotModel`) and damped Newton steps
(:func:`follow`; the project's least-squares ``inverse_kinematics`` takes some 0.2 s a pose, too slow
for the samples of a linear move), adds the
wrist's equivalent solutions (axis 4 + 180, axis 5 negated, axis 6 + 180) and whole turns of axes 4
and 6 within their limits, and chooses: with the configuration check on (``ConfJ \\On``, the
default) the solution whose ``cf1, cf4, cf6, cfx`` are the robtarget's, nearest to where the arm
stands; with it off, the solution nearest to where the arm stands (``ConfJ \\Off``). What is not
modelled: ABB's rule that ``ConfL \\On`` also stops a linear move whose axes 1/4/6 turn more than
90 deg on the way (:mod:`~handeye.rapid.interpreter.builtins.moves` checks the end configuration).
"""

from __future__ import annotations

import math

import numpy as np

from scipy.spatial.transform import Rotation

from ...robot import RobotModel
from .errors import RapidFatalError

__all__ = ["confdata", "solve_robtarget", "solutions", "nearest", "follow"]

#: Seeds of the numerical solver besides the current joints and the robtarget's quadrants (deg).
_SEEDS = ((0, 0, 0, 0, 45, 0), (0, 10, 20, 0, 60, 0), (0, 20, 30, 0, -60, 180), (0, -10, 10, 90, 60, -90))
#: Two solutions closer than this (deg on every axis) are the same.
_SAME_DEG = 1e-3
#: The Newton solver: finite-difference probe, largest step per axis (deg), orientation weight (mm/rad).
_PROBE_DEG, _MAX_STEP_DEG, _LEVER_MM = 1e-5, 20.0, 500.0


def confdata(model: RobotModel, joints) -> tuple:
    """``(cf1, cf4, cf6, cfx)`` of controller angles ``joints`` (deg, shape (dof,))."""
    q = np.asarray(joints, float)
    points = model.chain_points(q)  # P(0) axis 1, P(1) axis 2, P(2) axis 3, P(4) the wrist centre
    wrist, shoulder, elbow = points[4], points[1], points[2]
    heading = np.array([math.cos(math.radians(q[0])), math.sin(math.radians(q[0])), 0.0])
    behind_axis1 = float(wrist @ heading) < 0.0
    lower_arm, to_wrist = elbow - shoulder, wrist - shoulder
    reach = np.array([lower_arm @ heading, lower_arm[2]]), np.array([to_wrist @ heading, to_wrist[2]])
    behind_lower_arm = float(reach[0][0] * reach[1][1] - reach[0][1] * reach[1][0]) > 0.0
    quadrant = [int(math.floor(round(q[i], 6) / 90.0)) for i in (0, 3, 5)]  # 0 deg within 1e-6 is quadrant 0
    return (*quadrant, 4 * behind_axis1 + 2 * behind_lower_arm + int(q[4] < 0.0))


def _equivalents(model: RobotModel, q: np.ndarray) -> list:
    """``q``, its wrist flip, and whole turns of axes 4 and 6, inside the joint limits."""
    flip = q.copy()
    flip[3] += 180.0 if q[3] <= 0 else -180.0
    flip[4] = -q[4]
    flip[5] += 180.0 if q[5] <= 0 else -180.0
    out = []
    for base in (q, flip):
        for t4 in (-360.0, 0.0, 360.0):
            for t6 in (-360.0, 0.0, 360.0):
                c = base.copy()
                c[3] += t4
                c[5] += t6
                if model.within_limits(c):
                    out.append(c)
    return out


def follow(model: RobotModel, flange, seed, iterations: int = 40):
    """Joints (deg) putting tool0 at ``flange`` ``(4, 4)``, by damped Newton steps from ``seed`` (the
    solution of the seed's branch), or None when they do not converge inside the joint limits.

    The forward model is the project's (:meth:`RobotModel.forward`, batched: the Jacobian's seven
    configurations in one call), so a step costs one call; a ``MoveL`` solves every sample from the one
    before. Residual: position (mm) and 500 mm x the rotation vector of the orientation error, as
    :func:`~handeye.robot.kinematics.inverse_kinematics` weighs them.
    """
    target = np.asarray(flange, float)
    goal = Rotation.from_matrix(target[:3, :3]).inv()
    q = np.asarray(seed, float).copy()
    probe = np.vstack([np.zeros(model.dof), np.eye(model.dof) * _PROBE_DEG])
    low, high = model.joint_limits_deg[:, 0], model.joint_limits_deg[:, 1]
    for _ in range(iterations):
        p, quat = model.forward(q + probe)
        r = np.hstack([p - target[:3, 3], _LEVER_MM * (goal * Rotation.from_quat(quat, scalar_first=True)).as_rotvec()])
        if np.linalg.norm(r[0, :3]) < 1e-4 and np.linalg.norm(r[0, 3:]) < _LEVER_MM * 1e-8:
            return q if model.within_limits(q) else None
        jacobian = (r[1:] - r[0]).T / _PROBE_DEG
        step = np.linalg.lstsq(jacobian, -r[0], rcond=1e-10)[0]
        q = np.clip(q + np.clip(step, -_MAX_STEP_DEG, _MAX_STEP_DEG), low - 1.0, high + 1.0)
    return None


def solutions(model: RobotModel, flange, seeds) -> list:
    """The distinct joint solutions (deg) that put tool0 at ``flange`` ``(4, 4)``, from ``seeds``."""
    target = np.asarray(flange, float)
    found: list = []
    for seed in seeds:
        q = follow(model, target, seed)
        if q is None:
            continue
        for c in _equivalents(model, q):
            p = model.forward_transform(c)
            if np.linalg.norm(p[:3, 3] - target[:3, 3]) > 1e-2 or np.abs(p[:3, :3] - target[:3, :3]).max() > 1e-5:
                continue
            if all(np.abs(c - f).max() > _SAME_DEG for f in found):
                found.append(c)
    return found


def nearest(candidates, current) -> np.ndarray:
    """The candidate whose largest axis move from ``current`` is the least."""
    here = np.asarray(current, float)
    return min(candidates, key=lambda c: (np.abs(c - here).max(), np.abs(c - here).sum()))


def _conf_seed(conf, current) -> np.ndarray:
    cf1, cf4, cf6, cfx = conf
    seed = np.asarray(current, float).copy()
    seed[0], seed[3], seed[5] = cf1 * 90 + 45, cf4 * 90 + 45, cf6 * 90 + 45
    seed[4] = -45.0 if int(cfx) % 2 else 45.0
    return seed


def solve_robtarget(model: RobotModel, flange, conf, current, check: bool, what: str) -> np.ndarray:
    """The joints (deg) a move to the flange pose ``flange`` ``(4, 4)`` goes to (see the module docstring).

    Raises
    ------
    RapidFatalError
        The pose is out of reach, or (``check``) no solution has the robtarget's configuration.
    """
    here = np.asarray(current, float)
    found = solutions(model, flange, [here, _conf_seed(conf, here), *_SEEDS])
    if not found:
        p = np.asarray(flange, float)[:3, 3]
        raise RapidFatalError(f"{what}: the position [{p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}] (flange, base frame) "
                              f"is outside the reach or the joint limits of the {model.name}")
    if not check:
        return nearest(found, here)
    wanted = tuple(int(round(v)) for v in conf)
    matching = [c for c in found if confdata(model, c) == wanted]
    if not matching:
        have = sorted({confdata(model, c) for c in found})
        raise RapidFatalError(f"{what}: no solution with the robtarget's configuration [{', '.join(map(str, wanted))}] "
                              f"(cf1, cf4, cf6, cfx); the pose is reached with {', '.join(map(str, map(list, have)))}: "
                              "fix the robconf, or switch the check off (ConfJ \\Off / ConfL \\Off)")
    return nearest(matching, here)
