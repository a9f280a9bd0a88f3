"""Which layout reading of a log to keep, once each has been read as a session: the best, or a refusal.

Every pairing the layout search proposes (``layout_search``) that yields two equally long lists of
valid poses is read by the convention inference; the ones it refuses are out. Of the rest:

1. Pairings that give the same session (the same set-up and poses within 1e-6 mm and 1e-9) are
   one outcome (a tagged row read per tag or per row, say).
2. **Which list is the robot's** when no name says it: swapping the two lists fits the invariants
   exactly as well (``B X^-1 = X^-1 A``), so the content decides: the camera sees the board, so
   the board positions in the camera lie in a narrow cone about its optical axis (+z), and a
   robot's flange positions about its base do not (on generated stations: 20 deg at most against
   41 deg at least). The reading whose cone is at most 50 deg and 1.5 times narrower than the
   swapped reading's is kept; otherwise the documented layout
   (robot pose first in a row) is kept when the pair holds it, and
   the import is refused naming ``--robot-rows`` when it does not.
3. Of different outcomes, the one whose worst invariant misfit (against its floor: 1 deg, 2 deg,
   8 %) is three times below every other's is kept, and the runner-up is said; two within that
   factor are within the noise: the import is refused naming ``--robot-rows`` or ``--format``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...base import SessionError
from ...calibration import Session
from .log_group import Group

__all__ = ["Candidate", "choose_layout", "CONE_MAX_DEG", "CONE_FACTOR", "NOISE_FACTOR"]

#: Widest cone (deg) about the camera's +z that the boards it sees fill.
CONE_MAX_DEG = 50.0
#: The camera list's cone must be this much narrower than the swapped reading's.
CONE_FACTOR = 1.5
#: A layout wins when its misfit is this factor below every other layout's.
NOISE_FACTOR = 3.0


@dataclass(eq=False)
class Candidate:
    """One pairing: the robot and camera lists, the reading in words and what names it."""

    robot: Group
    camera: Group
    words: str
    robot_name: str = ""
    camera_name: str = ""
    cost: int = 0
    robot_first: bool = True
    swap: int | None = None
    session: Session | None = None
    stage: int = 0
    documented: bool = False
    extra: dict | None = None

    def matches(self, robot_rows: str) -> bool:
        """Whether ``--robot-rows`` names this pairing's robot list (its tag or file, or first/second)."""
        want = "".join(ch for ch in robot_rows.lower() if ch.isalpha())
        if want in ("first", "second"):
            return self.robot_first == (want == "first")
        name = "".join(ch for ch in self.robot_name.lower() if ch.isalpha())
        return bool(name) and name == want

    @property
    def read(self) -> Session:
        """The session this pairing was read as (only pairings that were read are compared)."""
        if self.session is None:
            raise SessionError(f"the pairing {self.words} was not read as a session")
        return self.session

    def badness(self) -> float:
        """The chosen reading's worst misfit against its floor (``readings.badness``, from the record)."""
        scores = self.read.extra["import"]["inference"]["scores"]
        values = [scores.get("angle_gap_deg"), (scores.get("axis_misfit_deg") or 0.0) / 2.0,
                  (scores.get("translation_misfit") or 0.0) / 0.08]
        values = [np.inf if v is None else float(v) for v in values]
        return max(values)

    def cone_deg(self) -> float:
        """Widest angle (deg) between a board position in the camera and the camera's axis (+z)."""
        t = np.array([p.target_in_camera[:3, 3] for p in self.read.postures])
        cos = t[:, 2] / np.maximum(np.linalg.norm(t, axis=1), 1e-12)
        return float(np.degrees(np.max(np.arccos(np.clip(cos, -1.0, 1.0)))))

    def poses(self) -> tuple:
        s = self.read
        return (s.setup, np.array([p.tool0_in_base for p in s.postures]), np.array([p.target_in_camera for p in s.postures]))


