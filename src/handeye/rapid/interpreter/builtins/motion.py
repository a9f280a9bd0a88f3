"""Motion and positions: MoveAbsJ, CJointT, CRobT, CPos, and the world zones (WZBoxDef, WZCylDef,
WZSphDef, WZHomeJointDef, WZLimJointDef, WZLimSup, WZDOSet, WZEnable, WZDisable, WZFree).

``MoveAbsJ`` returns when the arm stands still at the target (every zone is treated as ``fine``:
the interpreter does not run ahead of a move). ``CRobT`` gives the TCP of ``\\Tool`` (default: the
tool of the last move, ``tool0`` at first) in ``\\WObj`` (default ``wobj0``) from the arm's flange
pose. A world zone instruction hands the zone to the motion binding, which supervises the moves.
"""

from __future__ import annotations

from ..configuration import confdata
from ..errors import RapidFatalError
from ..values import PREDEFINED, TYPES, Record, to_num
from . import builtin
from .geometry import xyz
from .moves import tcp_in

_EXTAX = {f"eax_{c}": 9e9 for c in "abcdef"}


def _arm(task):
    return task.bindings.need("motion", "the robot")


def _dict(record: Record) -> dict:
    return {k: (_dict(v) if isinstance(v, Record) else v) for k, v in record.fields.items()}


def _joints(target: Record) -> list:
    robax = target.fields["robax"].fields
    return [robax[f"rax_{i}"] for i in range(1, 7)]


@builtin("MoveAbsJ", "\\Conc, ToJointPos:jointtarget, \\ID:num, \\NoEOffs, Speed:speeddata, \\V:num, \\T:num, "
                     "Zone:zonedata, \\Z:num, Tool:tooldata, \\WObj:wobjdata, \\TLoad:loaddata")
def _moveabsj(task, a):
    _conc, target, _id, _noeoffs, speed, v, t, zone, z, tool, _wobj, _tload = a
    speed_data = _dict(speed)
    if v is not None:
        speed_data["v_tcp"] = v
    if t is not None:
        speed_data["time"] = t
    task.current_tool = tool
    _arm(task).move_joints(task, _joints(target), speed_data, _dict(zone), tool)


def _jointtarget(joints) -> Record:
    robax = Record(TYPES["robjoint"], {f"rax_{i}": to_num(v) for i, v in enumerate(joints, 1)})
    return Record(TYPES["jointtarget"], {"robax": robax, "extax": Record(TYPES["extjoint"], dict(_EXTAX))})


@builtin("CJointT", "\\TaskRef:num, \\TaskName:string", returns="jointtarget")
def _cjointt(task, a):
    return _jointtarget(_arm(task).joints())


def _tcp(task, tool, wobj) -> tuple:
    """Position and orientation of ``tool``'s TCP in ``wobj`` (flange pose from the arm)."""
    tool = tool if tool is not None else getattr(task, "current_tool", None) or PREDEFINED["tool0"][1]
    return tcp_in(_arm(task), tool, wobj, "CRobT")


def _confdata(task, joints) -> Record:
    """The configuration of ``joints`` (:func:`~handeye.rapid.interpreter.configuration.confdata`)."""
    values = confdata(_arm(task).model(), joints)
    return Record(TYPES["confdata"], {k: float(v) for k, v in zip(("cf1", "cf4", "cf6", "cfx"), values)})


@builtin("CRobT", "\\TaskRef:num, \\TaskName:string, \\Tool:tooldata, \\WObj:wobjdata", returns="robtarget")
def _crobt(task, a):
    p, q = _tcp(task, a[2], a[3])
    return Record(TYPES["robtarget"], {
        "trans": Record(TYPES["pos"], dict(zip("xyz", (to_num(v) for v in p)))),
        "rot": Record(TYPES["orient"], dict(zip(("q1", "q2", "q3", "q4"), (to_num(v) for v in q)))),
        "robconf": _confdata(task, _arm(task).joints()),
        "extax": Record(TYPES["extjoint"], dict(_EXTAX)),
    })


@builtin("CPos", "\\Tool:tooldata, \\WObj:wobjdata", returns="pos")
def _cpos(task, a):
    p, _ = _tcp(task, a[0], a[1])
    return Record(TYPES["pos"], dict(zip("xyz", (to_num(v) for v in p))))


# ---------------------------------------------------------------------------------------- world zones
def _side(inside: bool, outside: bool, what: str) -> str:
    if inside == outside:
        raise RapidFatalError(f"{what} needs exactly one of \\Inside and \\Outside")
    return "inside" if inside else "outside"


def _shape(handle, shape: dict) -> None:
    handle.state = shape


@builtin("WZBoxDef", "\\Inside, \\Outside, Shape:shapedata, LowPoint:pos, HighPoint:pos")
def _wzboxdef(task, a):
    inside, outside, shape, low, high = a
    lo, hi = xyz(low), xyz(high)
    if any(h - l < 10 for l, h in zip(lo, hi)):
        raise RapidFatalError("WZBoxDef: HighPoint must exceed LowPoint by at least 10 mm on every axis")
    _shape(shape, {"type": "box", "side": _side(inside, outside, "WZBoxDef"), "low": lo, "high": hi})


