"""Capsules that contain a point cloud: the least-volume capsule of a set, and a few capsules of a part.

:func:`fit_capsule` minimises the capsule's volume ``pi r^2 L + 4/3 pi r^3`` over the two ends of its
axis (Nelder-Mead, from the principal axis through the centroid), the radius always the largest
distance of a point from the axis, so every point is inside at every step (restarted from its best
with a fresh simplex while that gains: the cost is a maximum, not smooth); on a given line (``line``:
a part that turns about that line, a capsule round about it), over the two ends' places on the line.

:func:`fit_capsules` splits a part into ``count`` capsules: k-means groups first (a fixed seed: the
same points give the same capsules), then each point goes to the capsule it is deepest in, each
capsule is fitted again to its points, and the split of least total volume is kept. Every point of
the part lies inside the capsule of its group; :func:`grown` then rounds the ends to whole mm and adds
a margin to the radius, the containment kept.

A capsule holds a facet when it holds its three corners (a capsule is convex), but a facet whose corners
lie in different capsules of a part can leave their union between them. :func:`facet_depths` bounds how
deep every facet lies in the union from below: the best capsule's depth at its three corners, or the
depth of samples on a grid over the facet (:func:`facet_samples`) less the grid's gap
(:func:`surface_gap`); :func:`cover_facets` grows the capsules until every facet is a margin deep.

Lengths in mm.
"""

from __future__ import annotations

from collections.abc import Sequence
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.cluster.vq import kmeans2
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, QhullError

from .capsules import point_segment_distance

__all__ = ["Capsule", "capsule_volume", "cover_facets", "facet_depths", "facet_grid", "facet_samples", "fit_capsule",
           "fit_capsules", "fit_surface_capsules", "grown", "surface_gap"]

#: Nelder-Mead runs at most, each from the last one's best with a fresh simplex.
_RESTARTS = 8


@dataclass(frozen=True)
class Capsule:
    """A segment ``start end`` (each ``(3,)``, mm) and a radius (mm)."""

    start: np.ndarray
    end: np.ndarray
    radius: float

    def distances(self, points: ArrayLike) -> np.ndarray:
        """Distance of points ``(n, 3)`` from the axis, ``(n,)``."""
        return point_segment_distance(np.asarray(points, float), self.start, self.end)

    def contains(self, points: ArrayLike, tolerance_mm: float = 1e-9) -> np.ndarray:
        """True where a point ``(n, 3)`` is inside (or on) the capsule, ``(n,)``."""
        return self.distances(points) <= self.radius + tolerance_mm


def capsule_volume(length: float, radius: float) -> float:
    """Volume of a capsule of axis length ``length`` and radius ``radius``, mm^3."""
    return math.pi * radius * radius * length + 4.0 / 3.0 * math.pi * radius ** 3


def _extreme(points: np.ndarray) -> np.ndarray:
    """The corners of the points' convex hull (a capsule is convex: it holds the points when it holds these)."""
    if len(points) < 5:
        return points
    try:
        return points[ConvexHull(points).vertices]
    except QhullError:  # flat or on a line: all of them
        return points


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


def fit_capsule(points: ArrayLike, line: tuple[ArrayLike, ArrayLike] | None = None,
                bounds: tuple[ArrayLike, ArrayLike] | None = None) -> Capsule:
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
    hull = _extreme(points)
    if line is not None:
        origin, direction = (np.asarray(v, float) for v in line)
        direction = direction / np.linalg.norm(direction)
        s = (points - origin) @ direction

        def at(x):
            low, high = min(x), max(x)
            return _enclosing(hull, origin + low * direction, origin + high * direction)

        start = np.array([s.min(), s.max()])
    else:
        centre = points.mean(axis=0)
        direction = np.linalg.svd(points - centre, full_matrices=False)[2][0]
        s = (points - centre) @ direction

        def at(x):
            return _enclosing(hull, x[:3], x[3:])

        start = np.concatenate([centre + s.min() * direction, centre + s.max() * direction])
    scale = max(float(np.ptp(s)), 1.0)
    def cost(x):
        capsule = at(x)
        return _volume(capsule) + 1000.0 * math.pi * capsule.radius ** 2 * _overshoot(capsule, bounds)

    best = start
    for _ in range(_RESTARTS):  # the cost is not smooth (a maximum): Nelder-Mead stalls; a fresh simplex moves on
        simplex = np.vstack([best] + [best + 0.1 * scale * row for row in np.eye(len(best))])
        fit = minimize(cost, best, method="Nelder-Mead",
                       options={"initial_simplex": simplex, "xatol": 0.05, "fatol": 1.0, "maxiter": 4000})
        if cost(fit.x) >= cost(best) - 1.0:
            break
        best = fit.x
    return at(best)


