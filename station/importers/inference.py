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
   the import says so with the numbers (a warning) and still reads as told.
2. **Invariants.** A reading is *consistent* when the rotation angles of the relative motions agree
   (median gap), one rotation carries every camera rotation axis onto the robot's (axis misfit) and
   one translation fits (translation misfit, as a fraction of the motion), each within three times
   the best reading's value (the noise of the data) and a floor (1 deg, 2 deg, 8 %). Readings that
   give the same session (same set-up, the same poses within the noise) count as one outcome.
3. **Plausibility**, only where physics leaves a genuine ambiguity. Inverting both pose sets, or
   one pose set together with the set-up, fits the invariants exactly as well: what changes is
   which object rides on the flange. So (a) the object on the flange (camera eye-in-hand, board
   eye-to-hand) is the one close to it: a reading that puts it 2.5 times farther away than the
   alternative puts its object is dropped; (b) the camera sees the board: of "board in camera" and
   "camera in board" the board is the one in front of the camera (within 50 deg of +z, or +x for
   ROS body frames) and in a narrow cone (the camera's field of view); a reading is dropped when
   the other one is in front and no wider, or is 1.8 times narrower.
4. **Declarations** break what is left: the format's documented meaning (MoveIt's
   ``T_cam_target``, ViSP's ``cPo``, a header's ``qw``), the set-up the file declares or the
   format's default. They decide only when exactly one remaining outcome matches all of them.
5. Otherwise the import is **refused**, naming the flag that decides.

The units of each side come from the magnitudes (median translation under 20 -> metres), must be
plausible (flange 50 mm .. 5 m from the base, board 30 mm .. 10 m from the camera) and must agree
with each other by the screw pitches (an X-free length ratio) within a factor 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...calibration.errors import SessionError
from ...calibration.invariants import fit_hand_eye, pair_indices, relative_angles_deg
from ...calibration.problem import EYE_IN_HAND, EYE_TO_HAND, SETUPS
from ...calibration.transforms import invert_transforms, rotation_error_deg

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

ROBOT_POSES = ("flange_in_base", "base_in_flange")
CAMERA_POSES = ("target_in_camera", "camera_in_target")
_POSE_WORDS = {"flange_in_base": "flange in base", "base_in_flange": "base in flange",
               "target_in_camera": "target in camera", "camera_in_target": "camera in target"}
#: A median translation length below this (in the file's numbers) is read as metres, above as mm.
METRES_BELOW = 20.0
_SCALE = {"m": 1000.0, "mm": 1.0}
#: Plausible median distances (mm): the flange from the base, the board from the camera.
PLAUSIBLE_MM = {"robot": (50.0, 5000.0), "camera": (30.0, 10000.0)}

#: Consistency: within this factor of the best reading's value, and under these floors ...
NOISE_FACTOR = 3.0
GAP_FLOOR_DEG = 1.0
AXIS_FLOOR_DEG = 2.0
TRANSLATION_FLOOR = 0.08
#: ... and at most these (above them no reading fits: the data are refused).
GAP_MAX_DEG = 5.0
AXIS_MAX_DEG = 10.0
TRANSLATION_MAX = 0.3
#: Plausibility: the flange object's offset ratio and the field-of-view tests that decide.
OFFSET_RATIO = 2.5
OFFSET_MAX_MM = 2000.0
FRONT_DEG = 50.0
SPREAD_RATIO = 1.8
SPREAD_SLACK = 1.3
#: The robot/camera length ratio (screw pitches) must be within this factor of 1.
SCALE_FACTOR = 3.0
#: Rotation pairs screened by their angle gap and kept for the full fit.
MAX_ROTATION_PAIRS = 48
SCREEN_PAIRS = 600
FIT_PAIRS = 1500


@dataclass(frozen=True)
class SideReading:
    """One reading of one side's numbers.

    Attributes
    ----------
    key : str
        Short stable name (``euler:ZYX:deg``, ``as written``).
    words : str
        The rotation convention in words.
    short : str
        A few words for the table.
    poses : ndarray, shape (n, 4, 4)
        In the file's length unit, in the file's direction.
    declared : bool
        The format, the file's header or the file's own keys say the numbers mean this.
    allowed : bool
        The flags (``--euler``, ``--quaternion-order``) allow this reading.
    """

    key: str
    words: str
    short: str
    poses: np.ndarray
    declared: bool = False
    allowed: bool = True


