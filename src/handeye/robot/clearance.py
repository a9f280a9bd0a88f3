"""Clearance of the moving arm from the cell and from itself: postures, and the joint-interpolated moves.

What moves is covered by spheres, never smaller than the body (the check errs on the safe side):

- each capsule of the robot model: the wrist's (:attr:`RobotModel.bodies`: links 4-6 of the IRB 1400)
  and the rest of the arm's (:attr:`RobotModel.link_bodies`: the base, links 1-3): spheres along its
  axis spaced ``s = r``, each of radius ``sqrt(r^2 + (s/2)^2)`` (1.12 r). The base never moves: it is
  left out of the keep-out check at every posture (``robot.base_clearance`` checks it once, when the
  cell is loaded) and kept in the self-collision check;
- each box the flange carries (tool0): a grid of cells at most :data:`CELL_MM` wide, one sphere per
  cell of radius half the cell's diagonal (at most 0.87 x :data:`CELL_MM` beyond a face);
- each carried sphere: itself.

The clearance of a configuration is the least ``signed distance of a sphere's centre - its radius``
over the spheres and the keep-out volumes (``robot.cell``), and the least distance between the
pairs of bodies the robot file lists (:attr:`RobotModel.self_pairs`; ``carried`` = every body the
flange carries): capsule against capsule by their segments' distance (``robot.capsules``) minus
both radii, a carried sphere against a capsule by its centre's distance from the segment minus both
radii. Both must be at least ``margin_mm``.

A move is the path ``MoveAbsJ`` runs: every axis linear in joint space, all starting and stopping
together, ``q(s) = a + s (b - a)``, whatever the speed. It is sampled so that no sphere centre moves
more than ``step_mm`` between two samples: a point of the part turned by axis ``i`` and beyond moves at
most ``sum_i R_i |d theta_i|`` (serial angles, radians), ``R_i`` the largest distance from axis ``i``
any watched point can have (the chain's lengths beyond it plus the point's offset on its own part).
Between two samples every centre is within ``step_mm / 2`` of a sampled place, so the clearance from
the cell anywhere along the move is at least the sampled one minus ``step_mm / 2``. Two bodies of the
arm move relative to each other only by the axes between their parts (the same sum over those axes
alone), so their clearance too is at least the sampled one minus ``step_mm / 2``.

Optionally one more point is watched against volumes of its own: the TCP the controller's world
zones supervise (``tcp_zones``), against the world-zone shapes (boxes of a frame of their own become
their axis-aligned bounding box there), so the plan never makes the controller stop the arm.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .cell import Box, KeepOut, Sphere
from .kinematics import RobotModel
from .self_check import SelfCheck

__all__ = ["CELL_MM", "CellGuard", "Violation", "arm_capsules", "carried_spheres", "link_spheres"]

#: Largest cell of the sphere grid covering a carried box, mm.
CELL_MM = 40.0
#: Configurations checked per batch (memory: batch x spheres x 3 floats).
_BATCH = 4096
#: Moves of at most this many samples in all are checked at every sample in one batch (the mock's single
#: moves), more by conservative advancement (the planner's hundreds of moves).
_DENSE = 1024


@dataclass(frozen=True)
class Violation:
    """The closest approach of a posture or a move to the cell or to the arm itself, below the margin.

    Attributes
    ----------
    body : str
        What came too close (``camera``, ``link 5``, ``TCP``).
    volume : str
        The keep-out volume (or world zone) it came close to, or (``kind`` ``self``) the arm's own body.
    clearance_mm : float
        The least clearance found (negative: inside the volume, or overlapping the body).
    at : float
        Where along the move, 0 (start) to 1 (end); 0 for a posture.
    kind : str
        ``cell`` (a keep-out volume) or ``self`` (two bodies of the arm and what it carries).
    """

    body: str
    volume: str
    clearance_mm: float
    at: float = 0.0
    kind: str = "cell"

    @property
    def pair(self) -> str:
        """``camera - link 3`` / ``link 5 - floor``: the two names."""
        return f"{self.body} - {self.volume}"

    @property
    def reason(self) -> str:
        """What to count violations by: ``camera too close to 'fixture'``, ``camera against link 3``."""
        if self.kind == "self":
            return f"{self.body} against {self.volume}"
        return f"{self.body} {'inside' if self.clearance_mm < 0 else 'too close to'} '{self.volume}'"

    def describe(self) -> str:
        """One line: ``camera is 12 mm inside 'fixture'`` / ``link 5 is 8 mm from 'floor'`` /
        ``camera against link 3: 8 mm apart`` / ``camera against link 3: 12 mm into it``."""
        if self.kind == "self":
            gap = self.clearance_mm
            return f"{self.reason}: {-gap:.0f} mm into it" if gap < 0 else f"{self.reason}: {gap:.0f} mm apart"
        if self.clearance_mm < 0:
            return f"{self.body} is {-self.clearance_mm:.0f} mm inside '{self.volume}'"
        return f"{self.body} is {self.clearance_mm:.0f} mm from '{self.volume}'"


def link_spheres(robot: RobotModel) -> list[tuple[int, int, float, float, str]]:
    """Spheres along the wrist's capsules (:attr:`RobotModel.bodies`): ``(start, end, t, radius, body name)``,
    one row per sphere. A sphere's centre is ``(1 - t) P(start) + t P(end)`` of :meth:`RobotModel.chain_points`."""
    home = robot.chain_points(np.zeros(robot.dof))
    return [(body.start, body.end, t, radius, body.name) for body in robot.bodies
            for t, radius in _along(float(np.linalg.norm(home[body.end] - home[body.start])), body.radius_mm)]


