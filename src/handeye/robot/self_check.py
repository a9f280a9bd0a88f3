"""Self-collision: the pairs of the arm's bodies that must keep clear of each other, and their distances.

The robot file lists the pairs by name (``self_collision.pairs``, :attr:`RobotModel.self_pairs`); the
word ``carried`` stands for every body the flange carries (the camera, its bracket, a cable loop).

- two capsules are apart by the distance of their axes (``robot.capsules``) minus both radii;
- a carried sphere and a capsule by the distance of its centre from the capsule's axis minus both radii;
- a carried box and a capsule: the capsule's axis is taken into tool0 and sampled at most
  :data:`AXIS_STEP_MM` apart; the box's signed distance (1-Lipschitz) at the samples, minus the radius
  and half the spacing, never exceeds the true distance (at most half the spacing below it).

Lengths in mm; negative distances: the bodies overlap.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
import math

import numpy as np
from numpy.typing import ArrayLike

from .capsules import point_segment_distance, segment_distance
from .cell import Box, Sphere
from .kinematics import CARRIED

__all__ = ["AXIS_STEP_MM", "SelfCheck"]

#: Largest spacing of the samples along a capsule's axis checked against a carried box, mm.
AXIS_STEP_MM = 10.0


def _bounding_sphere(box: Box) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` in the box's parent frame and radius of the sphere through a box's corners."""
    corners = box.corners()
    centre = corners.mean(axis=0)
    return centre, float(np.max(np.linalg.norm(corners - centre, axis=1)))