@dataclass
class Side:
    """The readings of one side (``robot`` or ``camera``) and what the file says about it."""

    name: str
    readings: list
    declared_direction: str | None = None
    declared_unit: str | None = None


@dataclass(frozen=True)
class Constraints:
    """Flags (win over everything) and declarations (break ties)."""

    setup: str | None = None
    robot_pose: str | None = None
    camera_pose: str | None = None
    units: str | None = None
    declared_setup: str | None = None
    default_setup: str | None = None
    conventions_given: str | None = None


@dataclass
class Reading:
    """One complete reading with its scores."""

    robot: int
    camera: int
    robot_pose: str
    camera_pose: str
    setup: str
    units: tuple
    gap_deg: float
    axis_deg: float
    translation: float
    flange_object: str
    flange_offset_mm: float
    fixed_distance_mm: float
    view_spread_deg: float
    view_front: bool
    consistent: bool = False
    plausible: bool = True
    why: str = ""
    verdict: str = ""
    outcome: int = -1
    klass: tuple = ()
    scale: float = float("nan")
    view: dict = field(default_factory=dict, repr=False)

    def dims(self) -> tuple:
        return (self.robot, self.camera, self.robot_pose, self.camera_pose, self.setup)


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


def _median_length(poses) -> float:
    return float(np.median(np.linalg.norm(np.asarray(poses)[:, :3, 3], axis=1))) if len(poses) else 0.0


def _unit_of(side: Side, reading: SideReading, forced: str | None) -> tuple[str, bool, float]:
    """(unit, plausible, median length in file numbers) of one side reading."""
    median = _median_length(reading.poses)
    unit = forced or ("m" if median < METRES_BELOW else "mm")
    lo, hi = PLAUSIBLE_MM[side.name]
    return unit, lo <= median * _SCALE[unit] <= hi, median


def _in_mm(poses, unit: str) -> np.ndarray:
    out = np.array(poses, dtype=float)
    out[:, :3, 3] *= _SCALE[unit]
    return out


def _view(camera_mm) -> dict:
    """Where the board would be seen from, for the camera poses read as given and as inverted."""
    out = {}
    for direction, poses in (("target_in_camera", camera_mm), ("camera_in_target", invert_transforms(camera_mm))):
        t = poses[:, :3, 3]
        d = t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
        mean = d.mean(axis=0)
        mean = mean / max(np.linalg.norm(mean), 1e-12)
        spread = float(np.percentile(np.degrees(np.arccos(np.clip(d @ mean, -1.0, 1.0))), 90))
        front = bool(max(mean[2], mean[0]) >= np.cos(np.radians(FRONT_DEG)))
        out[direction] = (spread, front)
    return out


def _view_decision(view: dict) -> tuple[str | None, str]:
    """Which camera direction the field of view favours (``None``: it does not decide) and why."""
    (s_t, f_t), (s_c, f_c) = view["target_in_camera"], view["camera_in_target"]
    words = f"board directions spread {s_t:.0f} deg as target in camera, {s_c:.0f} deg as camera in target"
    if f_t != f_c:
        front, back = ("target_in_camera", "camera_in_target") if f_t else ("camera_in_target", "target_in_camera")
        if view[front][0] <= SPREAD_SLACK * view[back][0]:
            return front, f"the board is in front of the camera only as {_POSE_WORDS[front]} ({words})"
        return None, words
    if max(s_t, s_c) >= SPREAD_RATIO * max(min(s_t, s_c), 1e-6):
        narrow = "target_in_camera" if s_t < s_c else "camera_in_target"
        return narrow, f"the board stays in a narrow cone only as {_POSE_WORDS[narrow]} ({words})"
    return None, words