def fit_capsules(points: ArrayLike, count: int, line: tuple[ArrayLike, ArrayLike] | None = None, seed: int = 0,
                 rounds: int = 6, slack_mm: float | None = None) -> list:
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
    _, labels = kmeans2(points, count, seed=seed, minit="++")  # pyright: ignore[reportCallIssue]  (the stubs know only rng; seed keeps the stream the robot file was fitted with)
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
    assert best is not None  # the first round's volume is below the initial infinity
    return best


def grown(capsule: Capsule, points: ArrayLike, margin_mm: float) -> Capsule:
    """The capsule with its ends rounded to whole mm and its radius the largest distance of ``points``
    ``(n, 3)`` from the rounded axis plus ``margin_mm``, rounded up to whole mm."""
    start, end = np.round(capsule.start), np.round(capsule.end)
    reach = float(point_segment_distance(np.asarray(points, float), start, end).max())
    return Capsule(start, end, float(math.ceil(reach + margin_mm)))


def surface_gap(spacing_mm: float) -> float:
    """How far a point of a facet can be from the nearest sample of :func:`facet_samples`, mm.

    Each facet is cut into sub-triangles with edges at most ``spacing_mm`` whose corners are the samples. A
    point of a triangle with longest edge ``L`` is at most ``L / sqrt(3)`` from its nearest corner (the
    circumradius, when the triangle is acute: the angle opposite ``L`` is 60-90 deg; at most ``L / 2`` when
    it is not), so every point of a facet is within ``spacing_mm / sqrt(3)`` of a sample; a point's depth
    in a union of capsules changes no faster than the point moves.
    """
    return float(spacing_mm) / math.sqrt(3.0)


