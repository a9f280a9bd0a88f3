"""Capsules that contain a point cloud: the least-volume capsule of a set, and a few capsules of a part.

:func:`fit_capsule` minimises the capsule's volume ``pi r^2 L + 4/3 pi r^3`` over the two ends of its
axis (Nelder-Mead, from the principal axis through the centroid), the radius always the largest
distance of a point from the axis, so every point is inside at every step; on a given line (``line``:
a part that turns about that line, a capsule round about it), over the two ends' places on the line.

:func:`fit_capsules` splits a part into ``count`` capsules: k-means groups first (a fixed seed: the
same points give the same capsules), then each point goes to the capsule it is deepest in, each
capsule is fitted again to its points, and the split of least total volume is kept. Every point of
the part lies inside the capsule of its group; :func:`grown` then rounds the ends to whole mm and adds
a margin to the radius, the containment kept.

Lengths in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import numpy as np
from scipy.cluster.vq import kmeans2
from scipy.optimize import minimize

from .capsules import point_segment_distance

__all__ = ["Capsule", "capsule_volume", "fit_capsule", "fit_capsules", "grown"]


@dataclass(frozen=True)
class Capsule:
    """A segment ``start end`` (each ``(3,)``, mm) and a radius (mm)."""

    start: np.ndarray
    end: np.ndarray
    radius: float

    def distances(self, points) -> np.ndarray:
        """Distance of points ``(n, 3)`` from the axis, ``(n,)``."""
        return point_segment_distance(np.asarray(points, float), self.start, self.end)

    def contains(self, points, tolerance_mm: float = 1e-9) -> np.ndarray:
        """True where a point ``(n, 3)`` is inside (or on) the capsule, ``(n,)``."""
        return self.distances(points) <= self.radius + tolerance_mm


def capsule_volume(length: float, radius: float) -> float:
    """Volume of a capsule of axis length ``length`` and radius ``radius``, mm^3."""
    return math.pi * radius * radius * length + 4.0 / 3.0 * math.pi * radius ** 3


def _enclosing(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> Capsule:
    return Capsule(start, end, float(point_segment_distance(points, start, end).max()))


def _volume(capsule: Capsule) -> float:
    return capsule_volume(float(np.linalg.norm(capsule.end - capsule.start)), capsule.radius)


def _overshoot(capsule: Capsule, bounds) -> float:
    """How far (mm, summed over the six faces) the capsule reaches beyond the box ``(low (3,), high (3,))``."""
    if bounds is None:
        return 0.0
    low = np.minimum(capsule.start, capsule.end) - capsule.radius
    high = np.maximum(capsule.start, capsule.end) + capsule.radius
    return float(np.sum(np.maximum(bounds[0] - low, 0.0)) + np.sum(np.maximum(high - bounds[1], 0.0)))


def fit_capsule(points, line=None, bounds=None) -> Capsule:
    """The least-volume capsule around points ``(n, 3)``; on ``line`` ``(origin (3,), direction (3,))`` if given.

    ``bounds`` ``(low (3,), high (3,))``: a box the capsule should not reach beyond (each mm beyond costs
    as much volume as the capsule's own cross-section times 1 m): the least volume alone may send a
    capsule far out where the part is not (a column's capsule into the floor).

    Returns
    -------
    Capsule
        Its radius is the largest distance of a point from its axis: every point is inside.
    """
    points = np.asarray(points, float)
    if line is not None:
        origin, direction = (np.asarray(v, float) for v in line)
        direction = direction / np.linalg.norm(direction)
        s = (points - origin) @ direction

        def at(x):
            low, high = min(x), max(x)
            return _enclosing(points, origin + low * direction, origin + high * direction)

        start = np.array([s.min(), s.max()])
    else:
        centre = points.mean(axis=0)
        direction = np.linalg.svd(points - centre, full_matrices=False)[2][0]
        s = (points - centre) @ direction

        def at(x):
            return _enclosing(points, x[:3], x[3:])

        start = np.concatenate([centre + s.min() * direction, centre + s.max() * direction])
    scale = max(float(np.ptp(s)), 1.0)
    simplex = np.vstack([start] + [start + 0.1 * scale * row for row in np.eye(len(start))])
    def cost(x):
        capsule = at(x)
        return _volume(capsule) + 1000.0 * math.pi * capsule.radius ** 2 * _overshoot(capsule, bounds)

    fit = minimize(cost, start, method="Nelder-Mead",
                   options={"initial_simplex": simplex, "xatol": 0.05, "fatol": 1.0, "maxiter": 4000})
    return at(fit.x) if cost(fit.x) <= cost(start) else at(start)


def fit_capsules(points, count: int, line=None, seed: int = 0, rounds: int = 6, slack_mm=None) -> list:
    """``count`` capsules whose union holds points ``(n, 3)``: ``[(Capsule, member indices)]``.

    Parameters
    ----------
    points : array-like, shape (n, 3)
    count : int
        How many capsules (1: :func:`fit_capsule` of all points).
    line : (origin, direction), optional
        Every capsule's axis on this line.
    seed : int
        Of the k-means start: the same points and seed give the same capsules.
    rounds : int
        Reassignments tried after the k-means start.
    slack_mm : float, optional
        No capsule should reach farther than this beyond the points' axis-aligned box (:func:`fit_capsule`'s
        ``bounds``); None: no bound.
    """
    points = np.asarray(points, float)
    bounds = None if slack_mm is None else (points.min(axis=0) - slack_mm, points.max(axis=0) + slack_mm)
    if count <= 1:
        return [(fit_capsule(points, line, bounds), np.arange(len(points)))]
    _, labels = kmeans2(points, count, seed=seed, minit="++")  # pyright: ignore[reportCallIssue]  (scipy: seed)
    best, best_volume = None, np.inf
    for _ in range(rounds + 1):
        groups = [np.flatnonzero(labels == c) for c in range(count) if np.any(labels == c)]
        fitted = [(fit_capsule(points[g], line, bounds), g) for g in groups]
        volume = sum(_volume(c) + 1000.0 * math.pi * c.radius ** 2 * _overshoot(c, bounds) for c, _ in fitted)
        if volume < best_volume - 1e-6:
            best, best_volume = fitted, volume
        excess = np.stack([c.distances(points) - c.radius for c, _ in fitted], axis=1)
        new = np.argmin(excess, axis=1)
        if np.array_equal(new, labels):
            break
        labels = new
    return cast(list, best)  # (never None: the first round always fits)


def grown(capsule: Capsule, points, margin_mm: float) -> Capsule:
    """The capsule with its ends rounded to whole mm and its radius the largest distance of ``points``
    ``(n, 3)`` from the rounded axis plus ``margin_mm``, rounded up to whole mm."""
    start, end = np.round(capsule.start), np.round(capsule.end)
    reach = float(point_segment_distance(np.asarray(points, float), start, end).max())
    return Capsule(start, end, float(math.ceil(reach + margin_mm)))
