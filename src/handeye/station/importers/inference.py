"""Which reading of a hand-eye log is the right one: decided by the data, said in words, never guessed.

A log gives, per posture, numbers for the robot and numbers for the camera. A *reading* says what
they mean: the rotation convention of each side (Euler order, quaternion order, matrix layout; see
``conventions``), the direction of each pose (the flange in the base or the base in the flange; the
board in the camera or the camera in the board), the set-up (eye-in-hand or eye-to-hand) and the
length unit of each side (m or mm). Every reading is scored by the X-free invariants of
``AX = XB`` (``calibration.invariants``) and by physical plausibility, and the decision follows
these rules, in order:

1. **Flags win.** ``--euler``, ``--quaternion-order``, ``--robot-pose``, ``--camera-pose``,
   ``--setup`` and ``--units`` keep only the readings they allow; when the data contradict a flag
   the import says so with the numbers (a warning) and still reads as told. When no reading fits
   at all (misfits beyond the noise of any real log), flags are obeyed only if they leave one
   reading; otherwise the import is refused with the misfit (the data cannot choose).
2. **Invariants.** The rotation conventions are screened first by what neither ``X``, the set-up
   nor an inversion changes (``readings.screen``): the median gap between the rotation angles of
   the robot's and the camera's relative motions, and between their screw pitches. The pairs of
   conventions within the noise of the best are then read in every direction and set-up, and a
   reading is *consistent* when the angles agree (median gap), one rotation carries every camera
   rotation axis onto the robot's (axis misfit) and one translation fits (translation misfit, as a
   fraction of the motion), each within three times the best reading's value (the noise of the
   data) or under a floor (1 deg, 2 deg, 8 %), and its robot turns enough to be tested (half the
   testable pairs of the best-turning reading); and, when the best fits under the floors, its
   misfits do not exceed the best one's posture by posture beyond the data's noise (a paired test,
   ``noise_test``): under the floors is not yet "equally well". Readings that give the same session (same set-up,
   the same poses within the noise) count as one outcome.
3. **Plausibility**, only where physics leaves a genuine ambiguity. Inverting both pose sets, or
   one pose set together with the set-up, fits the invariants exactly as well: what changes is
   which object rides on the flange. So (a) the object on the flange (camera eye-in-hand, board
   eye-to-hand) is the one close to it: a reading that puts it 2.5 times farther away than the
   alternative puts its object is dropped; (b) the camera sees the board: of "board in camera" and
   "camera in board" the board is the one in front of the camera (within 50 deg of +z, or +x for
   ROS body frames) and in a narrow cone (the camera's field of view); a reading is dropped when
   the other one is in front and no wider, or is 1.8 times narrower.
4. **Declarations** break what is left: the format's documented meaning (MoveIt's
   ``T_cam_target``, ViSP's ``cPo``, a header's ``a b c``, a key ``T_base_eef``, a file name), the
   set-up the file declares, or the plain format's default (files written by hand). They decide
   only when exactly one remaining outcome matches all of them.
5. Otherwise the import is **refused**, naming the flag that decides.

The units of each side come from the magnitudes (median translation under 20 -> metres), must be
plausible (flange 50 mm .. 5 m from the base, board 30 mm .. 10 m from the camera) and must agree
with each other by the screw pitches (an X-free length ratio) within a factor 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...base import SessionError
from ...calibration import SETUPS
from .ambiguity import AmbiguousReading, choice_lines
from .inference_table import format_table, inference_record, reading_words, table_rows
from .readings import (
    AXIS_MAX_DEG,
    CAMERA_POSES,
    GAP_MAX_DEG,
    TRANSLATION_MAX,
    METRES_BELOW,
    ROBOT_POSES,
    SCALE,
    SCALE_FACTOR,
    Constraints,
    Reading,
    Side,
    SideReading,
    badness,
    check_flag,
    mark_consistency,
    mark_outcomes,
    mark_plausibility,
    pairs_to_evaluate,
    pose_outcome,
    score_readings,
    scores_words,
    screen,
    side_units,
)

__all__ = [
    "ROBOT_POSES",
    "CAMERA_POSES",
    "SideReading",
    "Side",
    "Constraints",
    "Reading",
    "Inference",
    "infer",
    "format_table",
    "METRES_BELOW",
]


@dataclass
class Inference:
    """The chosen reading, the poses it gives (mm, flange in base, target in camera) and the record."""

    robot_mm: np.ndarray
    camera_mm: np.ndarray
    setup: str
    chosen: Reading
    table: list
    record: dict
    notes: list = field(default_factory=list)
    warnings: list = field(default_factory=list)


def _flag_names(readings: list, robot: Side, camera: Side) -> list:
    """The flags that tell the given readings apart (in the order a user would reach for them)."""
    names = []
    if len({robot.readings[r.robot].key for r in readings}) > 1 or len({camera.readings[r.camera].key for r in readings}) > 1:
        keys = {robot.readings[r.robot].key for r in readings} | {camera.readings[r.camera].key for r in readings}
        names.append("--quaternion-order" if all(k.startswith("quaternion") for k in keys) else "--euler")
    for attr, flag in (("robot_pose", "--robot-pose"), ("camera_pose", "--camera-pose"), ("setup", "--setup"),
                       ("units", "--units")):
        if len({getattr(r, attr) for r in readings}) > 1:
            names.append(flag)
    return names


def infer(robot: Side, camera: Side, constraints: Constraints = Constraints()) -> Inference:
    """Choose the reading of a log (module docstring); refuse with the deciding flag when the data cannot.

    Parameters
    ----------
    robot, camera : Side
        Every reading of each side's numbers (at least one each), the same number of postures;
        readings a flag excludes carry ``allowed=False`` (they are scored, to say what the data say).
    constraints : Constraints
        The user's flags and the file's declarations.

    Returns
    -------
    Inference

    Raises
    ------
    SessionError
        One line: no reading fits (and no flag asked for one), several fit and the data cannot
        tell them apart (naming the flag that decides), or lengths in no plausible unit.
    """
    c = constraints
    check_flag("setup", c.setup, SETUPS)
    check_flag("robot_pose", c.robot_pose, ROBOT_POSES)
    check_flag("camera_pose", c.camera_pose, CAMERA_POSES)
    check_flag("units", c.units, tuple(SCALE))
    if not robot.readings or not camera.readings:
        raise SessionError("no reading of the poses is possible")
    if not any(r.allowed for r in robot.readings) or not any(r.allowed for r in camera.readings):
        raise SessionError("the rotation convention given (--euler, --quaternion-order) does not apply to these poses")
    n = len(robot.readings[0].poses)
    warnings_, notes = [], []
    units = side_units(robot, camera, c, warnings_)
    gaps, pitches = screen(robot, camera, units, n)
    readings = score_readings(robot, camera, pairs_to_evaluate(robot, camera, gaps, pitches), gaps, units, n)
    mark_consistency(readings, n, notes)
    mark_plausibility(readings)
    mark_outcomes(robot, camera, readings, n)
    chosen, how, pool = _choose(robot, camera, c, readings, warnings_)
    _check_scale(chosen, c, n, warnings_)
    for r in readings:
        r.verdict = _verdict(r, chosen, _allowed(robot, camera, c, r))
    a, b = pose_outcome(robot, camera, chosen)
    table = table_rows(readings, chosen)
    decided_by = {"invariants", how} if chosen.consistent else {"flags"}
    record = inference_record(robot, camera, chosen, table, decided_by)
    if how == "declarations":
        others = [r for r in pool if r.outcome != chosen.outcome] or [
            r for r in readings if r.consistent and r.plausible and r.outcome != chosen.outcome]
        if others:
            notes.append(f"the data alone also fit {reading_words(robot, camera, others[0])}; read as the file "
                         f"declares (pass {' or '.join(_flag_names([chosen, others[0]], robot, camera))} to override)")
    return Inference(a, b, chosen.setup, chosen, table, record, notes, warnings_)


def _allowed(robot: Side, camera: Side, c: Constraints, r: Reading) -> bool:
    """Does reading ``r`` keep to every flag?"""
    return (robot.readings[r.robot].allowed and camera.readings[r.camera].allowed
            and (c.setup is None or r.setup == c.setup) and (c.robot_pose is None or r.robot_pose == c.robot_pose)
            and (c.camera_pose is None or r.camera_pose == c.camera_pose))


def _choose(robot: Side, camera: Side, c: Constraints, readings: list, warnings_: list) -> tuple:
    """``(chosen reading, the rule that decided, the readings left)`` (rules 1-5 of the module docstring).

    Raises
    ------
    SessionError
        Nothing fits and no flag asked for it; or several outcomes are left (naming the flags).
    """
    flags_given = (any(v is not None for v in (c.setup, c.robot_pose, c.camera_pose))
                   or not all(x.allowed for x in robot.readings + camera.readings))
    if not any(r.consistent for r in readings) and not flags_given:
        best = min(readings, key=badness)
        raise SessionError(
            f"no reading of the poses fits a rigid camera mount (best: {reading_words(robot, camera, best)}: "
            f"{scores_words(best)}); check that robot and camera poses are paired posture by posture, or give "
            f"the conventions (--euler, --quaternion-order, --robot-pose, --camera-pose, --setup)")
    if not any(r.consistent for r in readings):
        _refuse_unless_pinned(robot, camera, c, readings)
    free, free_how = _decide(robot, camera, c, readings)
    allowed = [r for r in readings if _allowed(robot, camera, c, r)]
    pool, how = _decide(robot, camera, c, allowed)
    free_decided = free_how in ("invariants", "plausibility", "declarations")
    other = min(free, key=badness) if free_decided else None
    if how in ("none fits", "implausible") and flags_given:  # read as told, say what the data say
        chosen = min(allowed, key=lambda r: (not _declared_match(robot, camera, c, r, flags_only=True),
                                             not r.consistent, badness(r)))
        what = (f"the poses do not fit it ({scores_words(chosen)})" if not chosen.consistent
                else f"{reading_words(robot, camera, chosen)} is {chosen.why.replace('not plausible: ', 'implausible: ')}")
        fits = f", while {reading_words(robot, camera, other)} fits ({scores_words(other)})" if other else ""
        warnings_.append(f"{_flags_text(robot, camera, c)}: {what}{fits}; read as given")
        return chosen, "flags", pool
    if how in ("undecided", "implausible"):
        outcomes_left = sorted({r.outcome for r in pool})
        best_of = sorted((min((r for r in pool if r.outcome == k), key=badness) for k in outcomes_left), key=badness)
        options = [reading_words(robot, camera, r) for r in best_of[:3]]
        fit = "equally well" if how == "undecided" else "(none of them plausibly)"
        if len(robot.readings[0].poses) < 3:
            raise SessionError(f"only {len(robot.readings[0].poses)} posture(s): at least 3 are needed to tell the pose "
                               f"conventions from the data (and to calibrate)")
        names = _flag_names(pool, robot, camera) or ["--setup"]
        raise AmbiguousReading(
            f"the data fit {len(outcomes_left)} readings {fit} ({'; or '.join(options)}); "
            f"pass {' or '.join(names)} to decide", choice_lines(robot, camera, best_of, names))
    chosen = min(pool, key=lambda r: (not _declared_match(robot, camera, c, r), badness(r)))
    if flags_given and other is not None and free[0].outcome != chosen.outcome:
        warnings_.append(
            f"{_flags_text(robot, camera, c)}: the data point to another reading ({reading_words(robot, camera, other)}"
            f": {other.why or 'fits and is plausible'}; the reading given: {chosen.why or 'fits too'}); read as given")
    return chosen, ("flags" if flags_given and not free_decided else how), pool


def _refuse_unless_pinned(robot: Side, camera: Side, c: Constraints, readings: list) -> None:
    """Nothing fits a rigid mount, and flags were given: refuse unless they leave one reading (read as
    told, with a warning); the data cannot choose among the rest (issue 40.4g: never pick silently).

    Raises
    ------
    SessionError
        Naming the best misfit and the flags that would pin the reading down.
    """
    allowed = [r for r in readings if _allowed(robot, camera, c, r)]
    if len({(r.robot, r.camera, r.robot_pose, r.camera_pose, r.setup) for r in allowed}) <= 1:
        return
    best = min(allowed, key=badness)
    left = [flag for flag, value in (("--setup", c.setup), ("--robot-pose", c.robot_pose),
                                     ("--camera-pose", c.camera_pose)) if value is None]
    raise SessionError(
        f"no reading of the poses fits a rigid camera mount, with the flags given or without (best the flags allow: "
        f"{reading_words(robot, camera, best)}: {scores_words(best)}; real logs misfit by under {GAP_MAX_DEG:g} deg, "
        f"{AXIS_MAX_DEG:g} deg, {100 * TRANSLATION_MAX:.0f} %), so the data cannot choose among the readings the "
        f"flags leave: check that robot and camera poses are paired posture by posture"
        + (f", or give {', '.join(left)} too to read it exactly as told" if left else ""))


def _decide(robot: Side, camera: Side, c: Constraints, pool: list) -> tuple[list, str]:
    """The readings of the one outcome the rules leave, and which rule decided.

    The second value is ``invariants``, ``plausibility`` or ``declarations`` when one outcome is left;
    ``none fits`` (no consistent reading), ``implausible`` (every consistent reading implausible and
    the declarations do not single one out) or ``undecided`` (several plausible outcomes) otherwise.
    """
    consistent = [r for r in pool if r.consistent]
    if not consistent:
        return [], "none fits"
    if len({r.outcome for r in consistent}) == 1:
        return consistent, "invariants"
    plausible = [r for r in consistent if r.plausible]
    candidates = plausible or consistent
    if plausible and len({r.outcome for r in plausible}) == 1:
        return plausible, "plausibility"
    matching = [r for r in candidates if _declared_match(robot, camera, c, r)]
    if matching and len({r.outcome for r in matching}) == 1:
        return matching, "declarations"
    return candidates, ("undecided" if plausible else "implausible")


def _check_scale(chosen: Reading, c: Constraints, n: int, warnings_: list) -> None:
    """The two sides' units must agree (screw pitches) once the reading is chosen."""
    scale = chosen.scale
    if n < 3 or not chosen.consistent or not np.isfinite(scale) or scale <= 0 or 1 / SCALE_FACTOR <= scale <= SCALE_FACTOR:
        return
    message = (f"robot and camera lengths disagree by a factor {scale:.4g} (screw pitches of the relative motions) "
               f"once read as robot {chosen.units[0]}, camera {chosen.units[1]}")
    if c.units is None:
        raise SessionError(message + "; pass --units (and check that both files hold lengths in m or mm)")
    warnings_.append(f"--units {c.units}: {message}; read as given")