def _same(a: Candidate, b: Candidate) -> bool:
    sa, ta, ca = a.poses()
    sb, tb, cb = b.poses()
    return sa == sb and ta.shape == tb.shape and bool(np.allclose(ta, tb, atol=1e-6) and np.allclose(ca, cb, atol=1e-6))


def _sides_decided(results: list, where) -> list:
    """Of each pair of swapped readings, the one whose camera list sees the board (module docstring)."""
    out, by_swap = [], {}
    for c in results:
        if c.swap is None:
            out.append(c)
        else:
            by_swap.setdefault(c.swap, []).append(c)
    for pair in by_swap.values():
        if len(pair) == 1:
            out.append(pair[0])
            continue
        narrow, wide = sorted(pair, key=lambda c: c.cone_deg())
        if narrow.cone_deg() <= CONE_MAX_DEG and wide.cone_deg() >= CONE_FACTOR * narrow.cone_deg():
            narrow.session.extra["import"]["notes"].append(
                f"the camera poses are the list {narrow.camera_name or 'read second'!r}: its boards lie within "
                f"{narrow.cone_deg():.0f} deg of the camera axis, the other list's within {wide.cone_deg():.0f} deg")
            out.append(narrow)
        elif any(c.documented for c in pair):
            kept = next(c for c in pair if c.documented)
            kept.session.extra["import"]["notes"].append(
                "the robot poses read as the table reader's layout places them (the board positions do not tell the two "
                "lists apart); pass --robot-rows to choose")
            out.append(kept)
        else:
            out.append(_Undecided(pair, where))
    return out


class _Undecided:
    """Two swapped readings the content cannot tell apart: kept as one candidate that refuses when chosen."""

    def __init__(self, pair: list, where):
        self.pair, self.where = pair, where

    def badness(self) -> float:
        return min(c.badness() for c in self.pair)

    def refuse(self):
        a, b = self.pair
        raise SessionError(
            f"{self.where}: cannot tell which list holds the robot poses ({a.words}; board cone "
            f"{a.cone_deg():.0f} deg one way, {b.cone_deg():.0f} deg the other): pass --robot-rows "
            f"{a.robot_name or 'first'} or --robot-rows {b.robot_name or 'second'}")


def choose_layout(results: list, where):
    """The session of the best layout reading (module docstring); its reading and runner-up in its notes.

    Raises
    ------
    SessionError
        When two different readings fit within the noise, or the side of two lists is undecided.
    """
    distinct = []
    for c in sorted(results, key=lambda c: (c.badness(), c.cost)):
        if not any(isinstance(d, Candidate) and d.swap is None and c.swap is None and _same(c, d) for d in distinct):
            distinct.append(c)
    ranked = sorted(_sides_decided(distinct, where), key=lambda c: c.badness())
    ranked = _merge_same(ranked)
    best = ranked[0]
    if isinstance(best, _Undecided):
        best.refuse()
    notes = best.session.extra["import"]["notes"]
    notes.insert(0, f"layout: {best.words}" + (f" (robot poses: '{best.robot_name}')" if best.robot_name else ""))
    if len(ranked) > 1:
        runner = ranked[1]
        words = runner.words if isinstance(runner, Candidate) else runner.pair[0].words
        if runner.badness() < NOISE_FACTOR * max(best.badness(), 0.1):
            raise SessionError(
                f"{where}: two layouts fit within the noise: {best.words} (misfit {best.badness():.2f}) and {words} "
                f"(misfit {runner.badness():.2f}); pass --robot-rows, or --format with a header naming the columns")
        notes.insert(1, f"layout runner-up: {words} (misfit {runner.badness():.2f} against {best.badness():.2f})")
    best.session.extra["import"]["layout"]["runner_up"] = None if len(ranked) == 1 else (
        ranked[1].words if isinstance(ranked[1], Candidate) else ranked[1].pair[0].words)
    return best.session


def _merge_same(ranked: list) -> list:
    """Candidates that give the same session count once (the first, the best-scored)."""
    out = []
    for c in ranked:
        if isinstance(c, Candidate) and any(isinstance(d, Candidate) and _same(c, d) for d in out):
            continue
        out.append(c)
    return out