class SelfCheck:
    """The self-collision pairs of one arm and what it carries, ready to be measured in batches.

    Parameters
    ----------
    pairs : sequence of (str, str)
        Body names (or ``carried``), as :attr:`RobotModel.self_pairs`.
    capsule_names : sequence of str
        The name of each capsule of the arm, in the order of the segments given to :meth:`clearances`.
    capsule_radii : array-like, shape (B,)
    capsule_lengths : array-like, shape (B,)
        The length of each capsule's axis, mm.
    carried : sequence
        :class:`~handeye.robot.cell.Box` and :class:`~handeye.robot.cell.Sphere` bodies in tool0.
    fine_within_mm : float
        A carried box whose circumscribed sphere is farther than this from a capsule is reported at that
        sphere's distance (a lower bound); nearer, at its own (use at least the margin plus a little).
    capsule_parts : array-like of int, shape (B,), optional
        The part each capsule rides on (0 the base, ``i`` the link axis ``i`` turns); ``carried_part``
        the flange's. They give :attr:`label_parts`: only the axes between a pair's parts change its distance.
    """

    def __init__(self, pairs: Iterable[Sequence[str]], capsule_names: Iterable[str], capsule_radii: ArrayLike,
                 capsule_lengths: Sequence[float] | np.ndarray, carried: Iterable[Box | Sphere] = (), fine_within_mm: float = 150.0,
                 capsule_parts: ArrayLike | None = None, carried_part: int = 0):
        self.fine_within_mm = float(fine_within_mm)
        capsule_names, carried = list(capsule_names), list(carried)
        carried_names = [body.name for body in carried]
        cap_pairs, body_pairs, labels = [], [], []
        for a, b in pairs:
            if b == CARRIED or b in carried_names:  # the carried side first
                a, b = b, a
            if b == CARRIED or b in carried_names:
                continue  # carried against carried: they ride together
            seconds = [j for j, n in enumerate(capsule_names) if n == b]
            for name in (carried_names if a == CARRIED else [a]):
                if name in carried_names:
                    firsts, rows = [carried_names.index(name)], body_pairs
                else:
                    firsts, rows = [i for i, n in enumerate(capsule_names) if n == name], cap_pairs
                if firsts and seconds:
                    labels.append((name, b))
                    rows += [(i, j, len(labels) - 1) for i in firsts for j in seconds]
        self.labels = labels
        self.carried = carried
        parts = np.zeros(len(capsule_names), int) if capsule_parts is None else np.asarray(capsule_parts, int)
        spans = [[] for _ in labels]
        for i, j, k in cap_pairs:
            spans[k] += [parts[i], parts[j]]
        for _, j, k in body_pairs:
            spans[k] += [int(carried_part), parts[j]]
        #: ``(L, 2)``: the lowest and the highest part of each pair's bodies.
        self.label_parts = np.array([[min(p), max(p)] for p in spans], int).reshape(-1, 2)
        radii = np.asarray(capsule_radii, float)
        self._caps = np.array(cap_pairs, int).reshape(-1, 3)
        self._cap_gap = radii[self._caps[:, 0]] + radii[self._caps[:, 1]]
        self._bodies = np.array(body_pairs, int).reshape(-1, 3)
        self._radii = radii
        longest = float(max([float(capsule_lengths[j]) for _, j, _ in body_pairs], default=0.0))
        self._t = np.linspace(0.0, 1.0, max(2, math.ceil(longest / AXIS_STEP_MM) + 1))
        self._half_spacing = np.asarray(capsule_lengths, float) / (len(self._t) - 1) / 2

    def __bool__(self) -> bool:
        return bool(len(self.labels))

    def _body_gaps(self, segments: np.ndarray, tool02base: np.ndarray) -> np.ndarray:
        """Distances ``(n, P)`` of the carried bodies of :attr:`_bodies` from their capsules (one batch per body).

        A box is first bounded by its circumscribed sphere (a lower bound of the distance); only where that
        bound is below :attr:`fine_within_mm` is the capsule's axis sampled against the box itself."""
        out = np.empty((len(segments), len(self._bodies)))
        rotation, origin = tool02base[:, :3, :3], tool02base[:, :3, 3]
        for i in np.unique(self._bodies[:, 0]):
            rows = np.flatnonzero(self._bodies[:, 0] == i)
            caps = self._bodies[rows, 1]
            body = self.carried[i]
            local = np.einsum("nji,ncej->ncei", rotation, segments[:, caps] - origin[:, None, None, :])  # in tool0
            if isinstance(body, Sphere):
                gap = point_segment_distance(np.asarray(body.centre_mm, float), local[:, :, 0], local[:, :, 1])
                out[:, rows] = gap - body.radius_mm - self._radii[caps]
                continue
            if not isinstance(body, Box):
                raise TypeError(f"a carried body is a Box or a Sphere; got {type(body).__name__}")
            centre, reach = _bounding_sphere(body)
            gap = point_segment_distance(centre, local[:, :, 0], local[:, :, 1]) - reach - self._radii[caps]
            near = np.nonzero(gap < self.fine_within_mm)
            if len(near[0]):
                ends = local[near]  # (K, 2, 3)
                t = self._t[None, :, None]
                points = (1 - t) * ends[:, None, 0] + t * ends[:, None, 1]
                c = caps[near[1]]
                gap[near] = body.signed_distance(points).min(axis=1) - self._radii[c] - self._half_spacing[c]
            out[:, rows] = gap
        return out

    def clearances(self, segments: np.ndarray, tool02base: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Least distance of the pairs at each configuration, which pair (an index of :attr:`labels`), and
        the least distance of each pair.

        Parameters
        ----------
        segments : ndarray, shape (n, B, 2, 3)
            The capsules' axes in base.
        tool02base : ndarray, shape (n, 4, 4)
            The flange at each configuration.

        Returns
        -------
        best : ndarray, shape (n,)
            mm (negative: overlapping); ``inf`` without pairs.
        pair : ndarray, shape (n,) of int
        each : ndarray, shape (n, L)
            mm, per pair of :attr:`labels`.
        """
        n = len(segments)
        parts, which = [], []
        if len(self._caps):
            i, j = self._caps[:, 0], self._caps[:, 1]
            parts.append(segment_distance(segments[:, i, 0], segments[:, i, 1], segments[:, j, 0], segments[:, j, 1])
                         - self._cap_gap)
            which.append(self._caps[:, 2])
        if len(self._bodies):
            parts.append(self._body_gaps(segments, tool02base))
            which.append(self._bodies[:, 2])
        if not parts:
            return np.full(n, np.inf), np.zeros(n, int), np.zeros((n, 0))
        gaps, labels = np.concatenate(parts, axis=1), np.concatenate(which)
        each = np.full((n, len(self.labels)), np.inf)
        np.minimum.at(each, (np.arange(n)[:, None], labels[None, :]), gaps)
        k = np.argmin(gaps, axis=1)
        return gaps[np.arange(n), k], labels[k], each