def facet_samples(facets: ArrayLike, spacing_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(n, 3)`` on facets ``(m, 3, 3)`` and the facet of each ``(n,)``: a barycentric grid of ``k``
    steps along each edge, ``k = ceil(longest edge / spacing_mm)``, corners included."""
    facets = np.asarray(facets, float).reshape(-1, 3, 3)
    longest = np.max(np.linalg.norm(facets - np.roll(facets, 1, axis=1), axis=2), axis=1)
    steps = np.maximum(1, np.ceil(longest / float(spacing_mm)).astype(int))
    points, owners = [np.zeros((0, 3))], [np.zeros(0, int)]
    for k in np.unique(steps):
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        keep = i + j <= k
        weights = np.stack([k - i[keep] - j[keep], i[keep], j[keep]], axis=1) / k  # (g, 3)
        which = np.flatnonzero(steps == k)
        points.append(np.einsum("gc,mcx->mgx", weights, facets[which]).reshape(-1, 3))
        owners.append(np.repeat(which, len(weights)))
    return np.concatenate(points), np.concatenate(owners)


def _grid_triangles(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric weights ``(g, 3)`` of the grid of ``k`` steps and its ``k * k`` sub-triangles ``(k * k, 3)``."""
    i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
    keep = i + j <= k
    index = np.full((k + 2, k + 2), -1)
    index[i[keep], j[keep]] = np.arange(int(keep.sum()))
    a, b = i[keep], j[keep]
    up = a + b <= k - 1
    down = a + b <= k - 2
    triangles = np.vstack([np.stack([index[a[up], b[up]], index[a[up] + 1, b[up]], index[a[up], b[up] + 1]], axis=1),
                           np.stack([index[a[down] + 1, b[down]], index[a[down], b[down] + 1],
                                     index[a[down] + 1, b[down] + 1]], axis=1)])
    weights = np.stack([k - a - b, a, b], axis=1) / k
    return weights, triangles


def facet_grid(facets: ArrayLike, spacing_mm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facets ``(m, 3, 3)`` cut into sub-triangles with edges at most ``spacing_mm``.

    Each facet is cut by the barycentric grid of :func:`facet_samples` (``k`` steps along each edge) into
    ``k * k`` sub-triangles similar to it.

    Returns
    -------
    points : ndarray, shape (n, 3)
        The grid's points (a facet's corners among them; shared by the sub-triangles of a facet).
    triangles : ndarray, shape (t, 3)
        Rows of indices into ``points``: the sub-triangles.
    owners : ndarray, shape (t,)
        The facet each sub-triangle lies on.
    """
    facets = np.asarray(facets, float).reshape(-1, 3, 3)
    longest = np.max(np.linalg.norm(facets - np.roll(facets, 1, axis=1), axis=2), axis=1)
    steps = np.maximum(1, np.ceil(longest / float(spacing_mm)).astype(int))
    points, triangles, owners, count = [np.zeros((0, 3))], [np.zeros((0, 3), int)], [np.zeros(0, int)], 0
    for k in np.unique(steps):
        weights, cells = _grid_triangles(int(k))
        which = np.flatnonzero(steps == k)
        points.append(np.einsum("gc,mcx->mgx", weights, facets[which]).reshape(-1, 3))
        offsets = count + len(weights) * np.arange(len(which))
        triangles.append((offsets[:, None, None] + cells[None]).reshape(-1, 3))
        owners.append(np.repeat(which, len(cells)))
        count += len(which) * len(weights)
    return np.concatenate(points), np.concatenate(triangles), np.concatenate(owners)


def _kmeans_labels(centres: np.ndarray, count: int, seed: int, sample: int = 20000) -> np.ndarray:
    """k-means groups of points ``(n, 3)``, found on a seeded subsample of at most ``sample`` and given to all."""
    pick = np.random.default_rng(seed).permutation(len(centres))[:sample]
    means, _ = kmeans2(centres[pick], count, seed=seed, minit="++")  # pyright: ignore[reportCallIssue]  (the stubs know only rng)
    return np.argmin([np.sum((centres - m) ** 2, axis=1) for m in means], axis=0)


def fit_surface_capsules(facets: ArrayLike, count: int, line: tuple[ArrayLike, ArrayLike] | None = None, seed: int = 0,
                         rounds: int = 8, slack_mm: float | None = None,
                         spacing_mm: float = 5.0) -> tuple[list, np.ndarray]:
    """``count`` capsules whose union holds the surface of facets ``(m, 3, 3)``, not only their corners.

    The facets are cut into sub-triangles (:func:`facet_grid`, edges at most ``spacing_mm``); each
    sub-triangle belongs to one capsule, which holds its three corners and so (a capsule is convex) all of
    it. The split starts from k-means groups of the sub-triangles' centres (seeded: the same facets give
    the same capsules); then, as :func:`fit_capsules`, each group's least-volume capsule is fitted (on the
    corners of its points' hull), each sub-triangle goes to the capsule its farthest corner is deepest
    in, and the split of least total volume is kept.

    Returns
    -------
    capsules : list of (Capsule, member point indices)
        Every corner of every sub-triangle of the capsule's group is inside it (:func:`grown` adds a
        margin that then holds for the whole surface of the group).
    points : ndarray, shape (n, 3)
        The grid's points the member indices refer to.
    """
    points, triangles, _ = facet_grid(facets, spacing_mm)
    corners = np.asarray(facets, float).reshape(-1, 3)
    bounds = None if slack_mm is None else (corners.min(axis=0) - slack_mm, corners.max(axis=0) + slack_mm)
    labels = np.zeros(len(triangles), int) if count <= 1 else \
        _kmeans_labels(points[triangles].mean(axis=1), count, seed)
    best, best_volume = None, np.inf
    for _ in range(rounds + 1):
        groups = [np.unique(triangles[labels == c]) for c in range(count) if np.any(labels == c)]
        fitted = [(fit_capsule(points[g], line, bounds), g) for g in groups]
        volume = sum(_volume(c) + 1000.0 * math.pi * c.radius ** 2 * _overshoot(c, bounds) for c, _ in fitted)
        if volume < best_volume - 1e-6:
            best, best_volume = fitted, volume
        excess = np.stack([c.distances(points) - c.radius for c, _ in fitted])  # (c, n)
        new = np.argmin(excess[:, triangles].max(axis=2), axis=0)
        if len(fitted) < count or np.array_equal(new, labels):
            break
        labels = new
    assert best is not None  # the first round's volume is below the initial infinity
    return best, points


def _depths(capsules, points) -> np.ndarray:
    """``(c, n)``: radius less the distance from each capsule's axis (positive inside)."""
    return np.array([c.radius - c.distances(points) for c in capsules]).reshape(len(capsules), len(points))


