"""Distances between capsules: the closest points of two segments, and of a point and a segment, vectorised.

A capsule is a segment with a radius; two capsules are apart by the distance of their segments minus
both radii (negative: they overlap). Used by the self-collision check (``robot.clearance``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["point_segment_distance", "segment_distance"]

_TINY = 1e-12


def point_segment_distance(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Distance of points ``p`` from segments ``a b``, all ``(..., 3)`` broadcast together; ``(...)``."""
    p, a, b = (np.asarray(x, float) for x in (p, a, b))
    d, offset = b - a, p - a
    # dot products of the last axis by einsum: far quicker than sum over an axis of 3 on large batches
    t = np.clip(np.einsum("...i,...i->...", offset, d) / np.maximum(np.einsum("...i,...i->...", d, d), _TINY), 0.0, 1.0)
    away = offset - t[..., None] * d
    return np.sqrt(np.einsum("...i,...i->...", away, away))


def segment_distance(p0: ArrayLike, p1: ArrayLike, q0: ArrayLike, q1: ArrayLike) -> np.ndarray:
    """Least distance between segments ``p0 p1`` and ``q0 q1``, all ``(..., 3)`` broadcast; ``(...)``.

    The closest points ``p0 + s d1`` and ``q0 + t d2`` with ``s, t`` in [0, 1] (Ericson, *Real-Time
    Collision Detection*, 5.1.9): ``s`` from the unclamped solution clamped, ``t`` from ``s``, then ``s``
    again from the clamped ``t``; degenerate segments (points) and parallel ones included.
    """
    p0, p1, q0, q1 = np.broadcast_arrays(*(np.asarray(x, float) for x in (p0, p1, q0, q1)))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = np.sum(d1 * d1, axis=-1), np.sum(d2 * d2, axis=-1)
    b, c, f = np.sum(d1 * d2, axis=-1), np.sum(d1 * r, axis=-1), np.sum(d2 * r, axis=-1)
    denom = a * e - b * b
    s = np.where(denom > _TINY * np.maximum(a * e, 1.0), (b * f - c * e) / np.where(denom > 0, denom, 1.0), 0.0)
    s = np.where(a > _TINY, np.clip(s, 0.0, 1.0), 0.0)
    t = np.where(e > _TINY, (b * s + f) / np.maximum(e, _TINY), 0.0)
    t_clamped = np.clip(t, 0.0, 1.0)
    s = np.where((t != t_clamped) & (a > _TINY), np.clip((b * t_clamped - c) / np.maximum(a, _TINY), 0.0, 1.0), s)
    closest = (p0 + s[..., None] * d1) - (q0 + t_clamped[..., None] * d2)
    return np.linalg.norm(closest, axis=-1)
