"""Quality verdict of a calibration: thresholds, checks, and what to do when a check fails.

The station's goal is the camera pose to about a tenth of a millimetre. Whether a calibration gets
there shows in four kinds of figures, each checked against a threshold of :class:`QualityThresholds`:

- **Consistency of the data** under the solved ``X``: the board points carried into the frame the
  board is fixed in (``base`` eye-in-hand) should sit on top of each other for every posture.
  ``d_org`` and each posture's residual (the same per posture) measure it. ``d_org`` has ONE
  definition, :func:`station_d_org`, used by the verdict, the HTML report (header, method table and
  chart, metrics) and the text summary alike: eq. 22 of the paper (mean distance of a point from its
  mean position) over the postures the chosen result kept (its inliers), on the session's board
  points (every board corner when the postures hold corners, else the three compact points of the
  board poses), the same points and postures for every method compared. Over all postures, outliers
  included, the same figure is called ``d_org incl. outliers``.
- **Where the camera is**: eye-in-hand, the camera's optical centre cannot sit inside the flange
  (a session written in metres solves to a frame a fraction of a millimetre from it) nor metres away.
- **Precision of X**: the one-sigma uncertainty of the robust default method (translation per axis in
  mm, rotation about each axis of the camera frame in degrees).
- **Motion that determines X**: enough consistent postures, few outliers, relative flange rotations
  that are sizeable and turn about every direction (``AX = XB`` is blind about an axis it never sees
  the flange turn about).

Every failed check carries advice on what to do next at the station.
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..calibration.errors import HandEyeError, brief
from ..calibration.metrics import d_org, fixed_points
from ..calibration.problem import EYE_IN_HAND, HandEyeProblem
from ..calibration.triplets import relative_motions

__all__ = [
    "CHECK_LABELS",
    "AxisCoverage",
    "Check",
    "D_ORG_ALL_NAME",
    "DOrg",
    "QualityThresholds",
    "ThresholdError",
    "Verdict",
    "kept_postures",
    "load_thresholds",
    "rotation_axis_coverage",
    "station_d_org",
    "verdict",
]

#: Relative rotations smaller than this have no usable axis; they are left out of the coverage.
MIN_AXIS_ANGLE_DEG = 2.0
#: The largest possible axis spread (axes spread evenly over the sphere): asin(sqrt(1/3)).
MAX_AXIS_SPREAD_DEG = math.degrees(math.asin(math.sqrt(1.0 / 3.0)))


class ThresholdError(HandEyeError):
    """A quality-threshold mapping or file is malformed (unknown key, bad value)."""


@dataclass(frozen=True)
class QualityThresholds:
    """Limits a calibration must meet to PASS (the defaults suit an NDT station with a Bumblebee XB3
    at 0.7-1.2 m from a 13x8 board on an IRB 1400, 30 planned postures).

    Attributes
    ----------
    max_d_org_mm : float
        Largest ``d_org`` (eq. 22, :func:`station_d_org`): mean distance of a board point in ``base``
        from its mean position, over the postures the result kept, every board corner of each (the
        three compact points when the session holds board poses only). It adds up the camera's 3-D
        corner noise (~0.15-0.4 mm for the XB3 wide pair at 1 m), the robot's repeatability and any kinematic or stereo calibration
        error. Default 1.0 mm: above it something systematic is wrong (stereo model, robot not at rest,
        tool0 poses from the wrong frame).
    max_posture_residual_mm : float
        Largest residual of a single posture kept in the solution (mean distance of its board points
        from their mean positions). Default 2.0 mm: a posture above it is most likely a misdetected or
        partly hidden board, or a robot pose read while the arm was still moving.
    max_sigma_translation_mm : float
        Largest one-sigma uncertainty of the camera position along x, y or z. Default 0.2 mm, so that
        2.5 sigma stays inside the 0.5 mm the station's acceptance test allows; set 0.1 when the robot
        and camera allow it (about 30 postures with 0.1 mm corner noise and 0.002 deg joint noise reach
        0.06-0.07 mm on the synthetic station).
    max_sigma_rotation_deg : float
        Largest one-sigma uncertainty of the camera rotation about its x, y or z axis. Default
        0.02 deg (2.5 sigma inside the acceptance test's 0.05 deg); note that 0.01 deg moves a point
        1 m in front of the camera by 0.17 mm.
    min_inlier_postures : int
        Fewest consistent postures (not outliers). Default 12: below that one bad posture weighs too
        much and the uncertainty estimate itself is unreliable; the capture plan takes 30.
    max_outlier_fraction : float
        Largest share of postures the method rejected as outliers. Default 0.2: a few misdetections
        happen, more hint at a systematic problem (pairing of poses and images, units, board orientation).
    min_rotation_axis_spread_deg : float
        Smallest spread of the relative rotation axes about their least exercised direction: how far
        the axes rise out of their best-fitting plane (asin of the RMS sine of that elevation), weighted
        by ``sin^2(angle / 2)`` so that small rotations count little. 0 when the flange only ever turned about axes in one plane,
        35.3 deg when the axes cover the sphere evenly. Default 10 deg (the synthetic 30-posture plan
        reaches ~19 deg).
    min_median_rotation_deg : float
        Smallest median rotation angle between two postures. Default 15 deg: small rotations leave the
        rotation axes (and so X) poorly determined; the method likes 20-45 deg.
    min_camera_offset_mm : float
        Eye-in-hand only: smallest distance of the camera frame (the left camera's optical centre)
        from the flange origin, ``|t|`` of ``cam2tool0``. Default 20 mm: the optical centre cannot sit
        inside the flange; a session whose lengths were written in metres solves to a frame a fraction
        of a millimetre from the flange, with every other figure looking excellent.
    max_camera_offset_mm : float
        Eye-in-hand only: largest distance of the camera frame from the flange origin. Default 500 mm:
        a stereo head on an IRB 1400 flange sits 100-300 mm from it; a frame further away points at
        wrong units on one side, the wrong set-up, or a camera on a long bracket (then raise it).
    """

    max_d_org_mm: float = 1.0
    max_posture_residual_mm: float = 2.0
    max_sigma_translation_mm: float = 0.2
    max_sigma_rotation_deg: float = 0.02
    min_inlier_postures: int = 12
    max_outlier_fraction: float = 0.2
    min_rotation_axis_spread_deg: float = 10.0
    min_median_rotation_deg: float = 15.0
    min_camera_offset_mm: float = 20.0
    max_camera_offset_mm: float = 500.0

    def __post_init__(self):
        for f in fields(self):
            _check_value(f.name, getattr(self, f.name))
        _check_pair(self.min_camera_offset_mm, self.max_camera_offset_mm)

    @classmethod
    def from_dict(cls, mapping, source: str = "thresholds") -> QualityThresholds:
        """Thresholds from a mapping; keys left out keep their defaults.

        Parameters
        ----------
        mapping : dict or None
            ``{key: number}`` with keys among the attributes of this class.
        source : str
            Where the mapping came from, for the error messages (e.g. the file name).

        Raises
        ------
        ThresholdError
            Unknown key, a value that is not a number, negative, out of range or (for
            ``min_inlier_postures``) not a whole number; one line naming the key.
        """
        if mapping is None:
            return cls()
        if not isinstance(mapping, dict):
            raise ThresholdError(f"{source}: expected a mapping of threshold names to numbers; got {type(mapping).__name__}")
        known = [f.name for f in fields(cls)]
        values = {}
        for key, value in mapping.items():
            if key not in known:
                raise ThresholdError(f"{source}: unknown key {brief(key)}; known keys: {', '.join(known)}")
            values[key] = _check_value(key, value, source)
        _check_pair(values.get("min_camera_offset_mm", cls.min_camera_offset_mm),
                    values.get("max_camera_offset_mm", cls.max_camera_offset_mm), source)
        return cls(**values)

    def to_dict(self) -> dict:
        return asdict(self)


def _check_pair(low: float, high: float, source: str = "thresholds") -> None:
    """The camera-offset range must not be empty."""
    if low >= high:
        raise ThresholdError(f"{source}: min_camera_offset_mm ({low:g}) must be below max_camera_offset_mm ({high:g})")


def _check_value(key: str, value, source: str = "thresholds"):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ThresholdError(f"{source}: {key} must be a number; got {brief(value)}")
    if not abs(value) <= sys.float_info.max:  # NaN, inf, or an int too large for a float (isfinite would raise)
        raise ThresholdError(f"{source}: {key} must be finite; got {brief(value)}")
    if key == "min_inlier_postures":
        if value != int(value) or value < 3:
            raise ThresholdError(f"{source}: {key} must be a whole number >= 3; got {brief(value)}")
        return int(value)
    if value <= 0:
        raise ThresholdError(f"{source}: {key} must be positive; got {brief(value)}")
    if key == "max_outlier_fraction" and value > 1:
        raise ThresholdError(f"{source}: {key} is a fraction between 0 and 1; got {brief(value)}")
    if key == "min_rotation_axis_spread_deg" and value > MAX_AXIS_SPREAD_DEG:
        raise ThresholdError(f"{source}: {key} cannot exceed {MAX_AXIS_SPREAD_DEG:.1f} deg (axes spread evenly "
                             f"over the sphere); got {brief(value)}")
    if key == "min_median_rotation_deg" and value >= 180:
        raise ThresholdError(f"{source}: {key} must be below 180 deg; got {brief(value)}")
    return float(value)


def load_thresholds(path) -> QualityThresholds:
    """Thresholds from a YAML file: a mapping of threshold keys, or a station config whose ``quality``
    section holds them (the rest of such a file is ignored here).

    Raises
    ------
    ThresholdError
        File missing or unreadable, not YAML, or a bad key or value (see :meth:`QualityThresholds.from_dict`).
    """
    from ..calibration.files import parse_yaml, read_text_file

    path = Path(path)
    text = read_text_file(path, "thresholds file", ThresholdError, missing=f"thresholds file not found: {path}")
    data = parse_yaml(text, path, ThresholdError, "; write 'key: number' lines")
    if isinstance(data, dict) and isinstance(data.get("quality"), dict):
        return QualityThresholds.from_dict(data["quality"], f"{path} (quality)")
    return QualityThresholds.from_dict(data if data is not None else {}, str(path))


@dataclass(frozen=True)
class AxisCoverage:
    """Directions of the relative flange rotations of all posture pairs.

    Attributes
    ----------
    axes : ndarray, shape (p, 3)
        Unit rotation axes of ``A_ij = A_i^-1 A_j`` (pairs ``i < j`` rotating more than
        :data:`MIN_AXIS_ANGLE_DEG`), in the hand frame: ``tool0`` eye-in-hand, ``base`` eye-to-hand.
    angles_deg : ndarray, shape (p,)
        Rotation angles of those pairs, in [0, 180].
    all_angles_deg : ndarray, shape (P,)
        Angles of every pair (also those too small for an axis).
    spread_deg : float
        Elevation of the axes out of their best-fitting plane (asin of the RMS sine), weighted by
        ``sin^2(angle/2)`` (0 = all in one plane, 35.3 = even over the sphere).
    weakest_direction : ndarray, shape (3,)
        The least exercised direction (normal of that plane), sign chosen with its largest component > 0.
    rms_about_axes_deg : ndarray, shape (3,)
        RMS over pairs of the rotation-vector component about the frame's x, y and z axes, degrees.
    frame : str
        ``tool0`` or ``base``.
    """

    axes: np.ndarray
    angles_deg: np.ndarray
    all_angles_deg: np.ndarray
    spread_deg: float
    weakest_direction: np.ndarray
    rms_about_axes_deg: np.ndarray
    frame: str

    @property
    def median_angle_deg(self) -> float:
        return float(np.median(self.all_angles_deg)) if self.all_angles_deg.size else 0.0


def rotation_axis_coverage(problem: HandEyeProblem) -> AxisCoverage:
    """:class:`AxisCoverage` of a problem's hand motions (all posture pairs)."""
    frame = "tool0" if problem.setup == EYE_IN_HAND else "base"
    motions = relative_motions(problem)
    q = motions.q_a  # (p, 4), w >= 0: angle in [0, 180]
    angles = motions.angle_a_deg
    vectors = q[:, 1:]
    rotvec_deg = angles[:, None] * vectors / np.maximum(np.linalg.norm(vectors, axis=1, keepdims=True), 1e-15)
    rms = np.sqrt(np.mean(rotvec_deg**2, axis=0)) if len(angles) else np.zeros(3)
    keep = angles >= MIN_AXIS_ANGLE_DEG
    vectors = vectors[keep]
    axes = vectors / np.linalg.norm(vectors, axis=1, keepdims=True) if len(vectors) else np.zeros((0, 3))
    weight = float(np.sum(vectors**2))
    if weight > 0:
        scatter = vectors.T @ vectors / weight  # sum of sin^2(a/2) n n^T over the sum of sin^2(a/2)
        eigenvalues, eigenvectors = np.linalg.eigh(scatter)
        spread = math.degrees(math.asin(math.sqrt(min(max(eigenvalues[0], 0.0), 1.0))))
        weakest = eigenvectors[:, 0]
        weakest = weakest * np.sign(weakest[np.argmax(np.abs(weakest))])
    else:
        spread, weakest = 0.0, np.array([0.0, 0.0, 1.0])
    return AxisCoverage(axes, angles[keep], angles, spread, weakest, rms, frame)


#: The name of d_org over every posture, outliers included (the report's second figure).
D_ORG_ALL_NAME = "d_org incl. outliers"


def kept_postures(problem: HandEyeProblem, result) -> np.ndarray:
    """Boolean mask ``(n,)`` of the postures ``result`` kept (all but its outliers)."""
    outliers = {int(i) for i in result.outliers}
    return np.array([int(i) not in outliers for i in problem.posture_ids], dtype=bool)


@dataclass(frozen=True)
class DOrg:
    """``d_org`` as the station reports it (see :func:`station_d_org`).

    Attributes
    ----------
    mm : float
        Eq. 22 over the kept postures.
    incl_outliers_mm : float or None
        Eq. 22 over every posture (:data:`D_ORG_ALL_NAME`); ``None`` when no posture was left out.
    postures : int
        Postures it is computed over.
    outliers : int
        Postures left out.
    points_per_posture : int
        Board points per posture.
    corners : bool
        The points are the measured board corners (else the three compact points of the board poses).
    """

    mm: float
    incl_outliers_mm: float | None
    postures: int
    outliers: int
    points_per_posture: int
    corners: bool

    def basis(self) -> str:
        """Which postures and points: ``over the 28 inlier postures (2 outliers left out), 104 board
        corners per posture``."""
        postures = (f"over the {self.postures} inlier postures ({self.outliers} outlier"
                    f"{'s' if self.outliers != 1 else ''} left out)" if self.outliers else
                    f"over all {self.postures} postures (no outliers)")
        points = (f"{self.points_per_posture} board corners per posture" if self.corners else
                  f"{self.points_per_posture} compact points per posture (board centre and one point along each "
                  f"board axis, from the board poses)")
        return f"{postures}, {points}"


def station_d_org(problem: HandEyeProblem, result, x=None) -> DOrg:
    """THE d_org of the station: eq. 22 over the postures ``result`` kept, on the session's board points.

    Every place the operator reads d_org (verdict, HTML header, method table and chart, metrics table,
    text summary) calls this, so they show the same number for the same result.

    Parameters
    ----------
    problem : HandEyeProblem
    result : CalibrationResult
        The chosen result: its outliers decide the postures.
    x : ndarray, shape (4, 4), optional
        Another solution of the same problem (a compared method) to measure on the SAME postures and
        points; ``result.x`` when omitted.

    Returns
    -------
    DOrg
    """
    x = result.x if x is None else np.asarray(x, float)
    kept = kept_postures(problem, result)
    fixed = fixed_points(problem.hand, x, problem.points_cam)
    n_kept = int(kept.sum())
    value = d_org(fixed[kept]) if n_kept >= 1 else float("nan")
    left_out = problem.n - n_kept
    return DOrg(value, d_org(fixed) if left_out else None, n_kept, left_out, int(problem.points_cam.shape[1]),
                bool(problem.points_cam.shape[1] > 3))


def direction_name(direction, frame: str) -> str:
    """``'tool0 z'`` when a unit vector lies within 30 deg of a frame axis, else its components."""
    direction = np.asarray(direction, float)
    k = int(np.argmax(np.abs(direction)))
    if abs(direction[k]) >= math.cos(math.radians(30.0)):
        return f"{frame} {'xyz'[k]}"
    return f"{frame} direction ({direction[0]:.2f}, {direction[1]:.2f}, {direction[2]:.2f})"


class Check(NamedTuple):
    """One line of the verdict: ``(name, value, limit, passed, advice)``.

    ``name`` is the threshold key (``max_...`` means value <= limit, ``min_...`` value >= limit);
    ``value`` is ``None`` when the figure is not available (counts as failed); ``advice`` says what to
    do next when the check failed ('' when it passed, or a note worth reading).
    """

    name: str
    value: float | None
    limit: float
    passed: bool
    advice: str


#: key -> (what is checked, unit, format of values)
CHECK_LABELS = {
    "max_d_org_mm": ("board points scatter in the fixed frame, d_org (eq. 22)", "mm", "{:.3f}"),
    "max_posture_residual_mm": ("largest residual of a posture kept in the solution", "mm", "{:.3f}"),
    "max_sigma_translation_mm": ("camera position uncertainty, largest one-sigma axis", "mm", "{:.3f}"),
    "max_sigma_rotation_deg": ("camera rotation uncertainty, largest one-sigma axis", "deg", "{:.4f}"),
    "min_inlier_postures": ("consistent postures (not outliers)", "", "{:.0f}"),
    "max_outlier_fraction": ("share of postures rejected as outliers", "", "{:.0%}"),
    "min_rotation_axis_spread_deg": ("spread of the rotation axes about the least exercised direction", "deg", "{:.1f}"),
    "min_median_rotation_deg": ("median rotation between two postures", "deg", "{:.1f}"),
    "min_camera_offset_mm": ("camera frame's distance from the flange (not inside it)", "mm", "{:.1f}"),
    "max_camera_offset_mm": ("camera frame's distance from the flange (not far off)", "mm", "{:.1f}"),
}


def format_check_value(name: str, value) -> str:
    """A check's value (or limit) as the report prints it, with its unit."""
    if value is None:
        return "n/a"
    _, unit, fmt = CHECK_LABELS.get(name, (name, "", "{:.4g}"))
    text = fmt.format(value)
    return f"{text} {unit}".strip()


@dataclass(frozen=True)
class Verdict:
    """The outcome of :func:`verdict`.

    Attributes
    ----------
    passed : bool
        Every check passed.
    checks : list of Check
    thresholds : QualityThresholds
    cause : str
        What the failed checks have in common, when the data show it (lengths not in mm: what to fix);
        '' otherwise. It leads the one-line verdict of a FAIL.
    """

    passed: bool
    checks: list
    thresholds: QualityThresholds = QualityThresholds()
    cause: str = ""

    @property
    def failed(self) -> list:
        return [c for c in self.checks if not c.passed]

    def line(self) -> str:
        """One line for the terminal: ``verdict: PASS (10 of 10 checks)``, or FAIL with the cause (when
        known) and the failed checks."""
        if self.passed:
            return f"verdict: PASS ({len(self.checks)} of {len(self.checks)} checks)"
        failed = "; ".join(
            f"{c.name} {format_check_value(c.name, c.value)} (limit {format_check_value(c.name, c.limit)})"
            for c in self.failed)
        cause = f" - {self.cause}" if self.cause else ""
        return f"verdict: FAIL{cause} ({len(self.failed)} of {len(self.checks)} checks failed: {failed})"

    def to_json(self) -> dict:
        return {
            "passed": self.passed,
            "cause": self.cause,
            "checks": [{"name": c.name, "value": c.value, "limit": c.limit, "passed": c.passed, "advice": c.advice}
                       for c in self.checks],
            "thresholds": self.thresholds.to_dict(),
        }


def _postures_text(items) -> str:
    return ", ".join(f"{i} ({r:.2f} mm)" for i, r in items)


def _check(name: str, value, limit, advice_if_failed: str, note: str = "") -> Check:
    if value is None:
        return Check(name, None, limit, False, advice_if_failed)
    passed = value <= limit if name.startswith("max_") else value >= limit
    return Check(name, float(value), limit, bool(passed), note if passed else advice_if_failed)


def verdict(result, problem: HandEyeProblem, thresholds: QualityThresholds | None = None) -> Verdict:
    """Judge a calibration against thresholds.

    Parameters
    ----------
    result : CalibrationResult
        From ``calibration.solve.calibrate`` on ``problem``.
    problem : HandEyeProblem
    thresholds : QualityThresholds, optional
        Defaults when omitted.

    Returns
    -------
    Verdict
        ``passed`` and one :class:`Check` per threshold, in the order of :class:`QualityThresholds`
        (the camera-offset pair eye-in-hand only). When the poses' lengths do not look like millimetres
        (``station.units_advice``) every failed check's advice, and the verdict's ``cause``, say which
        units to fix instead of what to re-capture.
    """
    from .units_advice import units_advice

    t = thresholds or QualityThresholds()
    ids = [int(i) for i in problem.posture_ids]
    outliers = [int(i) for i in result.outliers]
    inlier_mask = kept_postures(problem, result)
    residuals = {int(k): float(v) for k, v in result.residuals_mm.items()}
    n, n_in = len(ids), int(inlier_mask.sum())
    checks = []

    # consistency
    worst = sorted(((i, residuals[i]) for i in ids if i in residuals and i not in outliers), key=lambda item: -item[1])
    high = [(i, r) for i, r in worst if r > t.max_posture_residual_mm]
    scatter = station_d_org(problem, result)
    d_org_value = scatter.mm if math.isfinite(scatter.mm) else None
    blame = (f"postures {_postures_text(high[:5])} stand out: re-capture or remove them first" if high else
             "all postures share it: check the stereo calibration (STEREO.yaml, baseline in mm), that the robot "
             "stood still (fine point) at each capture, and that tool0 poses come from CRobT with tool0/wobj0")
    checks.append(_check("max_d_org_mm", d_org_value, t.max_d_org_mm,
                         f"board points scatter {d_org_value or 0.0:.2f} mm in the fixed frame "
                         f"(d_org {scatter.basis()}); {blame}"))
    checks.append(_check(
        "max_posture_residual_mm", worst[0][1] if worst else 0.0, t.max_posture_residual_mm,
        f"check postures {_postures_text(high[:8])}: board partly hidden or misdetected, robot not at rest, "
        f"or pose and image from different postures? re-capture or delete them"))

    # precision
    u = result.uncertainty
    no_sigma = (f"method {result.method} gives no uncertainty; run without --method (the robust default) "
                f"to judge the precision")
    if u is None:
        checks.append(_check("max_sigma_translation_mm", None, t.max_sigma_translation_mm, no_sigma))
        checks.append(_check("max_sigma_rotation_deg", None, t.max_sigma_rotation_deg, no_sigma))
    else:
        st, sr = np.asarray(u["translation_mm"], float), np.asarray(u["rotation_deg"], float)
        more = (f"; with {n_in} postures, more postures shrink it roughly as 1/sqrt(n) (the plan takes 30)"
                if n_in < 30 else "")
        checks.append(_check(
            "max_sigma_translation_mm", float(st.max()), t.max_sigma_translation_mm,
            f"camera position uncertain to +-{st.max():.3f} mm along camera {'xyz'[int(st.argmax())]}: add postures "
            f"with larger rotations (20-45 deg) about different axes and the board nearer (0.7-0.9 m){more}"))
        checks.append(_check(
            "max_sigma_rotation_deg", float(sr.max()), t.max_sigma_rotation_deg,
            f"camera rotation uncertain to +-{sr.max():.4f} deg about camera {'xyz'[int(sr.argmax())]}: add postures "
            f"that tilt the camera further (20-45 deg) about different axes, with the board filling the image{more}"))

    # motion
    checks.append(_check("min_inlier_postures", n_in, t.min_inlier_postures,
                         f"only {n_in} consistent postures: capture at least {t.min_inlier_postures - n_in} more "
                         f"(the capture plan takes 30)"))
    outlier_text = _postures_text((i, residuals.get(i, float("nan"))) for i in outliers)
    fraction = len(outliers) / n if n else 0.0
    checks.append(_check(
        "max_outlier_fraction", fraction, t.max_outlier_fraction,
        f"{len(outliers)} of {n} postures rejected ({outlier_text}): that many hints at a systematic problem; check "
        f"that each pose and image belong to the same posture, units (mm) and the board orientation, "
        f"then re-capture",
        note=(f"{'posture' if len(outliers) == 1 else 'postures'} {outlier_text} "
              f"{'was' if len(outliers) == 1 else 'were'} left out of the solution; check "
              f"{'it' if len(outliers) == 1 else 'them'} (board partly hidden or misdetected?)") if outliers else ""))
    coverage = rotation_axis_coverage(problem.subset(inlier_mask)) if n_in >= 2 else None
    if coverage is None:
        checks.append(_check("min_rotation_axis_spread_deg", None, t.min_rotation_axis_spread_deg,
                             "too few consistent postures to judge the rotation axes"))
        checks.append(_check("min_median_rotation_deg", None, t.min_median_rotation_deg,
                             "too few consistent postures to judge the rotations"))
    else:
        direction = direction_name(coverage.weakest_direction, coverage.frame)
        hint = " (axis 6 alone turns the flange about tool0 z)" if direction == "tool0 z" else ""
        checks.append(_check(
            "min_rotation_axis_spread_deg", coverage.spread_deg, t.min_rotation_axis_spread_deg,
            f"the flange hardly ever rotated about the {direction} axis: add postures rotating about it{hint}, "
            f"keeping the board in view"))
        checks.append(_check(
            "min_median_rotation_deg", coverage.median_angle_deg, t.min_median_rotation_deg,
            f"postures differ by only {coverage.median_angle_deg:.1f} deg of rotation (median): turn the flange "
            f"by 20-45 deg between postures, keeping the board in view"))

    # where the camera is
    if problem.setup == EYE_IN_HAND:
        offset = float(np.linalg.norm(result.x[:3, 3]))
        checks.append(_check(
            "min_camera_offset_mm", offset, t.min_camera_offset_mm,
            f"the camera frame is {offset:.1f} mm from the flange, inside it: the session's lengths look like metres; "
            f"lengths must be in mm (robot poses, board points and the stereo baseline)"))
        checks.append(_check(
            "max_camera_offset_mm", offset, t.max_camera_offset_mm,
            f"the camera frame is {offset:.0f} mm from the flange, more than {t.max_camera_offset_mm:g} mm: check the "
            f"session's units (mm on both sides) and set-up (eye-in-hand?), or raise max_camera_offset_mm if the "
            f"camera really sits that far"))

    passed = all(c.passed for c in checks)
    units = units_advice(problem)
    if units is None:
        return Verdict(passed, checks, t)
    checks = [_with_units(c, units, outliers) for c in checks]
    return Verdict(passed, checks, t, cause="" if passed else units.text)


def _with_units(check: Check, units, outliers) -> Check:
    """A check whose advice names the units problem: instead of the advice when it failed on a figure
    (a figure that is not available keeps its own advice); added to the note on outliers when the
    postures in another unit were left out (the result may then be right)."""
    if not check.passed and check.value is not None:
        return check._replace(advice=units.text)
    if check.name == "max_outlier_fraction" and units.postures and set(units.postures) <= set(outliers):
        return check._replace(advice=f"{check.advice}; {units.text}" if check.advice else units.text)
    return check