def facet_depths(capsules: Sequence[Capsule], facets: ArrayLike, spacing_mm: float = 5.0, enough_mm: float = np.inf) -> np.ndarray:
    """A lower bound ``(m,)`` on how deep each facet ``(m, 3, 3)`` lies inside the union of ``capsules``, mm.

    The larger of the best single capsule's least depth at the facet's corners (the depth in one capsule
    is concave, so the whole facet is at least that deep in it) and the least bound of its sub-triangles
    (:func:`facet_grid`, edges at most ``spacing_mm``): for each, the larger of the best single capsule's
    least depth at its corners and its corners' least depth in the union less :func:`surface_gap` of its
    longest edge. Negative: part of the facet may be outside. Facets at least ``enough_mm`` deep by their
    corners are not cut (their bound is the corners').
    """
    facets = np.asarray(facets, float).reshape(-1, 3, 3)
    corners = _depths(capsules, facets.reshape(-1, 3)).reshape(len(capsules), len(facets), 3)
    bound = corners.min(axis=2).max(axis=0) if len(capsules) else np.full(len(facets), -np.inf)
    weak = np.flatnonzero(bound < enough_mm)
    if not len(capsules) or not len(weak):
        return bound
    points, triangles, owners = facet_grid(facets[weak], spacing_mm)
    depth = _depths(capsules, points)[:, triangles]  # (c, t, 3)
    cell = points[triangles]
    edge = np.max(np.linalg.norm(cell - np.roll(cell, 1, axis=1), axis=2), axis=1)
    single = depth.min(axis=2).max(axis=0)
    union = depth.max(axis=0).min(axis=1) - edge / math.sqrt(3.0)
    sampled = np.full(len(weak), np.inf)
    np.minimum.at(sampled, owners, np.maximum(single, union))
    bound[weak] = np.maximum(bound[weak], sampled)
    return bound


def cover_facets(capsules: Sequence[Capsule], facets: ArrayLike, margin_mm: float, spacing_mm: float = 5.0) -> list:
    """The capsules with radii grown (to whole mm) until every facet ``(m, 3, 3)`` is ``margin_mm`` deep by
    :func:`facet_depths`: each sample of a facet short of it goes to the capsule it is deepest in, whose
    radius then holds it ``margin_mm`` plus :func:`surface_gap` deep."""
    capsules = list(capsules)
    facets = np.asarray(facets, float).reshape(-1, 3, 3)
    short = facets[facet_depths(capsules, facets, spacing_mm, margin_mm) < margin_mm - 1e-9]
    if not len(short):
        return capsules
    points, _ = facet_samples(short, spacing_mm)
    depth = _depths(capsules, points)
    best = np.argmax(depth, axis=0)
    need = margin_mm + surface_gap(spacing_mm)
    out = []
    for c, capsule in enumerate(capsules):
        mine = depth[c, best == c]
        grow = max(0.0, need - float(mine.min())) if len(mine) else 0.0
        out.append(Capsule(capsule.start, capsule.end, float(math.ceil(capsule.radius + grow - 1e-9))))
    return out
