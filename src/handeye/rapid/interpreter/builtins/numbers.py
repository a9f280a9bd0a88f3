"""Arithmetic functions: Abs, Round, Trunc, Sqrt, Pow, Exp, trigonometry in degrees, vectors and
orientations (VectMagn, DotProd, CrossProd, NOrient, OrientZYX, EulerZYX, PoseMult, PoseInv,
PoseVect), Dim."""

from __future__ import annotations

import math

from ..errors import RapidFatalError, RapidRuntimeError
from . import builtin
from .geometry import normalised, orient, pos, pose, pose_inv, pose_mult, qrot, quat, xyz

__all__ = ["round_half_away"]


def round_half_away(value: float, decimals: int = 0) -> float:
    """RAPID's Round: to ``decimals`` places, halves away from zero."""
    scale = 10.0 ** decimals
    return math.copysign(math.floor(abs(value) * scale + 0.5) / scale, value) + 0.0


def _decimals(value) -> int:
    if value is None:
        return 0
    if value != int(value) or not 0 <= value <= 9:
        raise RapidFatalError(f"\\Dec must be a whole number 0..9; got {value:g}")
    return int(value)


@builtin("Abs", "Value:num", returns="num")
def _abs(task, a):
    return abs(a[0])


@builtin("AbsDnum", "Value:dnum", returns="dnum")
def _absdnum(task, a):
    return abs(a[0])


@builtin("Round", "Val:num, \\Dec:num", returns="num")
def _round(task, a):
    return round_half_away(a[0], _decimals(a[1]))


@builtin("Trunc", "Val:num, \\Dec:num", returns="num")
def _trunc(task, a):
    scale = 10.0 ** _decimals(a[1])
    return math.trunc(a[0] * scale) / scale + 0.0


@builtin("Sqrt", "Value:num", returns="num")
def _sqrt(task, a):
    if a[0] < 0:
        raise RapidRuntimeError("ERR_ARGVALERR", f"Sqrt of a negative number ({a[0]:g})")
    return math.sqrt(a[0])


@builtin("Pow", "Base:num, Exponent:num", returns="num")
def _pow(task, a):
    try:
        return math.pow(a[0], a[1])
    except (ValueError, OverflowError):
        raise RapidRuntimeError("ERR_ARGVALERR", f"Pow({a[0]:g}, {a[1]:g})") from None


@builtin("Exp", "Exponent:num", returns="num")
def _exp(task, a):
    try:
        return math.exp(a[0])
    except OverflowError:
        raise RapidRuntimeError("ERR_OVERFLOW", f"Exp({a[0]:g})") from None


for _name, _fn in (("Sin", math.sin), ("Cos", math.cos), ("Tan", math.tan)):
    builtin(_name, "Angle:num", returns="num")(lambda task, a, fn=_fn: fn(math.radians(a[0])))
for _name, _fn in (("ASin", math.asin), ("ACos", math.acos), ("ATan", math.atan)):
    def _inverse(task, a, fn=_fn, name=_name):
        try:
            return math.degrees(fn(a[0]))
        except ValueError:
            raise RapidRuntimeError("ERR_ARGVALERR", f"{name}({a[0]:g})") from None
    builtin(_name, "Value:num", returns="num")(_inverse)


@builtin("ATan2", "Y:num, X:num", returns="num")
def _atan2(task, a):
    return math.degrees(math.atan2(a[0], a[1]))


@builtin("VectMagn", "Vector:pos", returns="num")
def _vectmagn(task, a):
    return math.sqrt(sum(v * v for v in xyz(a[0])))


@builtin("DotProd", "Vector1:pos, Vector2:pos", returns="num")
def _dotprod(task, a):
    return sum(x * y for x, y in zip(xyz(a[0]), xyz(a[1])))


@builtin("CrossProd", "Vector1:pos, Vector2:pos", returns="pos")
def _crossprod(task, a):
    (x1, y1, z1), (x2, y2, z2) = xyz(a[0]), xyz(a[1])
    return pos((y1 * z2 - z1 * y2, z1 * x2 - x1 * z2, x1 * y2 - y1 * x2))


@builtin("NOrient", "Rotation:orient", returns="orient")
def _norient(task, a):
    return orient(normalised(quat(a[0])))


@builtin("OrientZYX", "ZAngle:num, YAngle:num, XAngle:num", returns="orient")
def _orientzyx(task, a):
    halves = [math.radians(v) / 2 for v in a]
    (cz, sz), (cy, sy), (cx, sx) = [(math.cos(h), math.sin(h)) for h in halves]
    return orient((cz * cy * cx + sz * sy * sx, cz * cy * sx - sz * sy * cx,
                   cz * sy * cx + sz * cy * sx, sz * cy * cx - cz * sy * sx))


@builtin("EulerZYX", "\\X, \\Y, \\Z, Rotation:orient", returns="num")
def _eulerzyx(task, a):
    want_x, want_y, want_z, rotation = a
    if [want_x, want_y, want_z].count(True) != 1:
        raise RapidFatalError("EulerZYX needs exactly one of \\X, \\Y, \\Z")
    w, x, y, z = normalised(quat(rotation))
    if want_z:
        return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    if want_y:
        return math.degrees(math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x)))))
    return math.degrees(math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))


def _pose_parts(p):
    return xyz(p.fields["trans"]), quat(p.fields["rot"])


@builtin("PoseMult", "Pose1:pose, Pose2:pose", returns="pose")
def _posemult(task, a):
    return pose(*pose_mult(*_pose_parts(a[0]), *_pose_parts(a[1])))


@builtin("PoseInv", "Pose:pose", returns="pose")
def _poseinv(task, a):
    return pose(*pose_inv(*_pose_parts(a[0])))


@builtin("PoseVect", "Pose:pose, Pos:pos", returns="pos")
def _posevect(task, a):
    p, q = _pose_parts(a[0])
    return pos(tuple(u + v for u, v in zip(p, qrot(q, xyz(a[1])))))


@builtin("Dim", "ref ArrPar:any, DimNo:num", returns="num")
def _dim(task, a):
    value, dimension = a[0].get(), a[1]
    if dimension != int(dimension) or dimension < 1:
        raise RapidFatalError(f"Dim: DimNo must be 1, 2 or 3; got {dimension:g}")
    for _ in range(int(dimension) - 1):
        if not isinstance(value, list) or not value:
            raise RapidFatalError(f"Dim: the array has fewer than {int(dimension)} dimensions")
        value = value[0]
    if not isinstance(value, list):
        raise RapidFatalError("Dim: not an array")
    return float(len(value))
