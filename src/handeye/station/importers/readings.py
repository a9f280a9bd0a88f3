"""The readings of a log and their scores: units, the X-free invariants, plausibility, outcomes.

``inference.infer`` decides among the readings scored here. A *side reading* is one way to read
one side's numbers (a rotation convention); a :class:`Reading` adds the pose directions, the set-up
and the units, and carries its figures: the angle gap, the axis and translation misfits of the
linear AX = XB fit (``calibration.invariants``), the offset of the object on the flange and how
the board would be seen. Thresholds are named here, once.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ...base import SessionError, SessionUsageError
from ...calibration import MIN_MOTION_DEG, fit_hand_eye, pair_indices
from ...calibration import EYE_IN_HAND, EYE_TO_HAND
from ...geometry import invert_transforms, rotation_error_deg
from .noise_test import compare, posture_misfits

__all__ = [
    "ROBOT_POSES", "CAMERA_POSES", "POSE_WORDS", "METRES_BELOW", "SCALE", "PLAUSIBLE_MM", "SideReading", "Side",
    "Constraints", "Reading", "check_flag", "side_units", "pairs_to_evaluate", "score_readings",
    "mark_consistency", "mark_plausibility", "mark_outcomes", "pose_outcome", "badness", "scores_words", "screen",
]

ROBOT_POSES = ("flange_in_base", "base_in_flange")
CAMERA_POSES = ("target_in_camera", "camera_in_target")
POSE_WORDS = {"flange_in_base": "flange in base", "base_in_flange": "base in flange",
               "target_in_camera": "target in camera", "camera_in_target": "camera in target"}
#: A median translation length below this (in the file's numbers) is read as metres, above as mm.
METRES_BELOW = 20.0
SCALE = {"m": 1000.0, "mm": 1.0}
#: Plausible median distances (mm): the flange from the base, the board from the camera.
PLAUSIBLE_MM = {"robot": (50.0, 5000.0), "camera": (30.0, 10000.0)}

#: Consistency: within this factor of the best reading's value, and under these floors ...
NOISE_FACTOR = 3.0
GAP_FLOOR_DEG = 1.0
AXIS_FLOOR_DEG = 2.0
TRANSLATION_FLOOR = 0.08
#: ... and at most these (above them no reading fits: the data are refused). The worst of the real
#: logs in ../shared/datasets misfits by 1.2 deg, 2.6 deg and 6 %; twice that and more is beyond what
#: the noise of a hand-eye log explains (wrong pairing, a pose convention no reading has, a loose mount).
GAP_MAX_DEG = 2.5
AXIS_MAX_DEG = 5.0
TRANSLATION_MAX = 0.2
#: Plausibility: the flange object's offset ratio and the field-of-view tests that decide.
OFFSET_RATIO = 2.5
OFFSET_MAX_MM = 2000.0
FRONT_DEG = 50.0
SPREAD_RATIO = 1.8
SPREAD_SLACK = 1.3
#: The robot/camera length ratio (screw pitches) must be within this factor of 1.
SCALE_FACTOR = 3.0
#: Rotation pairs screened by their angle and pitch gaps (on a sample of SCREEN_PAIRS posture pairs);
#: every pair within the noise of the best on both is fitted in full (on FIT_PAIRS posture pairs; at
#: most MAX_ROTATION_PAIRS, a bound the screens keep far away).
MAX_ROTATION_PAIRS = 400
SCREEN_PAIRS = 600
FIT_PAIRS = 1000
#: A reading whose robot rotates enough for the axis test in under this fraction of the pairs the
#: best-rotating reading has (degrees read as radians, angles that barely turn) cannot be tested.
MIN_USABLE_FRACTION = 0.5



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
    usable_pairs: int = 0
    misfits: np.ndarray | None = field(default=None, repr=False)  # (n, 3) per posture, ``noise_test.posture_misfits``


def median_length(poses) -> float:
    """Median translation length of poses ``(n, 4, 4)`` in their own unit (0 for none)."""
    return float(np.median(np.linalg.norm(np.asarray(poses)[:, :3, 3], axis=1))) if len(poses) else 0.0


def unit_of(side: Side, reading: SideReading, forced: str | None) -> tuple[str, bool, float]:
    """(unit, plausible, median length in file numbers) of one side reading."""
    median = median_length(reading.poses)
    unit = forced or ("m" if median < METRES_BELOW else "mm")
    lo, hi = PLAUSIBLE_MM[side.name]
    return unit, lo <= median * SCALE[unit] <= hi, median


def in_mm(poses, unit: str) -> np.ndarray:
    """A copy of poses ``(n, 4, 4)`` with the translations converted from ``unit`` to mm."""
    out = np.array(poses, dtype=float)
    out[:, :3, 3] *= SCALE[unit]
    return out


def board_views(camera_mm) -> dict:
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


def view_decision(view: dict) -> tuple[str | None, str]:
    """Which camera direction the field of view favours (``None``: it does not decide) and why."""
    (s_t, f_t), (s_c, f_c) = view["target_in_camera"], view["camera_in_target"]
    words = f"board directions spread {s_t:.0f} deg as target in camera, {s_c:.0f} deg as camera in target"
    if f_t != f_c:
        front, back = ("target_in_camera", "camera_in_target") if f_t else ("camera_in_target", "target_in_camera")
        if view[front][0] <= SPREAD_SLACK * view[back][0]:
            return front, f"the board is in front of the camera only as {POSE_WORDS[front]} ({words})"
        return None, words
    if max(s_t, s_c) >= SPREAD_RATIO * max(min(s_t, s_c), 1e-6):
        narrow = "target_in_camera" if s_t < s_c else "camera_in_target"
        return narrow, f"the board stays in a narrow cone only as {POSE_WORDS[narrow]} ({words})"
    return None, words


def members(fit_a, fit_b, view: dict) -> list:
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


def pose_outcome(robot: Side, camera: Side, r: Reading):
    """The session poses reading ``r`` gives: ``(tool0_in_base, target_in_camera)``, mm."""
    a = in_mm(robot.readings[r.robot].poses, r.units[0])
    b = in_mm(camera.readings[r.camera].poses, r.units[1])
    if r.robot_pose == "base_in_flange":
        a = invert_transforms(a)
    if r.camera_pose == "camera_in_target":
        b = invert_transforms(b)
    return a, b


def same_outcome(one, two, tol_deg: float, tol_mm: float) -> bool:
    """Two ``(tool0, target, setup)`` outcomes give the same session (every pose within the tolerances)."""
    (a1, b1, s1), (a2, b2, s2) = one, two
    if s1 != s2:
        return False
    for p, q in ((a1, a2), (b1, b2)):
        if np.max(rotation_error_deg(p, q)) > tol_deg or np.max(np.linalg.norm(p[:, :3, 3] - q[:, :3, 3], axis=1)) > tol_mm:
            return False
    return True


def side_units(robot: Side, camera: Side, c: Constraints, warnings_: list) -> dict:
    """``{(side, reading index): (unit, plausible, median)}``; refuses a side plausible in no unit."""
    units = {}
    for side in (robot, camera):
        for k, reading in enumerate(side.readings):
            units[side.name, k] = unit_of(side, reading, c.units)
        if c.units is not None:
            guess, plausible, median = unit_of(side, side.readings[0], None)
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
            f"--units {c.units}: the {what} is then a median {median * SCALE[c.units]:.4g} mm away, outside the "
            f"plausible {lo:g} mm .. {hi / 1000:g} m; read as given")
    return units


def _screw(poses_mm, pairs) -> tuple:
    """Per posture pair: rotation angle (deg), translation along the rotation axis and translation
    length (mm) of ``T_i^-1 T_j``, the per-side halves of the angle and pitch invariants."""
    rel = invert_transforms(poses_mm[pairs[:, 0]]) @ poses_mm[pairs[:, 1]]
    vectors = Rotation.from_matrix(rel[:, :3, :3]).as_rotvec()
    angle = np.linalg.norm(vectors, axis=1)
    pitch = np.einsum("mi,mi->m", vectors / np.maximum(angle, 1e-12)[:, None], rel[:, :3, 3])
    return np.degrees(angle), pitch, np.linalg.norm(rel[:, :3, 3], axis=1)


def screen(robot: Side, camera: Side, units: dict, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The X-free, set-up-free and direction-free invariants of every (robot reading, camera reading)
    pair, on a sample of posture pairs: the median angle gap (deg) and the median screw-pitch gap
    ``|d_A - d_B|`` as a fraction of the median robot motion (NaN where no pair turns enough).

    The pitch catches what the angles cannot: Euler orders that relabel the axes of the right one,
    and quaternions read in the wrong order on both sides, turn by the right angles about the wrong
    axes.
    """
    shape = (len(robot.readings), len(camera.readings))
    if n < 3:
        return np.zeros(shape), np.zeros(shape)
    pairs = pair_indices(n, SCREEN_PAIRS)
    sides = []
    for side in (robot, camera):
        sides.append([_screw(in_mm(r.poses, units[side.name, k][0]), pairs) for k, r in enumerate(side.readings)])
    angle_r, pitch_r, motion_r = (np.array([s[k] for s in sides[0]]) for k in range(3))
    angle_c, pitch_c, _ = (np.array([s[k] for s in sides[1]]) for k in range(3))
    gaps = np.median(np.abs(angle_r[:, None, :] - angle_c[None, :, :]), axis=2)
    lo, hi = MIN_MOTION_DEG, 180.0 - MIN_MOTION_DEG
    usable = ((angle_r > lo) & (angle_r < hi))[:, None, :] & ((angle_c > lo) & (angle_c < hi))[None, :, :]
    gap = np.where(usable, np.abs(pitch_r[:, None, :] - pitch_c[None, :, :]), np.nan)
    motion = np.where(usable, np.broadcast_to(motion_r[:, None, :], usable.shape), np.nan)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows: no pair turns enough
        pitches = np.nanmedian(gap, axis=2) / np.nanmedian(motion, axis=2)
    return gaps, pitches