@builtin("WZCylDef", "\\Inside, \\Outside, Shape:shapedata, CentrePoint:pos, Radius:num, Height:num")
def _wzcyldef(task, a):
    inside, outside, shape, centre, radius, height = a
    if radius <= 0 or height == 0:
        raise RapidFatalError("WZCylDef: Radius must be > 0 and Height not 0")
    _shape(shape, {"type": "cylinder", "side": _side(inside, outside, "WZCylDef"), "centre": xyz(centre),
                   "radius": radius, "height": height})


@builtin("WZSphDef", "\\Inside, \\Outside, Shape:shapedata, CentrePoint:pos, Radius:num")
def _wzsphdef(task, a):
    inside, outside, shape, centre, radius = a
    if radius <= 0:
        raise RapidFatalError("WZSphDef: Radius must be > 0")
    _shape(shape, {"type": "sphere", "side": _side(inside, outside, "WZSphDef"), "centre": xyz(centre),
                   "radius": radius})


@builtin("WZHomeJointDef", "\\Inside, \\Outside, Shape:shapedata, MiddleJointVal:jointtarget, "
                           "DeltaJointVal:jointtarget")
def _wzhomejointdef(task, a):
    inside, outside, shape, middle, delta = a
    _shape(shape, {"type": "joints", "side": _side(inside, outside, "WZHomeJointDef"),
                   "low": [m - d for m, d in zip(_joints(middle), _joints(delta))],
                   "high": [m + d for m, d in zip(_joints(middle), _joints(delta))]})


@builtin("WZLimJointDef", "\\Inside, \\Outside, Shape:shapedata, LowJointVal:jointtarget, HighJointVal:jointtarget")
def _wzlimjointdef(task, a):
    inside, outside, shape, low, high = a
    _shape(shape, {"type": "joints", "side": _side(inside, outside, "WZLimJointDef"), "low": _joints(low),
                   "high": _joints(high)})


def _zone_ref(ref, what: str) -> Record:
    zone = ref.get()
    if not isinstance(zone, Record) or zone.type.name not in ("wztemporary", "wzstationary"):
        raise RapidFatalError(f"{what}: WorldZone must be a wztemporary or wzstationary")
    return zone


def _supervise(task, kind: str, temp, stat, ref, shape, **extra) -> None:
    what = "WZLimSup" if kind == "limit" else "WZDOSet"
    if bool(temp) == bool(stat):
        raise RapidFatalError(f"{what} needs exactly one of \\Temp and \\Stat")
    zone = _zone_ref(ref, what)
    if (zone.type.name == "wztemporary") != bool(temp):
        raise RapidFatalError(f"{what}: \\Temp goes with a wztemporary, \\Stat with a wzstationary")
    if shape.state is None:
        raise RapidFatalError(f"{what}: the shapedata is not defined (WZBoxDef ... first)")
    zones = task.__dict__.setdefault("world_zones", {})
    number = int(zone.fields["wz"]) or (max(zones, default=0) + 1)
    zone.fields["wz"] = float(number)
    zones[number] = {"kind": kind, "shape": dict(shape.state), "active": True, **extra}
    _arm(task).world_zone(number, zones[number])


@builtin("WZLimSup", "\\Temp, \\Stat, ref WorldZone:any, Shape:shapedata")
def _wzlimsup(task, a):
    _supervise(task, "limit", *a)


@builtin("WZDOSet", "\\Temp, \\Stat, ref WorldZone:any, \\Inside, \\Before, Shape:shapedata, Signal:signaldo, "
                    "SetValue:num")
def _wzdoset(task, a):
    temp, stat, ref, inside, before, shape, signal, value = a
    _supervise(task, "do", temp, stat, ref, shape, signal=signal, value=value,
               when="before" if before else "inside")


def _switch_zone(task, ref, what: str, active: bool | None) -> None:
    zone = _zone_ref(ref, what)
    zones = task.__dict__.setdefault("world_zones", {})
    number = int(zone.fields["wz"])
    if number not in zones:
        raise RapidFatalError(f"{what}: the world zone is not defined")
    if active is None:
        del zones[number]
        zone.fields["wz"] = 0.0
        _arm(task).world_zone(number, None)
        return
    zones[number]["active"] = active
    _arm(task).world_zone(number, zones[number])


@builtin("WZEnable", "ref WorldZone:any")
def _wzenable(task, a):
    _switch_zone(task, a[0], "WZEnable", True)


@builtin("WZDisable", "ref WorldZone:any")
def _wzdisable(task, a):
    _switch_zone(task, a[0], "WZDisable", False)


@builtin("WZFree", "ref WorldZone:any")
def _wzfree(task, a):
    _switch_zone(task, a[0], "WZFree", None)
