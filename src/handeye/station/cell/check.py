"""``handeye cell check``: the robot targets of a program checked against the cell and the arm itself.

Each row of a joints file (the robot's axis angles, deg, one posture a line) is checked as the planner
checks its postures, and with ``moves`` each joint-interpolated move between consecutive rows as the
planner checks its moves: the same :class:`~handeye.robot.clearance.CellGuard` (the station's
``cell`` section: keep-out volumes, carried bodies, margin, path step; the robot file's links and
self-collision pairs). The board's stand is not among the volumes (its pose comes from a capture).
A row outside the joint limits is not clear (``closest``: ``joint limits``) and its moves are not checked.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ...robot import CellGuard
from ...base import HandEyeError
from ...robot import RobotModel
from ..csv_values import is_header, parse_value, value_problem

__all__ = ["CellCheckResult", "JointRows", "check_joints", "read_joints_csv"]


class JointRows(NamedTuple):
    """What :func:`read_joints_csv` read: the rows, their line numbers and the header line it skipped.

    Attributes
    ----------
    rows : ndarray, shape (n, dof)
        Axis angles (deg), one posture a row.
    lines : list of int
        The file's line number (1-based) of each row.
    header : tuple of (int, str) or None
        ``(line number, text)`` of the line taken as a header (no field of it looks like a number), if any.
    """

    rows: np.ndarray
    lines: list
    header: tuple | None = None


def read_joints_csv(path: str | Path, dof: int) -> JointRows:
    """Rows ``(n, dof)`` of axis angles (deg), their line numbers and the header line skipped, if any.

    Blank lines and ``#`` comments are skipped; the first other line is a header only when none of its
    fields looks like a number (:func:`~handeye.station.csv_values.is_header`). Every value is a finite
    number (:func:`~handeye.station.csv_values.parse_value`); a row that is not ``dof`` of them is refused
    (HandEyeError, one line naming the line and what is wrong)."""
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise HandEyeError(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}") from None
    rows, lines, header = [], [], None
    for number, cells in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in cells if c.strip()]
        if not cells or cells[0].startswith("#"):
            continue
        if not rows and header is None and is_header(cells):  # one header line before the first row
            header = (number, ",".join(cells))
            continue
        problems = [value_problem(c) for c in cells]
        bad = next((p for p in problems if p), None)
        if bad:
            raise HandEyeError(f"{path} line {number}: {bad}; give the axis angles in deg, {dof} a line, comma "
                               "separated (a header line may hold no number)")
        if len(cells) != dof:
            raise HandEyeError(f"{path} line {number}: expected {dof} axis angles (deg), got {len(cells)} values")
        rows.append([parse_value(c) for c in cells])
        lines.append(number)
    if not rows:
        raise HandEyeError(f"{path} holds no row of axis angles (deg, {dof} a line)")
    return JointRows(np.array(rows, float), lines, header)


@dataclass
class CellCheckResult:
    """The verdict of every row and move: dicts as written to JSON (see :func:`check_joints`)."""

    postures: list = field(default_factory=list)
    moves: list = field(default_factory=list)
    margin_mm: float = 0.0

    @property
    def clear(self) -> bool:
        return all(p["clear"] for p in self.postures) and all(m["clear"] for m in self.moves)

    def to_dict(self) -> dict:
        return {"clear": self.clear, "margin_mm": self.margin_mm, "postures": self.postures, "moves": self.moves}

    def lines(self) -> list[str]:
        """One line per row and move: ``row 3 (line 5): NOT CLEAR: camera against link 3: 12 mm into it``."""
        out = []
        for p in self.postures:
            out.append(f"row {p['row']} (line {p['line']}): {'clear' if p['clear'] else 'NOT CLEAR'}: {p['text']}")
        for m in self.moves:
            out.append(f"move row {m['from_row']} -> {m['to_row']}: {'clear' if m['clear'] else 'NOT CLEAR'}: {m['text']}")
        bad = sum(not p["clear"] for p in self.postures) + sum(not m["clear"] for m in self.moves)
        out.append(f"{'all clear' if not bad else f'{bad} not clear'} ({len(self.postures)} postures, "
                   f"{len(self.moves)} moves, margin {self.margin_mm:g} mm)")
        return out


def _entry(found, margin_mm: float) -> dict:
    """``clear``, ``closest``, ``distance_mm``, ``kind`` and ``text`` of the closest approach ``found``."""
    if found is None:
        return {"clear": True, "closest": None, "distance_mm": None, "kind": None, "text": "nothing watched"}
    distance = round(float(found.clearance_mm), 1)
    return {"clear": bool(found.clearance_mm >= margin_mm), "closest": found.pair, "distance_mm": distance,
            "kind": found.kind, "text": found.describe()}


def _move_closest(guard: CellGuard, a, b):
    """The closest approach along the move ``a -> b`` at its samples (for a clear move's report)."""
    samples = guard.path_samples(a, b)
    cell, own = guard.clearances(samples)
    k = int(np.argmin(np.minimum(cell, own)))
    found = guard.closest(samples[k])
    if found is None:
        return None
    from dataclasses import replace

    return replace(found, at=float(k) / max(len(samples) - 1, 1))


def check_joints(robot: RobotModel, guard: CellGuard, joints: np.ndarray, lines: Sequence | None = None,
                 moves: bool = False) -> CellCheckResult:
    """Check postures ``(n, k)`` (deg) and, with ``moves``, the moves between consecutive ones.

    Returns
    -------
    CellCheckResult
        ``postures``: ``{row, line, clear, closest ("camera - link 3"), distance_mm, kind, text}`` (``row``
        0-based, ``line`` the file's); ``moves``: ``{from_row, to_row, clear, closest, distance_mm, at, kind,
        text}``, ``at`` the fraction of the move (0 start, 1 end) where it is closest (or first too close).
    """
    joints = np.asarray(joints, float).reshape(-1, robot.dof)
    lines = list(lines) if lines is not None else list(range(1, len(joints) + 1))
    result = CellCheckResult(margin_mm=guard.margin_mm)
    inside = []
    for row, q in enumerate(joints):
        problems = robot.limit_violations(q)
        inside.append(not problems)
        if problems:
            entry = {"clear": False, "closest": "joint limits", "distance_mm": None, "kind": "limits",
                     "text": "; ".join(problems)}
        else:
            entry = _entry(guard.closest(q), guard.margin_mm)
        result.postures.append({"row": row, "line": lines[row], **entry})
    if moves:
        pairs = [(i, i + 1) for i in range(len(joints) - 1) if inside[i] and inside[i + 1]]
        found = dict(zip(pairs, guard.moves_violations([(joints[i], joints[j]) for i, j in pairs])))
        for i in range(len(joints) - 1):
            if (i, i + 1) not in found:
                entry = {"clear": False, "closest": "joint limits", "distance_mm": None, "at": None, "kind": "limits",
                         "text": "an end is outside the joint limits: not checked"}
            else:
                violation = found[i, i + 1] or _move_closest(guard, joints[i], joints[i + 1])
                entry = {**_entry(violation, guard.margin_mm), "at": None if violation is None else round(violation.at, 3)}
                entry["clear"] = found[i, i + 1] is None
                if violation is not None:
                    entry["text"] += f" at {violation.at:.0%} of the move"
            result.moves.append({"from_row": i, "to_row": i + 1, **entry})
    return result
