"""The check's session: which postures of SESSION to revisit, in which order, and its folder.

The postures are chosen for diagnostic power (``calibration.verify_postures``), then ordered for the
shortest motion from where the robot stands, every move checked against the cell of the station
config (``station.cell.plan``: the same check the capture's planner makes). The check's measurements
are a session of their own beside SESSION (``SESSION-verify-<time>``, the capture format with a
capture record whose ``verify_of`` names SESSION and the postures), captured with the same RAPID
program and links as ``capture`` (``station.capture.loop``).
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path

import numpy as np

from ...base import HandEyeError
from ...calibration import Session, create_session
from ...geometry import transform_from_pose
from ..cell.plan import cell_check
from ..config.station import StationConfig

__all__ = ["TIME_BUDGET", "TIME_LIMIT", "TIME_TIGHTEN", "TIME_TRIES", "VerifyError", "capture_time", "cell_guard",
           "create_verify_session", "order_postures", "path_time", "path_time_along", "verify_folder"]


class VerifyError(HandEyeError):
    """The check cannot be made (a session it cannot check, a move the cell refuses)."""


def _motion_s(robot, a, b) -> float:
    return float(np.max(np.abs(np.asarray(b, float) - np.asarray(a, float)) / robot.max_speed_deg_s))


def order_postures(robot, start_joints, joints: np.ndarray, guard=None) -> list[int]:
    """The order (indices into ``joints``) with the least motion time from ``start_joints`` whose every
    move ``guard`` (a ``CellGuard``) allows; all orders tried for up to 7 postures, nearest-next beyond.

    Raises
    ------
    VerifyError
        No order keeps clear of the cell.
    """
    n = len(joints)

    def clear(a, b) -> bool:
        return guard is None or guard.path_violation(np.asarray(a, float), np.asarray(b, float)) is None

    orders = itertools.permutations(range(n)) if n <= 7 else [_nearest_next(robot, start_joints, joints)]
    costed = sorted(orders, key=lambda o: _path_s(robot, start_joints, joints, o))
    for order in costed[:200]:
        stops = [start_joints] + [joints[i] for i in order]
        if all(clear(a, b) for a, b in zip(stops[:-1], stops[1:])):
            return list(order)
    raise VerifyError("no order of the chosen postures keeps every move clear of the cell: check the cell section "
                      "of the station config, or choose other postures (--postures)")


def _path_s(robot, start, joints, order) -> float:
    stops = [start] + [joints[i] for i in order]
    return sum(_motion_s(robot, a, b) for a, b in zip(stops[:-1], stops[1:]))


def path_time(robot, start, joints) -> float:
    """Motion time (s, full axis speed) of the shortest order through ``joints`` from ``start``
    (every order for up to 6 postures, nearest-next beyond)."""
    joints = np.asarray(joints, float)
    if len(joints) <= 6:
        return min(_path_s(robot, start, joints, o) for o in itertools.permutations(range(len(joints))))
    return _path_s(robot, start, joints, _nearest_next(robot, start, joints))


def path_time_along(robot, start, joints) -> float:
    """Motion time (s, full axis speed) from ``start`` through ``joints`` in their order (a capture's plan)."""
    joints = np.asarray(joints, float)
    return _path_s(robot, start, joints, range(len(joints)))


def capture_time(robot, record: dict) -> float:
    """The full capture's robot time (s, full axis speed) from its capture record: from its start
    through every planned posture in the plan's order, each move synchronised (the slowest axis sets
    its time), as the mock arm and a ``MoveAbsJ`` time it. At the arm's speed fraction both this and a
    check's :func:`path_time_along` scale alike, so their ratio is the ratio of robot times."""
    plan = np.asarray(record["plan_joints_deg"], float)
    start = np.asarray(record.get("start_joints_deg") or plan[0], float)
    return path_time_along(robot, start, plan)


#: The posture choice aims at this fraction of the full capture's robot time (:func:`capture_time`)
#: for the check's real path: from where the robot stands through the chosen postures in the order
#: they are visited (the program stays at the last one: it has no move home).
TIME_BUDGET = 0.15
#: A check whose real path would exceed this fraction of the capture's robot time is chosen again
#: with a tighter budget (:data:`TIME_BUDGET` times ``TIME_TIGHTEN`` each time, up to ``TIME_TRIES``
#: choices); the bound is a fifth, this keeps a margin below it. When no choice fits (a session of
#: few postures) the shortest tried is taken and the check says so (``station.verify.check._chosen``).
TIME_LIMIT = 0.18
TIME_TIGHTEN = 0.8
TIME_TRIES = 6


def _nearest_next(robot, start, joints) -> tuple:
    left, here, order = list(range(len(joints))), start, []
    while left:
        nxt = min(left, key=lambda i: _motion_s(robot, here, joints[i]))
        order.append(nxt)
        left.remove(nxt)
        here = joints[nxt]
    return tuple(order)


def verify_folder(session_dir: Path) -> Path:
    """A new folder beside SESSION for the check's measurements: ``SESSION-verify-<time>[-n]``."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for n in range(1, 1000):
        path = session_dir.parent / (f"{session_dir.name}-verify-{stamp}" + ("" if n == 1 else f"-{n}"))
        if not path.exists():
            return path
    raise VerifyError(f"{session_dir.parent} holds 999 checks of {stamp}")


def cell_guard(config: StationConfig, robot, record: dict):
    """The cell guard of the station config around the board SESSION's plan was made for."""
    estimate = record.get("board_estimate")
    board2base = None if estimate is None else transform_from_pose(estimate["position_mm"], estimate["quaternion_wxyz"])
    return cell_check(config).guard(robot, board2base, config.target)


def create_verify_session(config: StationConfig, session: Session, session_dir: Path, indices, joints: np.ndarray,
                          folder: Path, station: str) -> Session:
    """Create the check's session (``folder``) with the capture record of the revisit: ``plan_joints_deg``
    the revisited postures' jointtargets as SESSION's program held them, ``verify_of`` SESSION and their
    numbers there."""
    record = session.extra["capture"]
    extra = {"capture": {
        "station": station,
        "plan_joints_deg": [[round(float(v), 4) for v in row] for row in joints],
        "start_joints_deg": record.get("start_joints_deg"),
        "plan_score": record.get("plan_score", {}),
        "board_estimate": record.get("board_estimate"),
        "nominal_mount": record.get("nominal_mount"),
        "skipped": {},
        "config": config.to_dict(),
        "verify_of": {"session": str(session_dir), "postures": [int(i) for i in indices]},
    }}
    new = Session(setup=session.setup, robot=session.robot, target=session.target, extra=extra)
    create_session(folder, new)
    return new