def _along(length: float, radius: float) -> list:
    """``(t, sphere radius)`` of the spheres covering a capsule of that axis length and radius."""
    count = max(1, math.ceil(length / radius) + 1) if length > 0 else 1
    spacing = length / (count - 1) if count > 1 else 0.0
    grown = math.hypot(radius, spacing / 2)
    return [(float(t), grown) for t in (np.linspace(0.0, 1.0, count) if count > 1 else [0.0])]


def arm_capsules(robot: RobotModel) -> list:
    """Every capsule of the arm as ``(name, part, start, end, radius)``: ``part`` 0 the base, ``i`` the link
    axis ``i`` turns; ``start``, ``end`` ``(3,)`` relative to that part's pivot with every axis at 0
    (:meth:`RobotModel.link_frames`). The wrist's capsules first (on the part of their farther chain
    point), then :attr:`RobotModel.link_bodies`."""
    home, pivots = robot.chain_points(np.zeros(robot.dof)), robot.home_pivots()
    out = []
    for body in robot.bodies:
        part = max(body.start, body.end)
        out.append((body.name, part, home[body.start] - pivots[part], home[body.end] - pivots[part], body.radius_mm))
    for body in robot.link_bodies:
        out.append((body.name, body.link, np.asarray(body.start_mm, float) - pivots[body.link],
                    np.asarray(body.end_mm, float) - pivots[body.link], body.radius_mm))
    return out


def carried_spheres(carried: Iterable[Box | Sphere]) -> list:
    """``(centre in tool0 (3,), radius, body name)`` of the spheres covering the carried bodies."""
    out = []
    for body in carried:
        if isinstance(body, Sphere):
            out.append((np.asarray(body.centre_mm, float), float(body.radius_mm), body.name))
            continue
        if not isinstance(body, Box):
            raise TypeError(f"a carried body is a Box or a Sphere; got {type(body).__name__}")
        low, high = np.asarray(body.min_mm, float), np.asarray(body.max_mm, float)
        counts = np.maximum(1, np.ceil((high - low) / CELL_MM)).astype(int)
        cell = (high - low) / counts
        radius = float(np.linalg.norm(cell) / 2)
        frame = np.eye(4) if body.box2parent is None else np.asarray(body.box2parent, float)
        for index in np.ndindex(*counts):
            centre = low + (np.asarray(index) + 0.5) * cell
            out.append((frame[:3, :3] @ centre + frame[:3, 3], radius, body.name))
    return out


