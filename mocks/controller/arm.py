"""The simulated arm as the RAPID program sees it: joints, the flange pose, MoveAbsJ, world zones.

:class:`ArmBinding` is the interpreter's motion binding over a :class:`~handeye.mocks.robot.SimulatedRobot`:
``MoveAbsJ`` starts a synchronised move and waits (in simulated time, ``time_scale``) until the arm
stands still; the approved posture a target is (its index in the program's CONST jointtargets) goes
to the arrival hooks. World zones the program defines (``WZLimSup``) are checked along the move
(the tool's TCP, sampled along the joint path); a move into a forbidden zone is not started and the
program stops with the zone named, as motion supervision stops a controller.
"""

from __future__ import annotations

import numpy as np

from ...calibration.transforms import transform_from_pose
from ...rapid.interpreter import MotionBinding, RapidFatalError
from ..robot import ZoneViolation

__all__ = ["ArmBinding", "zone_violation", "PATH_SAMPLES"]

#: Points along a move at which the world zones are checked.
PATH_SAMPLES = 24


def _inside(shape: dict, joints, tcp) -> bool:
    kind = shape["type"]
    if kind == "joints":
        return all(lo <= j <= hi for j, lo, hi in zip(joints, shape["low"], shape["high"]))
    if kind == "box":
        return all(lo <= v <= hi for v, lo, hi in zip(tcp, shape["low"], shape["high"]))
    centre = np.asarray(shape["centre"], float)
    if kind == "sphere":
        return float(np.linalg.norm(tcp - centre)) <= shape["radius"]
    low, high = sorted((centre[2], centre[2] + shape["height"]))
    return float(np.hypot(*(tcp[:2] - centre[:2]))) <= shape["radius"] and low <= tcp[2] <= high


def zone_violation(zone: dict, joints, tcp) -> bool:
    """True when ``joints`` / the TCP position ``tcp`` (mm) break a limiting world zone."""
    inside = _inside(zone["shape"], joints, np.asarray(tcp, float))
    return inside if zone["shape"]["side"] == "inside" else not inside


class ArmBinding(MotionBinding):
    """The motion binding of a mock controller (see the module docstring).

    Parameters
    ----------
    robot : SimulatedRobot
        Its ``postures`` are the program's approved postures (set when a program is loaded);
        ``robot.world_zones`` receives the zones the program defines.
    """

    def __init__(self, robot):
        self.robot = robot

    def joints(self) -> list:
        return [float(v) for v in self.robot.current_joints]

    def flange(self) -> tuple:
        pose = self.robot.tool0_pose()
        return tuple(float(v) for v in pose.position_mm), tuple(float(v) for v in pose.quaternion_wxyz)

    def _posture(self, target) -> int:
        postures = self.robot.postures
        if len(postures):
            match = np.flatnonzero(np.all(np.abs(postures - target) <= 1e-6, axis=1))
            if match.size:
                return int(match[0]) + 1
        return 0

    def _tcp(self, joints, tool) -> np.ndarray:
        flange = self.robot.model.forward_transform(joints)
        frame = tool.fields["tframe"].fields
        t = [frame["trans"].fields[c] for c in "xyz"]
        q = [frame["rot"].fields[c] for c in ("q1", "q2", "q3", "q4")]
        return (flange @ transform_from_pose(t, q))[:3, 3]

    def _check_zones(self, target, tool) -> None:
        zones = [(n, z) for n, z in sorted(self.robot.world_zones.items()) if z["kind"] == "limit" and z["active"]]
        if not zones:
            return
        start = np.asarray(self.robot.current_joints, float)
        for s in np.linspace(0.0, 1.0, PATH_SAMPLES + 1)[1:]:
            joints = start + s * (target - start)
            tcp = self._tcp(joints, tool)
            for number, zone in zones:
                if zone_violation(zone, joints, tcp):
                    raise RapidFatalError(
                        f"MoveAbsJ to {np.round(target, 4).tolist()}: world zone {number} "
                        f"({zone['shape']['type']}, {zone['shape']['side']}) would be violated "
                        f"{'at the target' if s == 1.0 else 'on the way'}; the robot did not move")

    def move_joints(self, task, joints, speed, zone, tool) -> None:
        target = np.asarray(joints, float)
        self._check_zones(target, tool)
        try:
            self.robot.start_move(target, posture=self._posture(target))
        except (ValueError, ZoneViolation) as exc:
            # outside the joint limits, or the path would enter a volume of the simulated cell: the
            # controller's motion supervision stops the program (with the reason) before the arm moves
            raise RapidFatalError(f"MoveAbsJ: {exc}") from None
        while self.robot.is_moving:
            task.idle(max(min(self.robot.time_to_arrival(), 0.05), 0.0005))
        self.robot.update()

    def world_zone(self, number: int, zone) -> None:
        if zone is None:
            self.robot.world_zones.pop(number, None)
        else:
            self.robot.world_zones[number] = dict(zone)
