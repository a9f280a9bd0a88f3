"""What to tell the operator when a session's lengths are not in millimetres.

The verdict (``station.report.quality``) is the second line of defence against lengths in the wrong unit:
a session refused before solving never reaches it, but one that gets through must not come back with
advice to "re-capture postures" when the fix is the units. :func:`units_advice` reads the unit
findings of ``calibration.diagnostics.find_unit_problems`` on a problem's poses and turns them into
one instruction that names the side (robot poses, board poses, one posture) and the unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...calibration import find_unit_problems
from ...calibration import HandEyeProblem, hand_poses

__all__ = ["UnitsAdvice", "units_advice"]

_SIDES = {"robot": "the robot poses (tool0_in_base)", "camera": "the board poses (board points in the camera)"}


@dataclass(frozen=True)
class UnitsAdvice:
    """The units problem of a session, as one instruction.

    Attributes
    ----------
    text : str
        One line: what looks wrong and what to do, e.g. ``the robot poses (tool0_in_base) look like
        metres and the board poses like mm: fix the units (lengths in mm)``.
    postures : tuple of int
        The postures concerned when only some are in another unit (empty when a whole side is).
    findings : list
        The ``calibration.diagnostics.Finding`` objects behind it.
    """

    text: str
    postures: tuple
    findings: list


def _side_text(findings) -> str | None:
    """Advice for findings about a whole side (no postures named), or None."""
    small, large, ratio = set(), set(), None
    for f in findings:
        part, median = f.values.get("part"), f.values.get("median_mm")
        if part in _SIDES and median is not None:
            (small if median < 1000.0 else large).add(part)  # findings lie below 20 mm or above 20 m
        elif "pitch_ratio" in f.values:
            ratio = float(f.values["pitch_ratio"])
    if small == {"robot", "camera"}:
        return ("the session's lengths look like metres (robot poses and board points alike): lengths must be in mm; "
                "re-capture or re-import the session in mm")
    if small == {"robot"} or (not small and ratio is not None and ratio < 1):
        return f"{_SIDES['robot']} look like metres and the board poses like mm: fix the units (lengths in mm)"
    if small == {"camera"} or (not small and ratio is not None and ratio > 1):
        return (f"{_SIDES['camera']} look like metres and the robot poses like mm: fix the units (lengths in mm; "
                f"check the stereo calibration's baseline T is in mm)")
    if large:
        sides = " and ".join(_SIDES[p] for p in sorted(large))
        return f"{sides} are implausibly large for millimetres: fix the units (lengths in mm)"
    return None


def _posture_text(findings) -> tuple[str, tuple]:
    postures = sorted({int(p) for f in findings for p in f.postures})
    parts = sorted({f.values.get("part") for f in findings} & set(_SIDES))
    which = " and ".join(_SIDES[p].split(" (")[0].replace("poses", "pose") for p in parts) or "the pose"
    smaller = [f for f in findings if f.values.get("distance_mm", 1.0) < f.values.get("median_mm", 0.0)]
    unit = "metres" if smaller and len(smaller) == len(findings) else "another unit"
    label = "posture" if len(postures) == 1 else "postures"
    names = ", ".join(map(str, postures))
    return (f"{label} {names}: {which} look{'s' if len(postures) == 1 else ''} written in {unit} unlike the others: "
            f"fix the units of {'that posture' if len(postures) == 1 else 'those postures'} (lengths in mm) or delete "
            f"{'it' if len(postures) == 1 else 'them'}", tuple(postures))


def units_advice(problem: HandEyeProblem) -> UnitsAdvice | None:
    """The units problem of a problem's poses, or ``None`` when their lengths look like millimetres.

    Parameters
    ----------
    problem : HandEyeProblem
        Its hand poses and board poses (``target2cam``) are checked with
        ``calibration.diagnostics.find_unit_problems``.

    Returns
    -------
    UnitsAdvice or None
    """
    tool0_in_base = hand_poses(problem.hand, problem.setup)  # the map is its own inverse for either set-up
    try:
        findings = [f for f in find_unit_problems(tool0_in_base, problem.target2cam,
                                                  [int(i) for i in problem.posture_ids]) if f.kind == "units"]
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not findings:
        return None
    whole = [f for f in findings if not f.postures]
    if whole:
        text = _side_text(whole) or (str(whole[0]).rstrip(".") + ": fix the units (lengths in mm)")
        return UnitsAdvice(text, (), findings)
    text, postures = _posture_text(findings)
    return UnitsAdvice(text, postures, findings)
