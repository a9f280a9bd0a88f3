"""The moves a station engineer adds: MoveJ, MoveL, ConfJ, ConfL, SingArea, VelSet, and the target
functions Offs and RelTool.

A robtarget is the TCP of the move's tool in its work object (``wobjdata``: ``uframe * oframe``) with
a configuration (``robconf``). Its joints come from :mod:`~handeye.rapid.interpreter.configuration`
(the configuration rules, ``ConfJ``/``ConfL``). ``MoveJ`` moves all axes joint-interpolated to them;
``MoveL`` moves the TCP along the straight line (and the orientation by slerp): the line is sampled at
most :data:`LINE_STEP_MM` apart (and :data:`LINE_STEP_DEG` of orientation), every sample through the
inverse kinematics from the one before, and the arm follows the samples' configurations. The motion
binding checks the whole path (world zones, the cell) before the arm moves; a move that would
violate it stops the program at its line, as motion supervision stops a controller.

What the interpreter does with the rest of a move's arguments: ``speeddata`` (or ``\\V``, ``\\T``) is
checked (a speed must be > 0) but the mock arm moves at its own speed; every zone, ``fine`` or not,
ends at rest (the interpreter does not run ahead of a move); ``\\Conc``, ``\\ID``, ``\\Z``, ``\\TLoad``
are accepted and change nothing. ``SingArea \\Wrist`` lets a linear move pass a wrist singularity
(axes 4 and 6 may turn fast between two samples); with ``SingArea \\Off`` (the default) such a
move stops the program, naming the singularity.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import math

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ....geometry import transform_from_pose
from ..configuration import confdata, follow, solve_robtarget
from ..errors import RapidFatalError
from ..values import PREDEFINED, TYPES, Record, copy_value, to_num
from . import builtin
from .geometry import pose_inv, pose_mult, qmul, qrot, quat, xyz

if TYPE_CHECKING:
    from ..runtime import Task

__all__ = ["LINE_STEP_MM", "LINE_STEP_DEG", "line_samples", "flange_of", "motion_settings", "tcp_in"]

#: Largest distance between two samples of a linear move, mm, and of its orientation, deg.
LINE_STEP_MM, LINE_STEP_DEG = 5.0, 2.0
#: A linear move's axis may turn at most this much between two samples (more: a singularity), deg.
_JUMP_DEG = 10.0
#: Samples of one linear move at most (a longer line is sampled more coarsely).
_MAX_SAMPLES = 600

_SPEED = ("v_tcp", "v_ori", "v_leax", "v_reax")


def motion_settings(task: Task) -> dict:
    """The task's ConfJ, ConfL and SingArea state (both checks on, no wrist interpolation at start)."""
    return task.__dict__.setdefault("motion_settings", {"confj": True, "confl": True, "wrist": False,
                                                        "override": 100.0, "max_tcp": 5000.0})


def _arm(task):
    return task.bindings.need("motion", "the robot")


def _frame(pose_record: Record) -> tuple:
    return xyz(pose_record.fields["trans"]), quat(pose_record.fields["rot"])


def _user_frame(tool, wobj, what: str) -> tuple:
    tool = tool if tool is not None else PREDEFINED["tool0"][1]
    wobj = wobj if wobj is not None else PREDEFINED["wobj0"][1]
    if not tool.fields["robhold"] or wobj.fields["robhold"]:
        raise RapidFatalError(f"{what}: only tools on the robot (robhold TRUE) and fixed work objects are supported")
    return _frame(tool.fields["tframe"]), pose_mult(*_frame(wobj.fields["uframe"]), *_frame(wobj.fields["oframe"]))


def flange_of(target_pose: tuple, tool, wobj, what: str) -> np.ndarray:
    """tool0 in base ``(4, 4)`` for the TCP of ``tool`` at ``target_pose`` ``(position, quaternion)`` in ``wobj``."""
    tframe, user = _user_frame(tool, wobj, what)
    p, q = pose_mult(*pose_mult(*user, *target_pose), *pose_inv(*tframe))
    return transform_from_pose(p, q)


def _target_pose(target: Record) -> tuple:
    return xyz(target.fields["trans"]), quat(target.fields["rot"])