def pairs_to_evaluate(robot: Side, camera: Side, gaps: np.ndarray, pitches: np.ndarray) -> list:
    """Rotation pairs fitted in full: those within the noise of the best on both screens, the best the
    flags allow, what the file declares, and a few of the rejected ones (to show in the table)."""
    order = [tuple(int(v) for v in np.unravel_index(k, gaps.shape)) for k in np.argsort(gaps, axis=None, kind="stable")]
    best = gaps[order[0]]
    close = [p for p in order if gaps[p] <= max(GAP_FLOOR_DEG, NOISE_FACTOR * best)]
    measured = [pitches[p] for p in close if np.isfinite(pitches[p])]
    if measured:
        limit = max(TRANSLATION_FLOOR, NOISE_FACTOR * min(measured))
        close = [p for p in close if not pitches[p] > limit]
    close = close[:MAX_ROTATION_PAIRS]
    allowed = [p for p in order if robot.readings[p[0]].allowed and camera.readings[p[1]].allowed][:3]
    declared = [p for p in order if robot.readings[p[0]].declared and camera.readings[p[1]].declared][:3]
    others = [p for p in order if p not in close][:4]
    return list(dict.fromkeys(close + allowed + declared + others))


def score_readings(robot: Side, camera: Side, evaluated: list, gaps, units: dict, n: int) -> list:
    """The eight readings of every evaluated rotation pair, with their invariant and plausibility figures."""
    readings = []
    fit_pairs = pair_indices(n, FIT_PAIRS) if n >= 2 else np.zeros((0, 2), int)
    for i, j in evaluated:
        unit_r, unit_c = units["robot", i][0], units["camera", j][0]
        a = in_mm(robot.readings[i].poses, unit_r)
        b = in_mm(camera.readings[j].poses, unit_c)
        fit_a = fit_hand_eye(a, b, fit_pairs)
        fit_b = fit_hand_eye(invert_transforms(a), b, fit_pairs)
        view = board_views(b)
        misfits = {id(fit_a): posture_misfits(fit_a, n), id(fit_b): posture_misfits(fit_b, n)}
        for k, m in enumerate(members(fit_a, fit_b, view)):
            fit = m.pop("fit")
            readings.append(Reading(i, j, units=(unit_r, unit_c), gap_deg=float(gaps[i, j]), axis_deg=fit.axis_deg,
                                    translation=fit.translation_ratio, klass=(i, j, k // 4), scale=fit.pitch_scale,
                                    view=view, usable_pairs=fit.pairs, misfits=misfits[id(fit)], **m))
    return readings


def mark_consistency(readings: list, n: int, notes: list) -> None:
    """``consistent`` for every reading: each misfit within the noise of the best reading (and its floor)."""
    if n < 3:
        for r in readings:
            r.consistent = True
        notes.append(f"only {n} posture(s): the conventions cannot be checked against the data")
        return
    most = max(r.usable_pairs for r in readings)
    testable = [r for r in readings if r.usable_pairs >= MIN_USABLE_FRACTION * most]
    best = min(testable, key=badness)
    no_axes = all(not np.isfinite(r.axis_deg) for r in readings)
    tol_gap = max(GAP_FLOOR_DEG, NOISE_FACTOR * best.gap_deg)
    tol_axis = max(AXIS_FLOOR_DEG, NOISE_FACTOR * finite(best.axis_deg))
    tol_tr = max(TRANSLATION_FLOOR, NOISE_FACTOR * finite(best.translation))
    if no_axes:
        notes.append("the robot barely rotates between postures: only the rotation angles were checked")
    fits_at_all = best.gap_deg <= GAP_MAX_DEG and (no_axes or (best.axis_deg <= AXIS_MAX_DEG
                                                                and best.translation <= TRANSLATION_MAX))
    for r in readings:
        bad = []
        if r.gap_deg > tol_gap:
            bad.append(f"angle gap {r.gap_deg:.2f} deg")
        if not no_axes and not finite(r.axis_deg) <= tol_axis:
            bad.append(f"axis misfit {r.axis_deg:.1f} deg")
        if not no_axes and not finite(r.translation) <= tol_tr:
            bad.append(f"translation misfit {100 * r.translation:.0f} %")
        if r.usable_pairs < MIN_USABLE_FRACTION * most:
            bad.append(f"too little rotation to test ({r.usable_pairs} pairs turn over {MIN_MOTION_DEG:g} deg, "
                       f"{most} in the best-turning reading)")
        r.consistent = fits_at_all and not bad
        r.why = "" if r.consistent else "does not fit: " + (", ".join(bad) or scores_words(r))
    _rule_out_beyond_noise(readings, best)


def _rule_out_beyond_noise(readings: list, best: Reading) -> None:
    """A consistent reading whose misfits exceed the best one's beyond the data's noise, posture by
    posture (``noise_test``), does not fit as well: it is not an equal alternative. Only when the best
    fits a rigid mount within what noise explains (every misfit under its floor): a best reading with
    a systematic misfit (a degenerate motion, such as turns about one axis only) is no yardstick."""
    if not badness(best) <= 1.0:
        return
    verdicts: dict = {}
    for r in readings:
        if not r.consistent or r.misfits is None or best.misfits is None or r.misfits is best.misfits:
            continue
        key = id(r.misfits)
        if key not in verdicts:
            verdicts[key] = compare(r.misfits, best.misfits)
        if verdicts[key].worse:
            r.consistent = False
            r.why = "does not fit as well: " + verdicts[key].words


def mark_plausibility(readings: list) -> None:
    """``plausible`` inside each class of equally consistent readings (``inference`` module docstring, rule 3)."""
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
        winner, why = view_decision(cls[0].view)
        if winner is not None:
            for r in cls:
                if r.plausible and r.camera_pose != winner:
                    r.plausible = False
                    r.why = f"not plausible: {why}"


def mark_outcomes(robot: Side, camera: Side, readings: list, n: int) -> None:
    """Number the distinct sessions the consistent readings give (same set-up and poses within the noise).

    Each reading is compared with the outcomes found so far through :func:`same_outcome`, but only with
    those :class:`OutcomeProbes` finds near it: a log read under hundreds of conventions would otherwise
    compare every pair of readings pose by pose."""
    consistent = [r for r in readings if r.consistent]
    tol_deg = max(0.05, 0.5 * min((finite(r.axis_deg) for r in consistent), default=0.0)) if n >= 3 else 0.05
    outcomes: list = []
    probes = OutcomeProbes(tol_deg, 0.5)
    for r in consistent:
        a, b = pose_outcome(robot, camera, r)
        outcome = (a, b, r.setup)
        r.outcome = next((k for k in probes.candidates(outcome)
                          if same_outcome(outcomes[k], outcome, tol_deg, 0.5)), None)
        if r.outcome is None:
            outcomes.append(outcome)
            probes.add(outcome)
            r.outcome = len(outcomes) - 1


class OutcomeProbes:
    """The outcomes found so far, indexed so that a new one meets only those :func:`same_outcome` could
    accept: same set-up and shapes, the first robot pose's translation in the same or a neighbouring cell
    of a grid of the translation tolerance (within the tolerance means at most one cell apart on each
    axis), then no probe pose (first, middle, last of each side) outside the tolerances. An outcome with
    a NaN anywhere is always a candidate (:func:`same_outcome` lets NaN through). The cost per outcome
    does not grow with the number found (a log read under hundreds of conventions gives thousands)."""

    def __init__(self, tol_deg: float, tol_mm: float) -> None:
        self.tol_deg, self.tol_mm = tol_deg, tol_mm
        self.poses: list = []                      # probe poses per outcome, (p, 4, 4)
        self.cells: dict = {}                      # (key, i, j, k) -> outcome indices
        self.unplaced: dict = {}                   # key -> outcomes with a NaN or no pose: always candidates

    @staticmethod
    def _probe(outcome) -> tuple:
        a, b, setup = outcome
        picks = sorted({0, len(a) // 2, len(a) - 1}) if len(a) else []
        return (setup, a.shape, b.shape), np.concatenate([a[picks], b[picks]]) if picks else np.zeros((0, 4, 4))

    def _cell(self, poses) -> tuple:
        """The grid cell ``(i, j, k)`` of the first robot pose's translation (of a :meth:`_placeable` outcome)."""
        return tuple(np.floor(poses[0, :3, 3] / self.tol_mm).astype(int))

    @staticmethod
    def _placeable(outcome, poses) -> bool:
        return len(poses) > 0 and not (np.isnan(outcome[0]).any() or np.isnan(outcome[1]).any()) \
            and bool(np.all(np.abs(poses[0, :3, 3]) < 1e12))

    def add(self, outcome) -> None:
        key, poses = self._probe(outcome)
        index = len(self.poses)
        self.poses.append(poses)
        if self._placeable(outcome, poses):
            self.cells.setdefault((key, *self._cell(poses)), []).append(index)
        else:
            self.unplaced.setdefault(key, []).append(index)

    def candidates(self, outcome) -> list:
        """Indices (ascending) of the outcomes that may be the same as ``outcome``."""
        key, poses = self._probe(outcome)
        if not self._placeable(outcome, poses):  # compared with every outcome of its kind, in full
            return sorted([k for (other, *_), ks in self.cells.items() if other == key for k in ks]
                          + self.unplaced.get(key, []))
        i, j, k = self._cell(poses)
        near = [n for di in (-1, 0, 1) for dj in (-1, 0, 1) for dk in (-1, 0, 1)
                for n in self.cells.get((key, i + di, j + dj, k + dk), ())]
        if near:
            stacked = np.stack([self.poses[n] for n in near])  # (m, p, 4, 4)
            far = (rotation_error_deg(stacked, poses[None]) > self.tol_deg) | (
                np.linalg.norm(stacked[..., :3, 3] - poses[None, :, :3, 3], axis=-1) > self.tol_mm)
            near = [n for n, ruled_out in zip(near, far.any(axis=1)) if not ruled_out]
        return sorted(near + self.unplaced.get(key, []))


def finite(v: float) -> float:
    """``v``, or infinity for NaN (a misfit that could not be measured never wins)."""
    return v if np.isfinite(v) else np.inf


def badness(r: Reading) -> float:
    """The worst of a reading's three misfits, each against its floor (1 = at the floor)."""
    values = (r.gap_deg / GAP_FLOOR_DEG, r.axis_deg / AXIS_FLOOR_DEG, r.translation / TRANSLATION_FLOOR)
    return max(v if np.isfinite(v) else np.inf for v in values) if np.isfinite(r.gap_deg) else np.inf


def check_flag(name: str, value, allowed) -> None:
    """Refuse a flag value outside ``allowed`` in one line."""
    if value is not None and value not in allowed:
        raise SessionUsageError(f"--{name.replace('_', '-')} must be one of {', '.join(allowed)}; got {value!r}")


def scores_words(r: Reading) -> str:
    """A reading's three misfits in words, for messages."""
    if not np.isfinite(r.axis_deg):
        return f"angle gap {r.gap_deg:.2f} deg; too little rotation for the other checks"
    return (f"angle gap {r.gap_deg:.2f} deg, axis misfit {r.axis_deg:.2f} deg, "
            f"translation misfit {100 * r.translation:.1f} % of the motion")