def _members(fit_a, fit_b, view: dict) -> list:
    """The eight (robot pose, camera pose, set-up) readings of one rotation pair, from its two class fits.

    ``fit_a`` fits ``H = robot as read``, ``fit_b`` ``H = robot inverted``; the camera poses as read.
    Readings that invert the camera poses swap the roles of the fitted ``X`` and ``G``.
    """
    rows = []
    table = [  # (fit, robot_pose, camera_pose, setup, flange offset from X (True) or G)
        (fit_a, "flange_in_base", "target_in_camera", EYE_IN_HAND, True),
        (fit_a, "base_in_flange", "target_in_camera", EYE_TO_HAND, False),
        (fit_a, "base_in_flange", "camera_in_target", EYE_IN_HAND, False),
        (fit_a, "flange_in_base", "camera_in_target", EYE_TO_HAND, True),
        (fit_b, "flange_in_base", "target_in_camera", EYE_TO_HAND, False),
        (fit_b, "base_in_flange", "target_in_camera", EYE_IN_HAND, True),
        (fit_b, "flange_in_base", "camera_in_target", EYE_IN_HAND, False),
        (fit_b, "base_in_flange", "camera_in_target", EYE_TO_HAND, True),
    ]
    for fit, robot_pose, camera_pose, setup, offset_is_x in table:
        x = float(np.linalg.norm(fit.x[:3, 3]))
        g = float(np.linalg.norm(fit.g[:3, 3]))
        offset, fixed = (x, g) if offset_is_x else (g, x)
        spread, front = view[camera_pose]
        rows.append(dict(robot_pose=robot_pose, camera_pose=camera_pose, setup=setup, fit=fit,
                         flange_object="camera" if setup == EYE_IN_HAND else "board",
                         flange_offset_mm=offset, fixed_distance_mm=fixed, view_spread_deg=spread, view_front=front))
    return rows


def _check_flag(name: str, value, allowed) -> None:
    if value is not None and value not in allowed:
        raise SessionError(f"--{name.replace('_', '-')} must be one of {', '.join(allowed)}; got {value!r}")


def _pose_outcome(robot: Side, camera: Side, r: Reading):
    a = _in_mm(robot.readings[r.robot].poses, r.units[0])
    b = _in_mm(camera.readings[r.camera].poses, r.units[1])
    if r.robot_pose == "base_in_flange":
        a = invert_transforms(a)
    if r.camera_pose == "camera_in_target":
        b = invert_transforms(b)
    return a, b


def _same_outcome(one, two, tol_deg: float, tol_mm: float) -> bool:
    (a1, b1, s1), (a2, b2, s2) = one, two
    if s1 != s2:
        return False
    for p, q in ((a1, a2), (b1, b2)):
        if np.max(rotation_error_deg(p, q)) > tol_deg or np.max(np.linalg.norm(p[:, :3, 3] - q[:, :3, 3], axis=1)) > tol_mm:
            return False
    return True


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


def _reading_words(robot: Side, camera: Side, r: Reading) -> str:
    rr, cr = robot.readings[r.robot], camera.readings[r.camera]
    return (f"{r.setup}, robot {_POSE_WORDS[r.robot_pose]} ({rr.short}, {r.units[0]}), "
            f"camera {_POSE_WORDS[r.camera_pose]} ({cr.short}, {r.units[1]})")


def _scores_words(r: Reading) -> str:
    if not np.isfinite(r.axis_deg):
        return f"angle gap {r.gap_deg:.2f} deg; too little rotation for the other checks"
    return (f"angle gap {r.gap_deg:.2f} deg, axis misfit {r.axis_deg:.2f} deg, "
            f"translation misfit {100 * r.translation:.1f} % of the motion")