def _verdict(r: Reading, chosen: Reading, allowed: bool) -> str:
    if r is chosen:
        return "chosen"
    if r.consistent and r.outcome == chosen.outcome:
        return "fits (same result)"
    if r.consistent and r.plausible and not allowed:
        return "fits; excluded by a flag"
    if r.consistent and r.plausible:
        return "fits; not what the file declares"
    return r.why or "does not fit"


def _flags_text(robot: Side, camera: Side, c: Constraints) -> str:
    parts = [f"--{k.replace('_', '-')} {v}" for k, v in (("setup", c.setup), ("robot_pose", c.robot_pose),
                                                       ("camera_pose", c.camera_pose)) if v]
    if not all(x.allowed for x in robot.readings + camera.readings):
        parts.append(c.conventions_given or "the rotation convention given")
    return ", ".join(parts)


def _declared_match(robot: Side, camera: Side, c: Constraints, r: Reading, flags_only: bool = False) -> bool:
    """Does reading ``r`` match everything the file and the format declare?"""
    if flags_only:  # reading as told: what is not told stays as declared, else as most logs hold it
        return ((c.robot_pose is not None or r.robot_pose == (robot.declared_direction or "flange_in_base"))
                and (c.camera_pose is not None or r.camera_pose == (camera.declared_direction or "target_in_camera")))
    setup = c.declared_setup or c.default_setup
    return ((robot.declared_direction is None or r.robot_pose == robot.declared_direction)
            and (camera.declared_direction is None or r.camera_pose == camera.declared_direction)
            and (setup is None or r.setup == setup)
            and (not any(x.declared for x in robot.readings) or robot.readings[r.robot].declared)
            and (not any(x.declared for x in camera.readings) or camera.readings[r.camera].declared))
