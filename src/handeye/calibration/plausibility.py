"""Units and plausibility of a session's lengths, checked before anything is solved.

A session in the wrong unit solves as happily as a right one: written all in metres, every length
shrinks by 1000, the points still agree with each other and the answer is a camera "0.1 mm from
the flange" that passes every residual check. So the lengths are checked against what they must be
at a real cell, before any solve (``solve.problem_from_session``) and therefore again before any
write-back (which solves the session again):

- the flange's distance from the robot base and the board's distance from the camera are tens of
  millimetres at the very least (:data:`MIN_DISTANCE_MM`); a median below that means metres;
- a single posture whose distance is 100 times off the others is in another unit than the rest;
- the flange cannot be farther from the base than the robot's arm is long (when the robot model is
  known);
- the square size the measured corners show (a grid fit with a free scale, ``board_scale``)
  matches the session's ``target.square_mm``: refused when off by more than
  :data:`SQUARE_TOLERANCE` (5 %) and by more than 4 standard errors of the estimate.

A session that fails is refused with one line naming the unit or the value; a session known to be
in metres is converted only when asked (:func:`session_in_mm`, ``--units m``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import SQUARE_TOLERANCE, judge_square_size
from ..base import CalibrationError, brief

if TYPE_CHECKING:
    from .session import Session

__all__ = [
    "MIN_DISTANCE_MM",
    "SQUARE_TOLERANCE",
    "UNITS",
    "Implausibility",
    "UnitsError",
    "check_plausible",
    "corner_spacing_mm",
    "implausibilities",
    "session_in_mm",
]

#: Smallest plausible median distance (mm) of the flange from the base and of the board from the camera.
MIN_DISTANCE_MM = 20.0
#: A posture whose distance is this factor off the median of the others is in another unit.
POSTURE_UNIT_FACTOR = 100.0
#: Length units a session may be declared in, and the factor to millimetres.
UNITS = {"mm": 1.0, "m": 1000.0}


class UnitsError(CalibrationError):
    """The session's lengths are not plausible millimetres (metres, a wrong square size, out of reach)."""


@dataclass(frozen=True)
class Implausibility:
    """One implausible length.

    Attributes
    ----------
    kind : str
        ``metres`` (the whole session), ``robot_metres``, ``board_metres`` (one side),
        ``posture_unit`` (one posture), ``square_size``, ``reach``.
    message : str
        One line for the operator, saying what to do.
    postures : tuple of int
        Posture indices concerned (empty for the whole session).
    """

    kind: str
    message: str
    postures: tuple = ()


def corner_spacing_mm(points_mm: ArrayLike, corners: tuple[int, int]) -> float:
    """Median distance between neighbouring corners of measured boards.

    Parameters
    ----------
    points_mm : array-like, shape (n, nx*ny, 3) or (nx*ny, 3)
        Corners in target index order (``row * nx + col``).
    corners : tuple of int
        ``(nx, ny)``.
    """
    nx, ny = (int(c) for c in corners)
    grid = np.asarray(points_mm, float).reshape(-1, ny, nx, 3)
    along_x = np.linalg.norm(np.diff(grid, axis=2), axis=-1).ravel()
    along_y = np.linalg.norm(np.diff(grid, axis=1), axis=-1).ravel()
    return float(np.median(np.concatenate([along_x, along_y])))