def side_words(side: Side, reading: SideReading, direction: str, unit: str) -> str:
    """``robot poses read as flange in base, position in m converted to mm, Euler ZYX ...``."""
    position = "position in mm" if unit == "mm" else "position in m converted to mm"
    return f"{side.name} poses read as {_POSE_WORDS[direction]}, {position}, {reading.words}"


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
    _check_flag("setup", c.setup, SETUPS)
    _check_flag("robot_pose", c.robot_pose, ROBOT_POSES)
    _check_flag("camera_pose", c.camera_pose, CAMERA_POSES)
    _check_flag("units", c.units, tuple(_SCALE))
    if not robot.readings or not camera.readings:
        raise SessionError("no reading of the poses is possible")
    if not any(r.allowed for r in robot.readings) or not any(r.allowed for r in camera.readings):
        raise SessionError("the rotation convention given (--euler, --quaternion-order) does not apply to these poses")
    n = len(robot.readings[0].poses)
    warnings_, notes = [], []
    units = _side_units(robot, camera, c, warnings_)
    gaps = _angle_gaps(robot, camera, n)
    evaluated = _pairs_to_evaluate(robot, camera, gaps)
    readings = _score(robot, camera, evaluated, gaps, units, n)
    _mark_consistency(readings, n, notes)
    _mark_plausibility(readings)
    _mark_outcomes(robot, camera, readings, n)

    def allowed(r: Reading) -> bool:
        return (robot.readings[r.robot].allowed and camera.readings[r.camera].allowed
                and (c.setup is None or r.setup == c.setup) and (c.robot_pose is None or r.robot_pose == c.robot_pose)
                and (c.camera_pose is None or r.camera_pose == c.camera_pose))

    flags_given = (any(v is not None for v in (c.setup, c.robot_pose, c.camera_pose))
                   or not all(x.allowed for x in robot.readings + camera.readings))
    consistent = [r for r in readings if r.consistent]
    if not consistent and not flags_given:
        best = min(readings, key=_badness)
        raise SessionError(
            f"no reading of the poses fits a rigid camera mount (best: {_reading_words(robot, camera, best)}: "
            f"{_scores_words(best)}); check that robot and camera poses are paired posture by posture, or give "
            f"the conventions (--euler, --quaternion-order, --robot-pose, --camera-pose, --setup)")
    free, free_how = _decide(robot, camera, c, readings)
    pool, how = _decide(robot, camera, c, [r for r in readings if allowed(r)])
    free_decided = free_how in ("invariants", "plausibility", "declarations")
    if how in ("none fits", "implausible") and flags_given:
        # the flags exclude every plausible reading that fits: read as told, say what the data say
        chosen = min((r for r in readings if allowed(r)),
                     key=lambda r: (not _declared_match(robot, camera, c, r, flags_only=True), not r.consistent,
                                    _badness(r)))
        what = (f"the poses do not fit it ({_scores_words(chosen)})" if not chosen.consistent
                else f"{_reading_words(robot, camera, chosen)} is {chosen.why.replace('not plausible: ', 'implausible: ')}")
        message = f"{_flags_text(robot, camera, c)}: {what}"
        if free_decided:
            other = min(free, key=_badness)
            message += f", while {_reading_words(robot, camera, other)} fits ({_scores_words(other)})"
        warnings_.append(message + "; read as given")
        how = "flags"
    elif how in ("undecided", "implausible"):
        outcomes_left = sorted({r.outcome for r in pool})
        options = [_reading_words(robot, camera, min((r for r in pool if r.outcome == k), key=_badness))
                   for k in outcomes_left[:3]]
        fit = "equally well" if how == "undecided" else "(none of them plausibly)"
        raise SessionError(
            f"the data fit {len(outcomes_left)} readings {fit} ({'; or '.join(options)}); "
            f"pass {' or '.join(_flag_names(pool, robot, camera)) or '--setup'} to decide")
    else:
        chosen = min(pool, key=lambda r: (not _declared_match(robot, camera, c, r), _badness(r)))
        if flags_given and free_decided and free[0].outcome != chosen.outcome:
            other = min(free, key=_badness)
            warnings_.append(
                f"{_flags_text(robot, camera, c)}: the data point to another reading ({_reading_words(robot, camera, other)}"
                f", which {other.why or 'fits and is plausible'}; the one given {chosen.why or 'fits too'}); read as given")
        if flags_given and not free_decided:
            how = "flags"
    _check_scale(chosen, c, n, warnings_)
    for r in readings:
        r.verdict = _verdict(r, chosen, allowed(r))
    a, b = _pose_outcome(robot, camera, chosen)
    table = _table_rows(readings, chosen)
    decided_by = {"invariants", how} if chosen.consistent else {"flags"}
    record = _record(robot, camera, chosen, table, decided_by, c)
    if how == "declarations":
        others = [r for r in pool if r.outcome != chosen.outcome] or [
            r for r in readings if r.consistent and r.plausible and r.outcome != chosen.outcome]
        if others:
            notes.append(f"the data alone also fit {_reading_words(robot, camera, others[0])}; read as the file "
                         f"declares (pass {' or '.join(_flag_names([chosen, others[0]], robot, camera))} to override)")
    return Inference(a, b, chosen.setup, chosen, table, record, notes, warnings_)