def _levers(robot: RobotModel, capsules, tool_reach: float) -> np.ndarray:
    """``R_i``, shape (k,): the largest distance from axis ``i`` (through chain point ``P(i-1)``) of any
    watched point of the parts it turns: the chain's lengths from axis ``i`` to the point's part, plus
    the point's distance from its part's pivot (tool0's carried bodies: on part ``k``, ``|D_k| + reach``)."""
    lengths = np.linalg.norm(robot.links, axis=1)
    offsets = [(part, max(float(np.linalg.norm(a)), float(np.linalg.norm(b)))) for _, part, a, b, _ in capsules]
    offsets.append((robot.dof, float(lengths[-1]) + tool_reach))
    levers = np.zeros(robot.dof)
    for i in range(robot.dof):  # axis i + 1 (1-based) turns the parts i + 1 ... k
        levers[i] = max([lengths[i:part - 1].sum() + offset for part, offset in offsets if part >= i + 1], default=0.0)
    return levers


class CellGuard:
    """Checks postures and moves of a robot against keep-out volumes and against itself.

    Parameters
    ----------
    robot : RobotModel
        Its capsules (:func:`arm_capsules`: the wrist and the rest of the arm) are watched, and its
        self-collision pairs (:attr:`RobotModel.self_pairs`).
    volumes : sequence
        Keep-out volumes in base (``robot.cell``: Box, Cylinder, Floor).
    carried : sequence
        Boxes and spheres the flange carries, in tool0.
    margin_mm : float
        Clearance every posture and every sample of a move must keep (0: only entering counts).
    step_mm : float
        Largest motion of any sphere centre between two samples of a move.
    tcp_zones : (array-like (3,), sequence of volumes), optional
        A point in tool0 (the TCP the controller's world zones watch) and the world-zone shapes it
        must keep ``margin_mm`` from.
    self_collision : bool
        Check the robot's self-collision pairs too (default).
    """

    def __init__(self, robot: RobotModel, volumes: Iterable[KeepOut], carried: Iterable[Box | Sphere] = (),
                 margin_mm: float = 30.0, step_mm: float = 10.0,
                 tcp_zones: tuple[ArrayLike, Iterable[KeepOut]] | None = None, self_collision: bool = True):
        if not step_mm > 0:
            raise ValueError(f"step_mm must be > 0; got {step_mm}")
        self.robot = robot
        self.margin_mm = float(margin_mm)
        self.step_mm = float(step_mm)
        capsules = arm_capsules(robot)
        tool = carried_spheres(carried)
        zones = []
        if tcp_zones is not None:
            point, zones = tcp_zones
            zones = list(zones)
            tool.append((np.asarray(point, float), 0.0, "TCP"))
        self.volumes = list(volumes) + zones
        self._parts = np.array([part for _, part, *_ in capsules], int)
        self._local = np.array([[a, b] for _, _, a, b, _ in capsules], float).reshape(-1, 2, 3)
        spheres = [(c, t, r, name) for c, (name, part, a, b, radius) in enumerate(capsules)
                   for t, r in _along(float(np.linalg.norm(b - a)), radius)]
        self._sphere_capsule = np.array([c for c, *_ in spheres], int)
        self._link_t = np.array([t for _, t, _, _ in spheres], float)
        self._tool_centres = np.array([c for c, _, _ in tool], float).reshape(-1, 3)
        self.radii = np.array([r for *_, r, _ in spheres] + [r for _, r, _ in tool], float)
        self.bodies = [name for *_, name in spheres] + [name for *_, name in tool]
        # which sphere is checked against which volume: the TCP against the zones only, the base against none
        tcp = np.array([name == "TCP" for name in self.bodies]) if tcp_zones is not None else np.zeros(len(self.bodies), bool)
        is_zone = np.arange(len(self.volumes)) >= len(self.volumes) - len(zones)
        fixed = np.concatenate([self._parts[self._sphere_capsule] == 0, np.zeros(len(tool), bool)])
        self._mask = (tcp[:, None] == is_zone[None, :]) & ~fixed[:, None]
        pairs = robot.self_pairs if self_collision else ()
        self.self_check = SelfCheck(pairs, [c[0] for c in capsules], [c[4] for c in capsules],
                                    [float(np.linalg.norm(c[3] - c[2])) for c in capsules], carried,
                                    fine_within_mm=self.margin_mm + 100.0, capsule_parts=self._parts,
                                    carried_part=robot.dof)
        reach = float(max((np.linalg.norm(c) for c, _, name in tool), default=0.0))
        self._lever = _levers(robot, capsules, reach)  # R_i

    @property
    def watches_anything(self) -> bool:
        return bool((len(self.radii) and len(self.volumes)) or self.self_check)

    # ----------------------------------------------------------------------------- geometry
    def capsule_segments(self, joints_deg: ArrayLike) -> np.ndarray:
        """The axes ``(n, B, 2, 3)`` in base of the arm's ``B`` capsules (:func:`arm_capsules`) at ``(n, k)``."""
        joints = np.atleast_2d(np.asarray(joints_deg, float))
        rotations, pivots = self.robot.link_frames(joints)
        r, p = rotations[:, self._parts], pivots[:, self._parts]  # (n, B, 3, 3), (n, B, 3)
        return np.einsum("nbij,bej->nbei", r, self._local) + p[:, :, None, :]

    def _tool_centres_at(self, tool02base: np.ndarray) -> np.ndarray:
        return np.einsum("nij,mj->nmi", tool02base[:, :3, :3], self._tool_centres) + tool02base[:, None, :3, 3]

    def sphere_centres(self, joints_deg: ArrayLike) -> np.ndarray:
        """Centres ``(n, m, 3)`` in base of the ``m`` spheres at configurations ``(n, k)``."""
        joints = np.atleast_2d(np.asarray(joints_deg, float))
        segments = self.capsule_segments(joints)
        return self._centres(segments, self._tool_centres_at(self.robot.forward_transform(joints)))

    def _centres(self, segments: np.ndarray, tool: np.ndarray) -> np.ndarray:
        t = self._link_t[None, :, None]
        links = (1 - t) * segments[:, self._sphere_capsule, 0] + t * segments[:, self._sphere_capsule, 1]
        return np.concatenate([links, tool], axis=1)

    def _cell_clearances(self, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = len(centres)
        best, sphere, volume = np.full(n, np.inf), np.zeros(n, int), np.zeros(n, int)
        for v, vol in enumerate(self.volumes):
            watched = np.flatnonzero(self._mask[:, v])
            if not len(watched):
                continue
            gap = vol.signed_distance(centres[:, watched]) - self.radii[watched]
            closest = np.argmin(gap, axis=1)
            value = gap[np.arange(n), closest]
            better = value < best
            best = np.where(better, value, best)
            sphere = np.where(better, watched[closest], sphere)
            volume = np.where(better, v, volume)
        return best, sphere, volume

    def clearances(self, joints_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Least clearance of each configuration ``(n, k)`` from the cell and between the self-collision
        pairs: ``(cell (n,), self (n,))`` in mm (``inf`` where nothing is watched)."""
        cell, _, _, own, *_ = self._evaluate(joints_deg)
        return cell, own

    def _evaluate(self, joints_deg):
        """``(cell clearance, sphere, volume, self clearance, pair)``, each ``(n,)``, and each pair's
        clearance ``(n, L)``."""
        joints = np.atleast_2d(np.asarray(joints_deg, float))
        n = len(joints)
        out = [np.full(n, np.inf), np.zeros(n, int), np.zeros(n, int), np.full(n, np.inf), np.zeros(n, int),
               np.full((n, len(self.self_check.labels)), np.inf)]
        if not self.watches_anything:
            return tuple(out)
        for start in range(0, n, _BATCH):
            chunk = joints[start:start + _BATCH]
            rows = slice(start, start + len(chunk))
            segments, tool02base = self.capsule_segments(chunk), self.robot.forward_transform(chunk)
            if len(self.volumes):
                centres = self._centres(segments, self._tool_centres_at(tool02base))
                out[0][rows], out[1][rows], out[2][rows] = self._cell_clearances(centres)
            if self.self_check:
                out[3][rows], out[4][rows], out[5][rows] = self.self_check.clearances(segments, tool02base)
        return tuple(out)

    def _closest(self, evaluated, r: int, at: float = 0.0) -> Violation:
        """The closer of the cell's and the self pairs' approaches of configuration ``r``."""
        cell, sphere, volume, own, pair = (x[r] for x in evaluated[:5])
        if own < cell:
            body, other = self.self_check.labels[pair]
            return Violation(body, other, float(own), float(at), "self")
        return Violation(self.bodies[sphere], self.volumes[volume].name, float(cell), float(at))

    def closest(self, joints_deg: ArrayLike) -> Violation | None:
        """The closest approach of one posture ``(k,)`` (to the cell or between the pairs), whatever the
        margin; None when nothing is watched."""
        evaluated = self._evaluate(np.asarray(joints_deg, float)[None])
        return self._closest(evaluated, 0) if np.isfinite(min(evaluated[0][0], evaluated[3][0])) else None

    # ----------------------------------------------------------------------------- postures
    def posture_violation(self, joints_deg: ArrayLike) -> Violation | None:
        """The closest approach of one posture ``(k,)`` when below the margin, else None."""
        found = self.closest(joints_deg)
        return found if found is not None and found.clearance_mm < self.margin_mm else None

    def flange_violation(self, tool02base: ArrayLike) -> Violation | None:
        """What the flange carries (and the world zones' TCP) closer than the margin to the cell at a flange
        pose ``(4, 4)``, else None: the part of :meth:`posture_violation` that needs no joints (a cheap
        test before the inverse kinematics)."""
        tool = np.asarray(tool02base, float)
        centres = self._tool_centres @ tool[:3, :3].T + tool[:3, 3]
        first = len(self._link_t)
        best = (np.inf, 0, 0)
        for v, vol in enumerate(self.volumes):
            gap = vol.signed_distance(centres) - self.radii[first:]
            gap[~self._mask[first:, v]] = np.inf
            k = int(np.argmin(gap)) if len(gap) else 0
            if len(gap) and gap[k] < best[0]:
                best = (float(gap[k]), first + k, v)
        if best[0] >= self.margin_mm:
            return None
        return Violation(self.bodies[best[1]], self.volumes[best[2]].name, best[0])

    # ----------------------------------------------------------------------------- moves
    def sample_count(self, a: ArrayLike, b: ArrayLike) -> int:
        """Samples (both ends included) of the move ``a -> b`` so no centre moves more than ``step_mm``."""
        delta = np.abs(self.robot.coupling @ np.radians(np.asarray(b, float) - np.asarray(a, float)))
        return max(2, math.ceil(float(self._lever @ delta) / self.step_mm) + 1)

    def path_samples(self, a: ArrayLike, b: ArrayLike) -> np.ndarray:
        """Configurations ``(s, k)`` along the joint-interpolated move from ``a`` to ``b`` (ends included)."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        s = np.linspace(0.0, 1.0, self.sample_count(a, b))[:, None]
        return a + s * (b - a)

    def path_violation(self, a: ArrayLike, b: ArrayLike) -> Violation | None:
        """The first place along the move ``a -> b`` closer than the margin, else None."""
        return self.moves_violations([(a, b)])[0]

    def moves_violations(self, moves: Sequence[tuple[ArrayLike, ArrayLike]]) -> list:
        """:meth:`path_violation` of many moves ``[(a, b), ...]``, advanced together.

        Each move is walked from its start by conservative advancement: from a sample of clearance
        ``c`` from the cell the next lies where the centres have moved at most ``c - margin``, and no
        self-collision pair of clearance ``d`` has moved relative to itself more than ``d - margin``
        (a pair moves relative to itself only by the axes between its two parts: the camera and
        link 3 by axes 4, 5 and 6), or at least ``step_mm``; so the clearance between two samples stays
        at least ``margin`` (when the first was the larger) or at least ``margin - step_mm / 2`` (when
        both samples keep the margin). A move stops at its first sample below the margin. Moves of few
        samples in all (:data:`_DENSE`, e.g. one move of the mock arm) are checked at every sample of
        :meth:`sample_count` in one batch instead: the same bound between samples, fewer round trips.
        """
        out: list = [None] * len(moves)
        if not len(moves) or not self.watches_anything:
            return out
        starts = np.array([np.asarray(a, float) for a, _ in moves]).reshape(len(moves), -1)
        ends = np.array([np.asarray(b, float) for _, b in moves]).reshape(len(moves), -1)
        counts = [self.sample_count(a, b) for a, b in zip(starts, ends)]
        if sum(counts) <= _DENSE:  # few samples in all: every one at once (one batch, no round trips)
            return [self._dense_violation(a, b, n) for a, b, n in zip(starts, ends, counts)]
        turns = np.abs(np.radians(ends - starts) @ self.robot.coupling.T)  # serial angles over the move, (m, k)
        spans = turns @ self._lever  # mm of motion over the move
        rates = self._pair_rates(turns)  # mm of relative motion of each pair over the move, (m, L)
        s = np.zeros(len(moves))
        active = np.ones(len(moves), bool)
        while active.any():
            rows = np.flatnonzero(active)
            at = s[rows]
            evaluated = self._evaluate(starts[rows] + at[:, None] * (ends[rows] - starts[rows]))
            cell, own = evaluated[0], evaluated[3]
            for r in np.flatnonzero(np.minimum(cell, own) < self.margin_mm):
                out[rows[r]] = self._closest(evaluated, int(r), at[r])
                active[rows[r]] = False
            done = active[rows] & (at >= 1.0)
            active[rows[done]] = False
            with np.errstate(divide="ignore", invalid="ignore"):
                pairs_free = np.where(rates[rows] > 0, (evaluated[5] - self.margin_mm) / rates[rows], np.inf).min(
                    axis=1, initial=np.inf)
            span = np.maximum(spans[rows], 1e-9)
            advance = np.maximum(np.minimum((cell - self.margin_mm) / span, pairs_free), self.step_mm / span)
            s[rows] = np.where(at < 1.0, np.minimum(at + advance, 1.0), at)
        return out

    def _pair_rates(self, turns: np.ndarray) -> np.ndarray:
        """``(m, L)``: how far the bodies of each self-collision pair can move relative to each other over
        moves of serial turns ``(m, k)`` (radians): only the axes between the pair's parts count."""
        parts = self.self_check.label_parts
        out = np.zeros((len(turns), len(parts)))
        for p, (low, high) in enumerate(parts):
            out[:, p] = turns[:, low:high] @ self._lever[low:high]  # axes low + 1 ... high (1-based)
        return out

    def _dense_violation(self, a, b, count: int) -> Violation | None:
        """The first of ``count`` evenly spaced samples of ``a -> b`` (:meth:`sample_count`: no centre moves
        more than ``step_mm`` between two) closer than the margin, else None."""
        s = np.linspace(0.0, 1.0, count)
        evaluated = self._evaluate(a + s[:, None] * (b - a))
        low = np.flatnonzero(np.minimum(evaluated[0], evaluated[3]) < self.margin_mm)
        return self._closest(evaluated, int(low[0]), float(s[low[0]])) if len(low) else None

    def pairwise_violations(self, nodes: ArrayLike) -> dict:
        """``{(i, j): Violation}`` of the moves between every two configurations ``(n, k)``, ``i < j``
        (a move and its reverse sweep the same path); pairs that are clear are left out."""
        nodes = np.asarray(nodes, float)
        pairs = [(i, j) for i in range(len(nodes)) for j in range(i + 1, len(nodes))]
        found = self.moves_violations([(nodes[i], nodes[j]) for i, j in pairs])
        return {pair: v for pair, v in zip(pairs, found) if v is not None}