def _distances(session, tool02base: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Flange distances from the base and board distances from the camera, one per posture (mm)."""
    flange = np.linalg.norm(np.asarray(tool02base, float)[:, :3, 3], axis=1)
    board = []
    for p in session.postures:
        if p.points_mm is not None:
            board.append(float(np.linalg.norm(np.mean(p.points_mm, axis=0))))
        elif p.target_in_camera is not None:
            board.append(float(np.linalg.norm(p.target_in_camera[:3, 3])))
        else:
            return flange, None
    return flange, np.array(board)


def _odd_postures(distances: np.ndarray, ids, what: str) -> list:
    median = float(np.median(distances))
    if median <= 0:
        return []
    ratio = distances / median
    found = []
    for k in np.flatnonzero((ratio < 1.0 / POSTURE_UNIT_FACTOR) | (ratio > POSTURE_UNIT_FACTOR)):
        found.append(Implausibility(
            "posture_unit", f"posture {ids[k]}: the {what} is {distances[k]:.4g} mm against a median of {median:.4g} mm "
                            f"for the postures: this posture looks written in another unit; fix or remove it",
            (int(ids[k]),)))
    return found


def _robot_reach_mm(name) -> tuple[str, float] | None:
    if not name:
        return None
    from ..robot import load_robot

    try:
        robot = load_robot(name)
    except (ValueError, OSError):
        return None
    return robot.name, float(np.linalg.norm(robot.base_offset) + np.sum(np.linalg.norm(robot.links, axis=1)))


def implausibilities(session: Session, tool02base: np.ndarray) -> list:
    """Every implausible length of a session (an empty list when the lengths look like millimetres).

    Parameters
    ----------
    session : calibration.session.Session
    tool02base : array-like, shape (n, 4, 4)
        The flange poses of the session's postures (given, or from the joints), in posture order.
    """
    ids = [p.index for p in session.postures]
    flange, board = _distances(session, tool02base)
    flange_median = float(np.median(flange))
    board_median = float(np.median(board)) if board is not None else None
    robot_small = flange_median < MIN_DISTANCE_MM
    board_small = board_median is not None and board_median < MIN_DISTANCE_MM
    fix = "write the session's lengths in mm (or convert it with --units m)"
    if robot_small and board_small:
        return [Implausibility(
            "metres", f"the session looks like metres: the flange is a median {flange_median:.4g} from the base and the "
                      f"board {board_median:.4g} from the camera, where millimetres would be hundreds; {fix}")]
    if robot_small:
        return [Implausibility(
            "robot_metres", f"the robot poses look like metres (the flange a median {flange_median:.4g} from the base) "
                            f"while the board is in mm ({board_median:.4g} mm from the camera); write tool0_in_base in mm")]
    if board_small:
        return [Implausibility(
            "board_metres", f"the board measurements look like metres (a median {board_median:.4g} from the camera) while "
                            f"the robot poses are in mm ({flange_median:.4g} mm from the base); write points_mm and "
                            "target_in_camera in mm")]
    found = _odd_postures(flange, ids, "flange's distance from the base")
    if board is not None:
        found += _odd_postures(board, ids, "board's distance from the camera")
    reach = _robot_reach_mm(session.robot)
    if reach is not None:
        name, longest = reach
        for k in np.flatnonzero(flange > 1.05 * longest):
            found.append(Implausibility(
                "reach", f"posture {ids[k]}: the flange is {flange[k]:.0f} mm from the base, beyond the reach of the "
                         f"{name} ({longest:.0f} mm): the pose is in another unit or from another frame", (int(ids[k]),)))
    found += _square_size(session)
    return found


def _square_size(session) -> list:
    """The square-size implausibility (``board_scale.judge_square_size``), when it refuses."""
    target = session.target
    with_points = [p.points_mm for p in session.postures if p.points_mm is not None]
    if getattr(target, "kind", "checkerboard") == "circles":
        return []  # not a square grid: the board fit checks its spacing
    if not (target is not None and target.square_mm and len(with_points) == len(session.postures) and with_points
            and all(len(points) == target.count for points in with_points)):
        return []
    with np.errstate(all="ignore"):
        judgement = judge_square_size(np.array(with_points), target.corners, target.square_mm)
    if judgement.verdict in ("units", "square_size"):
        return [Implausibility("square_size", judgement.message)]
    return []


def check_plausible(session: Session, tool02base: np.ndarray) -> None:
    """Refuse a session whose lengths are not plausible millimetres.

    Raises
    ------
    UnitsError
        With the first :class:`Implausibility`'s message (and how many more there are).
    """
    found = implausibilities(session, tool02base)
    if found:
        more = f" ({len(found) - 1} more like it)" if len(found) > 1 else ""
        raise UnitsError(found[0].message + more)


def session_in_mm(session: Session, units: str = "mm") -> Session:
    """The session with its lengths converted from ``units`` to mm (a copy; ``mm`` returns it as is).

    Positions of ``tool0_in_base``, ``points_mm`` and the translation of ``target_in_camera`` are
    scaled; joint angles and ``target.square_mm`` are not (the square size is checked against the
    converted corners, so a square size in the wrong unit is still refused).
    """
    if units not in UNITS:
        raise UnitsError(f"units must be one of {', '.join(UNITS)}; got {brief(units)}")
    factor = UNITS[units]
    if factor == 1.0:
        return session

    def scaled(transform):
        if transform is None:
            return None
        out = np.array(transform, float)
        out[:3, 3] *= factor
        return out

    postures = [replace(p, tool0_in_base=scaled(p.tool0_in_base), target_in_camera=scaled(p.target_in_camera),
                        points_mm=None if p.points_mm is None else np.asarray(p.points_mm, float) * factor)
                for p in session.postures]
    return replace(session, postures=postures)