def _side_units(robot: Side, camera: Side, c: Constraints, warnings_: list) -> dict:
    """``{(side, reading index): (unit, plausible, median)}``; refuses a side plausible in no unit."""
    units = {}
    for side in (robot, camera):
        for k, reading in enumerate(side.readings):
            units[side.name, k] = _unit_of(side, reading, c.units)
        if c.units is not None:
            guess, plausible, median = _unit_of(side, side.readings[0], None)
            if guess != c.units and plausible:
                warnings_.append(f"--units {c.units}: the {side.name} translations have a median length of {median:.4g}, "
                                 f"which looks like {guess}; read as {c.units}")
                continue
        if any(units[side.name, k][1] for k in range(len(side.readings))):
            continue
        unit, _, median = units[side.name, 0]
        lo, hi = PLAUSIBLE_MM[side.name]
        what = "flange from the base" if side.name == "robot" else "board from the camera"
        if c.units is None:
            raise SessionError(
                f"the {side.name} translations have a median length of {median:.4g}: neither {median:.4g} mm nor "
                f"{median:.4g} m is a plausible distance of the {what} ({lo:g} mm .. {hi / 1000:g} m); pass --units")
        warnings_.append(
            f"--units {c.units}: the {what} is then a median {median * _SCALE[c.units]:.4g} mm away, outside the "
            f"plausible {lo:g} mm .. {hi / 1000:g} m; read as given")
    return units


def _angle_gaps(robot: Side, camera: Side, n: int) -> np.ndarray:
    """Median angle gap (deg) of every (robot reading, camera reading) pair, on a sample of posture pairs."""
    if n < 3:
        return np.zeros((len(robot.readings), len(camera.readings)))
    pairs = pair_indices(n, SCREEN_PAIRS)
    angles_r = np.array([relative_angles_deg(r.poses, pairs) for r in robot.readings])
    angles_c = np.array([relative_angles_deg(r.poses, pairs) for r in camera.readings])
    return np.median(np.abs(angles_r[:, None, :] - angles_c[None, :, :]), axis=2)


def _pairs_to_evaluate(robot: Side, camera: Side, gaps: np.ndarray) -> list:
    """Rotation pairs fitted in full: those within the angle noise, the best the flags allow, what the
    file declares, and a few of the rejected ones (to show in the table)."""
    order = [tuple(int(v) for v in np.unravel_index(k, gaps.shape)) for k in np.argsort(gaps, axis=None, kind="stable")]
    best = gaps[order[0]]
    close = [p for p in order if gaps[p] <= max(GAP_FLOOR_DEG, NOISE_FACTOR * best)][:MAX_ROTATION_PAIRS]
    allowed = [p for p in order if robot.readings[p[0]].allowed and camera.readings[p[1]].allowed][:3]
    declared = [p for p in order if robot.readings[p[0]].declared and camera.readings[p[1]].declared][:3]
    others = [p for p in order if p not in close][:4]
    return list(dict.fromkeys(close + allowed + declared + others))


