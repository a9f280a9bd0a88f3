"""Clearance of the moving arm from the cell: postures, and the joint-interpolated moves between them.

What moves is covered by spheres, never smaller than the body (the check errs on the safe side):

- each capsule of the robot model (:attr:`RobotModel.bodies`: links 4-6 of the IRB 1400): spheres
  along its axis spaced ``s = r``, each of radius ``sqrt(r^2 + (s/2)^2)`` (1.12 r);
- each box the flange carries (tool0): a grid of cells at most :data:`CELL_MM` wide, one sphere per
  cell of radius half the cell's diagonal (at most 0.87 x :data:`CELL_MM` beyond a face);
- each carried sphere: itself.

The clearance of a configuration is the least ``signed distance of a sphere's centre - its radius``
over the spheres and the keep-out volumes (``calibration.cell``); it must be at least ``margin_mm``.

A move is the path ``MoveAbsJ`` runs: every axis linear in joint space, all starting and stopping
together, ``q(s) = a + s (b - a)``, whatever the speed. It is sampled so that no sphere centre moves
more than ``step_mm`` between two samples: a centre at most ``R_i`` from axis ``i`` moves at most
``sum_i R_i |d theta_i|`` (serial angles, radians), ``R_i`` the length of the chain beyond axis ``i``
plus the carried reach. Between two samples every centre is within ``step_mm / 2`` of a sampled
place, so the clearance anywhere along the move is at least the sampled one minus ``step_mm / 2``.

Optionally one more point is watched against volumes of its own: the TCP the controller's world
zones supervise (``tcp_zones``), against the world-zone shapes (boxes of a frame of their own become
their axis-aligned bounding box there), so the plan never makes the controller stop the arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cell import Box, Sphere
from .kinematics import RobotModel

__all__ = ["CELL_MM", "CellGuard", "Violation", "carried_spheres", "link_spheres"]

#: Largest cell of the sphere grid covering a carried box, mm.
CELL_MM = 40.0
#: Configurations checked per batch (memory: batch x spheres x 3 floats).
_BATCH = 4096


@dataclass(frozen=True)
class Violation:
    """The closest approach of a posture or a move to the cell, below the margin.

    Attributes
    ----------
    body : str
        What came too close (``camera``, ``link 5``, ``TCP``).
    volume : str
        The keep-out volume (or world zone) it came close to.
    clearance_mm : float
        The least clearance found (negative: inside the volume).
    at : float
        Where along the move, 0 (start) to 1 (end); 0 for a posture.
    """

    body: str
    volume: str
    clearance_mm: float
    at: float = 0.0

    @property
    def reason(self) -> str:
        """What to count violations by: ``camera too close to 'fixture'``."""
        return f"{self.body} {'inside' if self.clearance_mm < 0 else 'too close to'} '{self.volume}'"

    def describe(self) -> str:
        """One line: ``camera is 12 mm inside 'fixture'`` / ``link 5 is 8 mm from 'floor'``."""
        if self.clearance_mm < 0:
            return f"{self.body} is {-self.clearance_mm:.0f} mm inside '{self.volume}'"
        return f"{self.body} is {self.clearance_mm:.0f} mm from '{self.volume}'"


def link_spheres(robot: RobotModel):
    """Spheres along the robot's capsules: ``(start, end, t, radius, body name)`` arrays, one row per sphere.

    A sphere's centre is ``(1 - t) P(start) + t P(end)`` of :meth:`RobotModel.chain_points`.
    """
    rows = []
    for body in robot.bodies:
        length = float(np.linalg.norm(robot.chain_points(np.zeros(robot.dof))[body.end]
                                      - robot.chain_points(np.zeros(robot.dof))[body.start]))
        count = max(1, math.ceil(length / body.radius_mm) + 1) if length > 0 else 1
        spacing = length / (count - 1) if count > 1 else 0.0
        radius = math.hypot(body.radius_mm, spacing / 2)
        for t in (np.linspace(0.0, 1.0, count) if count > 1 else [0.0]):
            rows.append((body.start, body.end, float(t), radius, body.name))
    return rows


def carried_spheres(carried) -> list:
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


class CellGuard:
    """Checks postures and moves of a robot against keep-out volumes.

    Parameters
    ----------
    robot : RobotModel
        Its :attr:`~RobotModel.bodies` (the wrist end) are watched.
    volumes : sequence
        Keep-out volumes in base (``calibration.cell``: Box, Cylinder, Floor).
    carried : sequence
        Boxes and spheres the flange carries, in tool0.
    margin_mm : float
        Clearance every posture and every sample of a move must keep (0: only entering counts).
    step_mm : float
        Largest motion of any sphere centre between two samples of a move.
    tcp_zones : (array-like (3,), sequence of volumes), optional
        A point in tool0 (the TCP the controller's world zones watch) and the world-zone shapes it
        must keep ``margin_mm`` from.
    """

    def __init__(self, robot: RobotModel, volumes, carried=(), margin_mm: float = 30.0, step_mm: float = 10.0,
                 tcp_zones=None):
        if not step_mm > 0:
            raise ValueError(f"step_mm must be > 0; got {step_mm}")
        self.robot = robot
        self.margin_mm = float(margin_mm)
        self.step_mm = float(step_mm)
        links = link_spheres(robot)
        tool = carried_spheres(carried)
        zones = []
        if tcp_zones is not None:
            point, zones = tcp_zones
            zones = list(zones)
            tool.append((np.asarray(point, float), 0.0, "TCP"))
        self.volumes = list(volumes) + zones
        self._link_index = np.array([[a, b] for a, b, *_ in links], int).reshape(-1, 2)
        self._link_t = np.array([t for _, _, t, *_ in links], float)
        self._tool_centres = np.array([c for c, _, _ in tool], float).reshape(-1, 3)
        self.radii = np.array([r for *_, r, _ in links] + [r for _, r, _ in tool], float)
        self.bodies = [name for *_, name in links] + [name for *_, name in tool]
        # which sphere is checked against which volume: the TCP against the zones only, the rest against the cell
        tcp = np.array([name == "TCP" for name in self.bodies]) if tcp_zones is not None else np.zeros(len(self.bodies), bool)
        is_zone = np.arange(len(self.volumes)) >= len(self.volumes) - len(zones)
        self._mask = tcp[:, None] == is_zone[None, :]
        reach = float(max((np.linalg.norm(c) for c, _, _ in tool), default=0.0))
        lengths = np.linalg.norm(robot.links, axis=1)
        self._lever = np.array([lengths[i:].sum() + reach for i in range(robot.dof)])  # R_i

    @property
    def watches_anything(self) -> bool:
        return bool(len(self.radii) and len(self.volumes))

    # ----------------------------------------------------------------------------- geometry
    def sphere_centres(self, joints_deg) -> np.ndarray:
        """Centres ``(n, m, 3)`` in base of the ``m`` spheres at configurations ``(n, k)``."""
        joints = np.atleast_2d(np.asarray(joints_deg, float))
        parts = []
        if len(self._link_t):
            chain = self.robot.chain_points(joints)
            t = self._link_t[None, :, None]
            parts.append((1 - t) * chain[:, self._link_index[:, 0]] + t * chain[:, self._link_index[:, 1]])
        if len(self._tool_centres):
            tool02base = self.robot.forward_transform(joints)
            parts.append(np.einsum("nij,mj->nmi", tool02base[:, :3, :3], self._tool_centres) + tool02base[:, None, :3, 3])
        return np.concatenate(parts, axis=1) if parts else np.zeros((len(joints), 0, 3))

    def clearances(self, joints_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Least clearance of each configuration ``(n, k)``, and which sphere and volume: ``(n,)`` x 3."""
        joints = np.atleast_2d(np.asarray(joints_deg, float))
        n = len(joints)
        best = np.full(n, np.inf)
        sphere = np.zeros(n, int)
        volume = np.zeros(n, int)
        if not self.watches_anything:
            return best, sphere, volume
        for start in range(0, n, _BATCH):
            centres = self.sphere_centres(joints[start:start + _BATCH])
            rows = slice(start, start + len(centres))
            for v, vol in enumerate(self.volumes):
                gap = vol.signed_distance(centres) - self.radii
                gap[:, ~self._mask[:, v]] = np.inf
                closest = np.argmin(gap, axis=1)
                value = gap[np.arange(len(gap)), closest]
                better = value < best[rows]
                best[rows] = np.where(better, value, best[rows])
                sphere[rows] = np.where(better, closest, sphere[rows])
                volume[rows] = np.where(better, v, volume[rows])
        return best, sphere, volume

    def _violation(self, clearance: float, sphere: int, volume: int, at: float = 0.0) -> Violation:
        return Violation(self.bodies[sphere], self.volumes[volume].name, float(clearance), float(at))

    # ----------------------------------------------------------------------------- postures
    def posture_violation(self, joints_deg) -> Violation | None:
        """The closest approach of one posture ``(k,)`` when below the margin, else None."""
        best, sphere, volume = self.clearances(np.asarray(joints_deg, float)[None])
        return self._violation(best[0], sphere[0], volume[0]) if best[0] < self.margin_mm else None

    def flange_violation(self, tool02base) -> Violation | None:
        """What the flange carries (and the world zones' TCP) closer than the margin at a flange pose
        ``(4, 4)``, else None: the part of :meth:`posture_violation` that needs no joints (a cheap
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
        return self._violation(*best) if best[0] < self.margin_mm else None

    # ----------------------------------------------------------------------------- moves
    def sample_count(self, a, b) -> int:
        """Samples (both ends included) of the move ``a -> b`` so no centre moves more than ``step_mm``."""
        delta = np.abs(self.robot.coupling @ np.radians(np.asarray(b, float) - np.asarray(a, float)))
        return max(2, math.ceil(float(self._lever @ delta) / self.step_mm) + 1)

    def path_samples(self, a, b) -> np.ndarray:
        """Configurations ``(s, k)`` along the joint-interpolated move from ``a`` to ``b`` (ends included)."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        s = np.linspace(0.0, 1.0, self.sample_count(a, b))[:, None]
        return a + s * (b - a)

    def path_violation(self, a, b) -> Violation | None:
        """The first place along the move ``a -> b`` closer than the margin, else None."""
        return self.moves_violations([(a, b)])[0]

    def moves_violations(self, moves) -> list:
        """:meth:`path_violation` of many moves ``[(a, b), ...]``, advanced together.

        Each move is walked from its start by conservative advancement: from a sample of clearance
        ``c`` the next lies where the centres have moved at most ``max(c - margin, step_mm)``, so
        the clearance between two samples stays at least ``margin`` (when ``c - margin`` was the
        larger) or at least ``margin - step_mm / 2`` (when both samples keep the margin). A move
        stops at its first sample below the margin.
        """
        starts = np.array([np.asarray(a, float) for a, _ in moves]).reshape(len(moves), -1)
        ends = np.array([np.asarray(b, float) for _, b in moves]).reshape(len(moves), -1)
        out: list = [None] * len(moves)
        if not len(moves) or not self.watches_anything:
            return out
        spans = np.abs(np.radians(ends - starts) @ self.robot.coupling.T) @ self._lever  # mm of motion over the move
        s = np.zeros(len(moves))
        active = np.ones(len(moves), bool)
        while active.any():
            rows = np.flatnonzero(active)
            at = s[rows]
            best, sphere, volume = self.clearances(starts[rows] + at[:, None] * (ends[rows] - starts[rows]))
            for r in np.flatnonzero(best < self.margin_mm):
                out[rows[r]] = self._violation(best[r], sphere[r], volume[r], at[r])
                active[rows[r]] = False
            done = active[rows] & (at >= 1.0)
            active[rows[done]] = False
            advance = np.maximum(best - self.margin_mm, self.step_mm) / np.maximum(spans[rows], 1e-9)
            s[rows] = np.where(at < 1.0, np.minimum(at + advance, 1.0), at)
        return out

    def pairwise_violations(self, nodes) -> dict:
        """``{(i, j): Violation}`` of the moves between every two configurations ``(n, k)``, ``i < j``
        (a move and its reverse sweep the same path); pairs that are clear are left out."""
        nodes = np.asarray(nodes, float)
        pairs = [(i, j) for i in range(len(nodes)) for j in range(i + 1, len(nodes))]
        found = self.moves_violations([(nodes[i], nodes[j]) for i, j in pairs])
        return {pair: v for pair, v in zip(pairs, found) if v is not None}