def _conf(target: Record) -> tuple:
    c = target.fields["robconf"].fields
    return c["cf1"], c["cf4"], c["cf6"], c["cfx"]


def _speed(speed: Record, v, t, what: str) -> dict:
    data = {k: speed.fields[k] for k in _SPEED}
    if v is not None:
        data["v_tcp"] = v
    if t is not None:
        data["time"] = t
    if data["v_tcp"] <= 0 or (t is not None and t <= 0):
        raise RapidFatalError(f"{what}: the speed must be > 0 (speeddata v_tcp, \\V or \\T)")
    return data


def _zone(zone: Record) -> dict:
    return dict(zone.fields)


_MOVE = ("\\Conc, ToPoint:robtarget, \\ID:num, Speed:speeddata, \\V:num, \\T:num, Zone:zonedata, \\Z:num, "
         "\\Inpos:num, Tool:tooldata, \\WObj:wobjdata, \\TLoad:loaddata")


@builtin("MoveJ", _MOVE)
def _movej(task, a):
    _conc, target, _id, speed, v, t, zone, _z, _inpos, tool, wobj, _tload = a
    arm = _arm(task)
    flange = flange_of(_target_pose(target), tool, wobj, "MoveJ")
    joints = solve_robtarget(arm.model(), flange, _conf(target), arm.joints(), motion_settings(task)["confj"], "MoveJ")
    task.current_tool = tool
    arm.move_path(task, joints[None], _speed(speed, v, t, "MoveJ"), _zone(zone), tool, "MoveJ")


@builtin("MoveL", _MOVE)
def _movel(task, a):
    _conc, target, _id, speed, v, t, zone, _z, _inpos, tool, wobj, _tload = a
    arm = _arm(task)
    settings = motion_settings(task)
    model = arm.model()
    path = line_samples(tcp_in(arm, tool, wobj, "MoveL"), _target_pose(target))
    joints = _follow_line(model, path, arm.joints(), tool, wobj, settings["wrist"])
    end = confdata(model, joints[-1])
    wanted = tuple(int(round(c)) for c in _conf(target))
    if settings["confl"] and end != wanted:
        raise RapidFatalError(f"MoveL: the line ends in configuration {list(end)} (cf1, cf4, cf6, cfx), the "
                              f"robtarget has {list(wanted)}; the robot did not move (fix the robconf, or ConfL \\Off)")
    task.current_tool = tool
    arm.move_path(task, joints, _speed(speed, v, t, "MoveL"), _zone(zone), tool, "MoveL")


def tcp_in(arm, tool, wobj, what: str) -> tuple:
    """Where the TCP of ``tool`` is in ``wobj`` now, ``(position, quaternion)`` (from the arm's flange pose)."""
    tframe, user = _user_frame(tool, wobj, what)
    p, q = arm.flange()
    return pose_mult(*pose_inv(*user), *pose_mult(tuple(p), tuple(q), *tframe))


def line_samples(start: tuple, end: tuple) -> list:
    """Poses ``(position, quaternion)`` along the straight line from ``start`` to ``end`` (both included),
    at most :data:`LINE_STEP_MM` and :data:`LINE_STEP_DEG` apart; the orientation by slerp."""
    p0, p1 = np.asarray(start[0], float), np.asarray(end[0], float)
    rotations = Rotation.from_quat([start[1], end[1]], scalar_first=True)
    turn = math.degrees((rotations[0].inv() * rotations[1]).magnitude())
    count = int(min(_MAX_SAMPLES, max(1, math.ceil(max(np.linalg.norm(p1 - p0) / LINE_STEP_MM,
                                                            turn / LINE_STEP_DEG)))))
    s = np.linspace(0.0, 1.0, count + 1)
    quats = Slerp([0.0, 1.0], rotations)(s).as_quat(scalar_first=True)
    return [(tuple(p0 + k * (p1 - p0)), tuple(q)) for k, q in zip(s, quats)]