def _score(robot: Side, camera: Side, evaluated: list, gaps, units: dict, n: int) -> list:
    """The eight readings of every evaluated rotation pair, with their invariant and plausibility figures."""
    readings = []
    fit_pairs = pair_indices(n, FIT_PAIRS) if n >= 2 else np.zeros((0, 2), int)
    for i, j in evaluated:
        unit_r, unit_c = units["robot", i][0], units["camera", j][0]
        a = _in_mm(robot.readings[i].poses, unit_r)
        b = _in_mm(camera.readings[j].poses, unit_c)
        fit_a = fit_hand_eye(a, b, fit_pairs)
        fit_b = fit_hand_eye(invert_transforms(a), b, fit_pairs)
        view = _view(b)
        for k, m in enumerate(_members(fit_a, fit_b, view)):
            fit = m.pop("fit")
            readings.append(Reading(i, j, units=(unit_r, unit_c), gap_deg=float(gaps[i, j]), axis_deg=fit.axis_deg,
                                    translation=fit.translation_ratio, klass=(i, j, k // 4), scale=fit.pitch_scale,
                                    view=view, **m))
    return readings


def _mark_consistency(readings: list, n: int, notes: list) -> None:
    """``consistent`` for every reading: each misfit within the noise of the best reading (and its floor)."""
    if n < 3:
        for r in readings:
            r.consistent = True
        notes.append(f"only {n} posture(s): the conventions cannot be checked against the data")
        return
    best = min(readings, key=_badness)
    no_axes = all(not np.isfinite(r.axis_deg) for r in readings)
    tol_gap = max(GAP_FLOOR_DEG, NOISE_FACTOR * best.gap_deg)
    tol_axis = max(AXIS_FLOOR_DEG, NOISE_FACTOR * _finite(best.axis_deg))
    tol_tr = max(TRANSLATION_FLOOR, NOISE_FACTOR * _finite(best.translation))
    if no_axes:
        notes.append("the robot barely rotates between postures: only the rotation angles were checked")
    fits_at_all = best.gap_deg <= GAP_MAX_DEG and (no_axes or (best.axis_deg <= AXIS_MAX_DEG
                                                                and best.translation <= TRANSLATION_MAX))
    for r in readings:
        bad = []
        if r.gap_deg > tol_gap:
            bad.append(f"angle gap {r.gap_deg:.2f} deg")
        if not no_axes and not _finite(r.axis_deg) <= tol_axis:
            bad.append(f"axis misfit {r.axis_deg:.1f} deg")
        if not no_axes and not _finite(r.translation) <= tol_tr:
            bad.append(f"translation misfit {100 * r.translation:.0f} %")
        r.consistent = fits_at_all and not bad
        r.why = "" if r.consistent else "does not fit: " + (", ".join(bad) or _scores_words(r))


def _mark_plausibility(readings: list) -> None:
    """``plausible`` inside each class of equally consistent readings (module docstring, rule 3)."""
    classes: dict = {}
    for r in readings:
        if r.consistent:
            classes.setdefault(r.klass, []).append(r)
    for cls in classes.values():
        offsets = sorted({round(r.flange_offset_mm, 6) for r in cls})
        if len(offsets) == 2 and offsets[1] >= OFFSET_RATIO * max(offsets[0], 1.0):
            for r in cls:
                if round(r.flange_offset_mm, 6) == offsets[1]:
                    r.plausible = False
                    r.why = (f"not plausible: the {r.flange_object} {r.flange_offset_mm:.0f} mm from the flange "
                             f"(the other reading: {offsets[0]:.0f} mm)")
        for r in cls:
            if r.plausible and r.flange_offset_mm > OFFSET_MAX_MM:
                r.plausible = False
                r.why = f"not plausible: the {r.flange_object} {r.flange_offset_mm:.0f} mm from the flange"
        winner, why = _view_decision(cls[0].view)
        if winner is not None:
            for r in cls:
                if r.plausible and r.camera_pose != winner:
                    r.plausible = False
                    r.why = f"not plausible: {why}"


def _mark_outcomes(robot: Side, camera: Side, readings: list, n: int) -> None:
    """Number the distinct sessions the consistent readings give (same set-up and poses within the noise)."""
    consistent = [r for r in readings if r.consistent]
    tol_deg = max(0.05, 0.5 * min((_finite(r.axis_deg) for r in consistent), default=0.0)) if n >= 3 else 0.05
    outcomes: list = []
    for r in consistent:
        a, b = _pose_outcome(robot, camera, r)
        for k, o in enumerate(outcomes):
            if _same_outcome(o, (a, b, r.setup), tol_deg, 0.5):
                r.outcome = k
                break
        else:
            outcomes.append((a, b, r.setup))
            r.outcome = len(outcomes) - 1


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


def _finite(v: float) -> float:
    return v if np.isfinite(v) else np.inf


def _badness(r: Reading) -> float:
    """The worst of a reading's three misfits, each against its floor (1 = at the floor)."""
    values = (r.gap_deg / GAP_FLOOR_DEG, r.axis_deg / AXIS_FLOOR_DEG, r.translation / TRANSLATION_FLOOR)
    return max(v if np.isfinite(v) else np.inf for v in values) if np.isfinite(r.gap_deg) else np.inf


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


def _table_rows(readings: list, chosen: Reading) -> list:
    """The candidates shown: the chosen rotation pair's eight readings, then the best of every other."""
    same = [r for r in readings if (r.robot, r.camera) == (chosen.robot, chosen.camera)]
    others = {}
    for r in readings:
        key = (r.robot, r.camera)
        if key == (chosen.robot, chosen.camera):
            continue
        if key not in others or (r.consistent, -r.axis_deg if np.isfinite(r.axis_deg) else -np.inf) > (
                others[key].consistent, -others[key].axis_deg if np.isfinite(others[key].axis_deg) else -np.inf):
            others[key] = r
    rest = sorted(others.values(), key=lambda r: (not r.consistent, r.gap_deg))[:6]
    return [chosen] + [r for r in same if r is not chosen] + rest


def _record(robot: Side, camera: Side, chosen: Reading, table: list, decided_by: set, c: Constraints) -> dict:
    rr, cr = robot.readings[chosen.robot], camera.readings[chosen.camera]
    how = {"invariants": "the X-free invariants of AX = XB", "plausibility": "plausibility (which object rides on "
           "the flange, where the board is seen)", "declarations": "what the file declares",
           "flags": "the flags given"}
    return {
        "robot": side_words(robot, rr, chosen.robot_pose, chosen.units[0]),
        "camera": side_words(camera, cr, chosen.camera_pose, chosen.units[1]),
        "setup": chosen.setup,
        "decided_by": [how[k] for k in ("invariants", "plausibility", "declarations", "flags") if k in decided_by],
        "scores": {"angle_gap_deg": _round(chosen.gap_deg), "axis_misfit_deg": _round(chosen.axis_deg),
                   "translation_misfit": _round(chosen.translation), "pitch_ratio": _round(chosen.scale),
                   f"{chosen.flange_object}_from_flange_mm": _round(chosen.flange_offset_mm)},
        "candidates": [_row_record(robot, camera, r) for r in table],
    }


def _round(v, digits: int = 4):
    return round(float(v), digits) if v is not None and np.isfinite(v) else None


def _row_record(robot: Side, camera: Side, r: Reading) -> dict:
    return {
        "robot": f"{robot.readings[r.robot].short}, {_POSE_WORDS[r.robot_pose]}, {r.units[0]}",
        "camera": f"{camera.readings[r.camera].short}, {_POSE_WORDS[r.camera_pose]}, {r.units[1]}",
        "setup": r.setup,
        "angle_gap_deg": _round(r.gap_deg, 3),
        "axis_misfit_deg": _round(r.axis_deg, 3),
        "translation_misfit": _round(r.translation, 4),
        "flange_object_mm": _round(r.flange_offset_mm, 1),
        "view_spread_deg": _round(r.view_spread_deg, 1),
        "verdict": r.verdict,
    }


def format_table(record: dict) -> list:
    """The candidates of an import record as text lines (the table ``handeye import`` prints)."""
    rows = record.get("candidates") or []
    if not rows:
        return []
    head = ("robot", "camera", "set-up", "gap deg", "axis deg", "transl.", "on flange", "view", "verdict")
    body = []
    for r in rows:
        tr = r["translation_misfit"]
        body.append((r["robot"], r["camera"], r["setup"], _fmt(r["angle_gap_deg"], 2), _fmt(r["axis_misfit_deg"], 2),
                     "-" if tr is None else f"{100 * tr:.1f} %", _fmt(r["flange_object_mm"], 0) + " mm",
                     _fmt(r["view_spread_deg"], 0) + " deg", r["verdict"]))
    widths = [max(len(str(x[k])) for x in [head] + body) for k in range(len(head))]
    lines = ["  ".join(str(x[k]).ljust(widths[k]) for k in range(len(head))).rstrip() for x in [head] + body]
    return lines


def _fmt(v, digits: int) -> str:
    return "-" if v is None else f"{v:.{digits}f}"
