"""Quaternions and poses as RAPID writes them (``q1`` the scalar part), for the math functions and CRobT."""

from __future__ import annotations

import math

from ..errors import RapidFatalError
from ..values import TYPES, Record, to_num

__all__ = ["quat", "orient", "pos", "pose", "xyz", "qmul", "qrot", "qconj", "pose_mult", "pose_inv", "normalised"]


def xyz(r: Record) -> tuple:
    f = r.fields
    return f["x"], f["y"], f["z"]


def quat(r: Record) -> tuple:
    f = r.fields
    return f["q1"], f["q2"], f["q3"], f["q4"]


def pos(values) -> Record:
    return Record(TYPES["pos"], dict(zip(("x", "y", "z"), (to_num(v) for v in values))))


def orient(values) -> Record:
    return Record(TYPES["orient"], dict(zip(("q1", "q2", "q3", "q4"), (to_num(v) for v in values))))


def pose(p, q) -> Record:
    return Record(TYPES["pose"], {"trans": pos(p), "rot": orient(q)})


def qmul(a, b) -> tuple:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def qconj(q) -> tuple:
    return q[0], -q[1], -q[2], -q[3]


def qrot(q, v) -> tuple:
    w, x, y, z = qmul(qmul(q, (0.0, *v)), qconj(q))
    return x, y, z


def normalised(q) -> tuple:
    norm = math.sqrt(sum(c * c for c in q))
    if norm == 0:
        raise RapidFatalError("NOrient: the orientation is zero")
    return tuple(c / norm for c in q)


def pose_mult(p1, q1, p2, q2) -> tuple:
    """``pose1 * pose2``: ``(position, quaternion)``."""
    r = qrot(q1, p2)
    return tuple(a + b for a, b in zip(p1, r)), qmul(q1, q2)


def pose_inv(p, q) -> tuple:
    c = qconj(q)
    return tuple(-v for v in qrot(c, p)), c
