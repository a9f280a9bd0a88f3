"""The simulated arm as the RAPID program sees it: joints, the flange pose, MoveAbsJ, MoveJ, MoveL, world zones.

:class:`ArmBinding` is the interpreter's motion binding over a :class:`~handeye.mocks.robot.SimulatedRobot`:
``MoveAbsJ`` starts a synchronised move and waits (in simulated time, ``time_scale``) until the arm
stands still; the approved posture a target is (its index in the program's CONST jointtargets) goes
to the arrival hooks. World zones the program defines (``WZLimSup``) are checked along the move
(the tool's TCP, sampled along the joint path); a move into a forbidden zone is not started and the
program stops with the zone named, as motion supervision stops a controller. ``MoveJ`` and ``MoveL``
arrive as a sequence of joint configurations (a ``MoveL``: its samples along the TCP line), which
the arm checks against the cell in one call (:meth:`SimulatedRobot.start_path
<handeye.mocks.robot.SimulatedRobot.start_path>`) before it moves.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ...geometry import transform_from_pose
from ...rapid import MotionBinding, RapidFatalError
from ..robot import ZoneViolation
from .runner import RapidRecord

if TYPE_CHECKING:
    from ...rapid import Task
    from ...robot import RobotModel
    from ..robot import SimulatedRobot

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


def zone_violation(zone: dict, joints: Sequence[float], tcp: npt.ArrayLike) -> bool:
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

    def __init__(self, robot: SimulatedRobot):
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

    def model(self) -> RobotModel:
        return self.robot.model

    def _check_zones(self, path, tool, what: str) -> None:
        """World zones along the path: a single joint move sampled :data:`PATH_SAMPLES` times, a
        linear move at its samples (the TCP of ``tool``)."""
        zones = [(n, z) for n, z in sorted(self.robot.world_zones.items()) if z["kind"] == "limit" and z["active"]]
        if not zones:
            return
        target = path[-1]
        if len(path) == 1:
            start = np.asarray(self.robot.current_joints, float)
            path = start + np.linspace(0.0, 1.0, PATH_SAMPLES + 1)[1:, None] * (target - start)
        for i, joints in enumerate(path):
            tcp = self._tcp(joints, tool)
            for number, zone in zones:
                if zone_violation(zone, joints, tcp):
                    raise RapidFatalError(
                        f"{what} to {np.round(target, 4).tolist()}: world zone {number} "
                        f"({zone['shape']['type']}, {zone['shape']['side']}) would be violated "
                        f"{'at the target' if i == len(path) - 1 else 'on the way'}; the robot did not move")

    def move_joints(self, task: Task, joints: Sequence[float], speed: dict, zone: dict, tool: RapidRecord) -> None:
        self.move_path(task, [joints], speed, zone, tool, "MoveAbsJ")

    def move_path(self, task: Task, configurations: npt.ArrayLike, speed: dict, zone: dict, tool: RapidRecord,
                  what: str) -> None:
        path = np.asarray(configurations, float).reshape(-1, self.robot.model.dof)
        self._check_zones(path, tool, what)
        try:
            self.robot.start_path(path, posture=self._posture(path[-1]))
        except (ValueError, ZoneViolation) as exc:
            # outside the joint limits, or the path would enter a volume of the simulated cell: the
            # controller's motion supervision stops the program (with the reason) before the arm moves
            raise RapidFatalError(f"{what}: {exc}") from None
        while self.robot.is_moving:
            task.idle(max(min(self.robot.time_to_arrival(), 0.05), 0.0005))
        self.robot.update()

    def world_zone(self, number: int, zone: dict | None) -> None:
        if zone is None:
            self.robot.world_zones.pop(number, None)
        else:
            self.robot.world_zones[number] = dict(zone)