def _follow_line(model, path: list, current, tool, wobj, wrist: bool) -> np.ndarray:
    """The joints ``(n, dof)`` of every sample after the first, each solved from the one before."""
    previous, out = np.asarray(current, float), []
    for i, sample in enumerate(path[1:], 1):
        joints = follow(model, flange_of(sample, tool, wobj, "MoveL"), previous)
        if joints is None:
            p = sample[0]
            raise RapidFatalError(f"MoveL: the line leaves the reach or the joint limits of the {model.name} at "
                                  f"{i / (len(path) - 1):.0%} of the move ([{p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}] in the "
                                  "work object); the robot did not move")
        jump = np.abs(joints - previous)
        if not wrist:
            jump_axes = np.flatnonzero(jump > _JUMP_DEG)
        else:
            jump_axes = np.flatnonzero(np.delete(jump, [3, 5]) > _JUMP_DEG)
        if len(jump_axes):
            axis = int(jump_axes[0]) + 1
            raise RapidFatalError(f"MoveL: the line passes a singularity at {i / (len(path) - 1):.0%} of the move "
                                  f"(axis {axis} turns {jump[axis - 1]:.0f} deg between two points 5 mm apart); the "
                                  "robot did not move (SingArea \\Wrist lets the wrist pass, or use MoveJ)")
        out.append(joints)
        previous = joints
    return np.array(out)


@builtin("VelSet", "Override:num, Max:num")
def _velset(task, a):
    """The speed override (percent) and the highest TCP speed (mm/s) of the moves that follow: checked and
    kept (:func:`motion_settings`); the mock arm moves at its own speed."""
    override, highest = a
    if not 0 < override <= 100 or highest <= 0:
        raise RapidFatalError(f"VelSet {override:g}, {highest:g}: the override must be 0 < % <= 100 and Max > 0 mm/s")
    motion_settings(task).update(override=float(override), max_tcp=float(highest))


@builtin("ConfJ", "\\On, \\Off")
def _confj(task, a):
    motion_settings(task)["confj"] = _on_off(a, "ConfJ")


@builtin("ConfL", "\\On, \\Off")
def _confl(task, a):
    motion_settings(task)["confl"] = _on_off(a, "ConfL")


def _on_off(a, what: str) -> bool:
    on, off = a
    if on == off:
        raise RapidFatalError(f"{what} takes one of \\On and \\Off")
    return bool(on)


@builtin("SingArea", "\\Wrist, \\LockAxis4, \\Off")
def _singarea(task, a):
    wrist, lock4, off = a
    if int(wrist) + int(lock4) + int(off) != 1:
        raise RapidFatalError("SingArea takes one of \\Wrist, \\LockAxis4 and \\Off")
    if lock4:
        raise RapidFatalError("SingArea \\LockAxis4 is not supported by the interpreter (use \\Wrist or \\Off)")
    motion_settings(task)["wrist"] = bool(wrist)


# ---------------------------------------------------------------------------------------- target functions
def _moved(point: Record, position, rotation=None) -> Record:
    out = copy_value(point)
    out.fields["trans"] = Record(TYPES["pos"], dict(zip("xyz", (to_num(v) for v in position))))
    if rotation is not None:
        out.fields["rot"] = Record(TYPES["orient"], dict(zip(("q1", "q2", "q3", "q4"), (to_num(v) for v in rotation))))
    return out


@builtin("Offs", "Point:robtarget, XOffset:num, YOffset:num, ZOffset:num", returns="robtarget")
def _offs(task, a):
    point, dx, dy, dz = a
    x, y, z = xyz(point.fields["trans"])
    return _moved(point, (x + dx, y + dy, z + dz))


def _axis_turn(axis: int, degrees: float) -> tuple:
    half = math.radians(degrees) / 2.0
    q = [math.cos(half), 0.0, 0.0, 0.0]
    q[1 + axis] = math.sin(half)
    return tuple(q)


@builtin("RelTool", "Point:robtarget, Dx:num, Dy:num, Dz:num, \\Rx:num, \\Ry:num, \\Rz:num", returns="robtarget")
def _reltool(task, a):
    """Displaced in the tool's own frame; turned about the tool's x, then the new y, then the new z."""
    point, dx, dy, dz, rx, ry, rz = a
    p, q = xyz(point.fields["trans"]), quat(point.fields["rot"])
    position = tuple(c + d for c, d in zip(p, qrot(q, (dx, dy, dz))))
    for axis, angle in enumerate((rx, ry, rz)):
        if angle is not None:
            q = qmul(q, _axis_turn(axis, angle))
    return _moved(point, position, q)
