"""Plans that keep clear of the cell: the check of a station, postures vetoed, the visiting order repaired.

The planner (``station.capture.planning``) asks three things of this module:

- :class:`CellCheck`: how plans are checked (the cell's geometry, the margin, the path sampling, the
  TCP of the world zones) and the :class:`~handeye.robot.clearance.CellGuard` for a board pose;
- :class:`PostureVeto`: the sampler's veto, refusing a posture closer than the margin to the cell and
  counting why;
- :func:`clear_route`: the visiting order, with every move (the start's included) clear of the cell.
  Moves that are not clear are avoided by the order when another order avoids them (each blocked move
  costs infinitely much in the shortest-motion order); a posture that still sits at a blocked move is
  dropped and another drawn in its place (a few rounds), and when the draws run out the postures at
  blocked moves are dropped until every move of the order is clear.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...robot import base_clearances, base_envelope
from ...robot import CellModel
from ...robot import CellGuard
from ...geometry import BoardGeometry, board_corners
from ...robot import RobotModel
from ..board_square import known_square_mm

if TYPE_CHECKING:
    from ..config.station import StationConfig

__all__ = ["CellCheck", "PostureVeto", "Rejections", "base_problem", "board_problem", "cell_check", "clear_route",
           "start_problem", "view_points"]

#: Rounds of drawing replacements for postures at blocked moves.
REPAIR_ROUNDS = 4


@dataclass(frozen=True)
class CellCheck:
    """How a plan is checked against the cell.

    Attributes
    ----------
    model : CellModel
        Keep-out volumes, carried bodies, the board's stand.
    margin_mm : float
        Clearance every posture and every sampled point of a move keeps.
    step_mm : float
        Largest motion of any checked point between two samples of a move.
    zone_tcp_mm : tuple of float, shape (3,), optional
        The point in tool0 the controller's world zones watch, when the program declares them; the plan
        then keeps it ``margin_mm`` from every world zone as the controller sees it.
    """

    model: CellModel
    margin_mm: float = 30.0
    step_mm: float = 10.0
    zone_tcp_mm: tuple | None = None

    def guard(self, robot: RobotModel, board2base: np.ndarray | None = None, board: BoardGeometry | None = None) -> CellGuard:
        """The guard for a board at ``board2base`` (its stand included)."""
        zones = None
        if self.zone_tcp_mm is not None:
            zones = (self.zone_tcp_mm, self.model.world_zone_volumes(board2base, board))
        return CellGuard(robot, self.model.volumes(board2base, board), self.model.carried, self.margin_mm, self.step_mm,
                         tcp_zones=zones)


def cell_check(config: StationConfig) -> CellCheck:
    """The :class:`CellCheck` of a station config (its ``cell`` section; with ``cell.world_zones`` the
    camera's nominal mount is the TCP the zones watch)."""
    c = config.cell
    tcp = tuple(config.camera.nominal_mount[0]) if c.world_zones else None
    return CellCheck(c.model(), c.margin_mm, c.path_step_mm, tcp)


@dataclass
class Rejections:
    """Why postures and moves were rejected: ``reason -> count`` (``robot.clearance.Violation.reason``)."""

    postures: Counter = field(default_factory=Counter)
    moves: Counter = field(default_factory=Counter)

    def lines(self) -> list[str]:
        """``3 postures: camera too close to 'fixture'``, most frequent first."""
        out = [f"{n} posture{'s' if n != 1 else ''}: {reason}" for reason, n in self.postures.most_common()]
        out += [f"{n} move{'s' if n != 1 else ''}: {reason}" for reason, n in self.moves.most_common()]
        return out

    def summary(self) -> str:
        """One line: ``12 postures and 2 moves rejected (3 postures: camera too close to 'fixture'; ...)``."""
        p, m = sum(self.postures.values()), sum(self.moves.values())
        if not p and not m:
            return "no posture or move rejected"
        return f"{p} posture{'s' if p != 1 else ''} and {m} move{'s' if m != 1 else ''} rejected ({'; '.join(self.lines())})"

    def to_dict(self) -> dict:
        return {"postures": dict(self.postures), "moves": dict(self.moves)}


class PostureVeto:
    """The sampler's vetoes (``robot.views.sample_eye_in_hand_postures``): a posture closer than the
    margin to the cell is refused and its reason counted; :meth:`pose` tests what the flange carries on
    the flange pose alone, before the inverse kinematics, :meth:`__call__` the whole posture."""

    def __init__(self, guard: CellGuard, rejections: Rejections):
        self.guard = guard
        self.rejections = rejections

    def _counted(self, violation) -> bool:
        if violation is not None:
            self.rejections.postures[violation.reason] += 1
        return violation is None

    def pose(self, tool02base: np.ndarray) -> bool:
        return self._counted(self.guard.flange_violation(tool02base))

    def __call__(self, joints) -> bool:
        return self._counted(self.guard.posture_violation(joints))


def view_points(board2base: np.ndarray, board: BoardGeometry, distance_mm: Sequence[float], cone_deg: float) -> np.ndarray:
    """Where a camera viewing the board stands at the least and the greatest distance, straight on and
    at the cone's rim (8 directions): ``(18, 3)`` points in base (mm).

    Parameters
    ----------
    board2base : array-like, shape (4, 4)
        The board's target frame in base (its z points into the board, away from the camera).
    board : BoardGeometry
    distance_mm : tuple of float, shape (2,)
        Camera-to-board-centre distance range (``plan.distance_mm``).
    cone_deg : float
        Largest angle of the viewing direction from the board normal (``plan.cone_deg``).
    """
    frame = np.asarray(board2base, float)
    centre = frame[:3, :3] @ board_corners(board.corners, known_square_mm(board)).mean(axis=0) + frame[:3, 3]
    cone, turns = np.radians(cone_deg), np.radians(np.arange(0.0, 360.0, 45.0))
    local = np.vstack([[0.0, 0.0, -1.0], np.stack([np.sin(cone) * np.cos(turns), np.sin(cone) * np.sin(turns),
                                                   np.full(turns.shape, -np.cos(cone))], axis=1)])
    directions = local @ frame[:3, :3].T
    return np.concatenate([centre + d * directions for d in distance_mm])


def board_problem(model: CellModel, board2base: np.ndarray, board: BoardGeometry,
                  distance_mm: Sequence[float] = (700.0, 1200.0),
                  cone_deg: float = 35.0) -> str | None:
    """Why no view of the board can be planned because one configured keep-out volume fills the space the
    camera must stand in to see it (every point of :func:`view_points`), or None.

    Parameters
    ----------
    model : CellModel
        Its ``keep_out`` volumes (the board's own stand is derived from the board and is not one).
    board2base : array-like, shape (4, 4)
    board : BoardGeometry
    distance_mm : tuple of float, shape (2,)
    cone_deg : float
    """
    views = view_points(board2base, board, distance_mm, cone_deg)
    frame = np.asarray(board2base, float)
    corners = board_corners(board.corners, known_square_mm(board)) @ frame[:3, :3].T + frame[:3, 3]
    for volume in model.keep_out:
        if np.all(volume.signed_distance(views) < 0):
            holds = " holds the board and" if np.any(volume.signed_distance(corners) < 0) else ""
            return (f"the keep-out volume {volume.name!r} ({volume.kind}, cell.keep_out){holds} fills the space the "
                    f"camera must view the board from ({distance_mm[0]:g}-{distance_mm[1]:g} mm in front of it, within "
                    f"{cone_deg:g} deg of its normal: plan.distance_mm, plan.cone_deg), so it would block every view; "
                    "shrink it to what the arm must avoid (the board's own stand is kept out already: "
                    "cell.stand_margin_mm)")
    return None


def base_problem(robot: RobotModel, volumes: Sequence, margin_mm: float, keep_out: Sequence | None = None) -> str | None:
    """Why the cell cannot be planned in because a keep-out volume comes within the margin of the robot's
    base, which never moves (``robot.base_clearance``; volumes wholly at or below the mounting plane,
    base z 0, carry the robot and are left out), or None. The nearest such volume is named.

    Parameters
    ----------
    robot : RobotModel
        Its base capsules (:attr:`RobotModel.link_bodies` on part 0).
    volumes : sequence
        Keep-out volumes in base.
    margin_mm : float
        ``cell.margin_mm``.
    keep_out : sequence, optional
        The configured volumes (``cell.keep_out``); any other of ``volumes`` is the board's stand. None:
        all are configured.
    """
    near = [(volume, gap) for volume, gap in base_clearances(robot, volumes) if gap < margin_mm]
    if not near:
        return None
    volume, gap = min(near, key=lambda pair: pair[1])
    box = base_envelope(robot)
    if box is None:  # the clearances above were measured to the base's capsules: there are some
        raise ValueError(f"robot {robot.name} has no base capsules to name an envelope by")
    low, high = box
    where = (f"reaches {-gap:.0f} mm into" if gap < 0 else f"is {gap:.0f} mm from") + " the robot's base"
    envelope = (f"x {low[0]:.0f}..{high[0]:.0f}, y {low[1]:.0f}..{high[1]:.0f}, z up to {high[2]:.0f} mm in base, "
                f"the robot file's base capsule")
    if keep_out is None or volume in keep_out:
        return (f"the keep-out volume {volume.name!r} ({volume.kind}, cell.keep_out) {where} ({envelope}), within "
                f"cell.margin_mm ({margin_mm:g} mm); the base never moves, so no posture could keep the margin: move or "
                "shrink the volume to what the arm must avoid, or, if the robot stands on it (the floor, a "
                "foundation), give it wholly at or below base z 0")
    return (f"the board's stand {volume.name!r} {where} ({envelope}), within cell.margin_mm ({margin_mm:g} mm): "
            "place the board farther from the robot's foot, or lower cell.stand_margin_mm")


def start_problem(guard: CellGuard, start: np.ndarray) -> str | None:
    """Why the start posture cannot start a plan (inside a volume, or closer than the margin), or None."""
    violation = guard.posture_violation(start)
    if violation is None:
        return None
    if violation.clearance_mm < 0:
        return (f"at the start posture, {violation.describe()}: jog the robot out of it, with the board in view, "
                "then run capture again")
    return (f"at the start posture, {violation.describe()}, within the margin of {guard.margin_mm:g} mm "
            "(cell.margin_mm): jog the robot clear of it, with the board in view, then run capture again")


class _BlockedMoves:
    """Which moves between postures are blocked, each pair checked once."""

    def __init__(self, guard: CellGuard):
        self.guard = guard
        self._known: dict = {}

    @staticmethod
    def _key(joints) -> bytes:
        return np.round(np.asarray(joints, float), 6).tobytes()

    def matrix(self, nodes: np.ndarray) -> tuple[np.ndarray, dict]:
        """``(n, n)`` blocked moves between ``nodes`` and their violations ``{(i, j): Violation}``."""
        keys = [self._key(n) for n in nodes]
        todo = [(i, j) for i in range(len(nodes)) for j in range(i + 1, len(nodes)) if (keys[i], keys[j]) not in self._known]
        for (i, j), found in zip(todo, self.guard.moves_violations([(nodes[i], nodes[j]) for i, j in todo])):
            self._known[keys[i], keys[j]] = self._known[keys[j], keys[i]] = found
        blocked = np.zeros((len(nodes), len(nodes)), bool)
        why = {}
        for i in range(len(nodes)):
            for j in range(len(nodes)):
                found = self._known.get((keys[i], keys[j])) if i != j else None
                if found is not None:
                    blocked[i, j] = True
                    why[i, j] = found
        return blocked, why


def clear_route(robot: RobotModel, guard: CellGuard, start: np.ndarray, joints: np.ndarray,
                redraw: Callable[[int], np.ndarray], rejections: Rejections,
                order_for_short_motions: Callable) -> np.ndarray:
    """The postures in a visiting order whose every move, from ``start`` on, is clear of the cell.

    Parameters
    ----------
    robot : RobotModel
    guard : CellGuard
    start : array-like, shape (k,)
    joints : ndarray, shape (n, k)
        Postures already clear of the cell (each on its own).
    redraw : callable
        ``redraw(m)``: up to ``m`` new postures ``(<= m, k)`` clear of the cell, to replace dropped ones.
    rejections : Rejections
        Receives the reason of every posture dropped for a blocked move.
    order_for_short_motions : callable
        ``(robot, joints, start, blocked) -> order``: the planner's shortest-motion order.

    Returns
    -------
    ndarray, shape (m, k)
        In visiting order; ``m <= n`` when postures had to be dropped.
    """
    joints = np.asarray(joints, float).reshape(-1, robot.dof)
    moves = _BlockedMoves(guard)
    rounds = 0
    while len(joints):
        nodes = np.vstack([np.asarray(start, float)[None], joints])
        blocked, why = moves.matrix(nodes)
        order = order_for_short_motions(robot, joints, start, blocked)
        route = [0] + [int(i) + 1 for i in order]
        bad = [(a, b) for a, b in zip(route[:-1], route[1:]) if blocked[a, b]]
        if not bad:
            return joints[order]
        drop = set()
        for a, b in bad:  # drop the end of the move with the more blocked moves (never the start)
            candidates = [n for n in (a, b) if n != 0 and n not in drop]
            if candidates:
                victim = max(candidates, key=lambda n: (blocked[n].sum(), n))
                drop.add(victim)
                rejections.moves[why[a, b].reason] += 1
        keep = np.array([row for i, row in enumerate(joints, start=1) if i not in drop]).reshape(-1, robot.dof)
        fresh = redraw(len(drop)) if rounds < REPAIR_ROUNDS else np.zeros((0, robot.dof))
        rounds += 1
        joints = np.vstack([keep, np.asarray(fresh, float).reshape(-1, robot.dof)])
    return joints
