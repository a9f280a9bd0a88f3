"""Quality verdict of a calibration: thresholds, checks, and what to do when a check fails.

The station's goal is the camera pose to about a tenth of a millimetre. Whether a calibration gets
there shows in four kinds of figures, each checked against a threshold of :class:`QualityThresholds`:

- **Consistency of the data** under the solved ``X``: the board points carried into the frame the
  board is fixed in (``base`` eye-in-hand) should sit on top of each other for every posture.
  ``d_org`` and each posture's residual (the same per posture) measure it. ``d_org`` has ONE
  definition, ``calibration.quality_words.result_d_org``, used by the verdict, the HTML report
  (header, method table and chart, metrics) and the text summary alike: eq. 22 of the paper (mean
  distance of a point from its mean position) over the postures the chosen result kept (its
  inliers), on the session's board points (every board corner when the postures hold corners, else
  the three compact points of the board poses), the same points and postures for every method
  compared. Over all postures, outliers included, the same figure is called ``d_org incl. outliers``.
- **Where the camera is**: eye-in-hand, the camera's optical centre cannot sit inside the flange
  (a session written in metres solves to a frame a fraction of a millimetre from it) nor metres away.
- **Precision of X**: the one-sigma uncertainty of the default method (translation per axis in
  mm, rotation about each axis of the camera frame in degrees).
- **Motion that determines X**: enough consistent postures, few outliers, relative flange rotations
  that are sizeable (median relative rotation angle) and turn about every direction (rotation-axis
  spread; ``AX = XB`` is blind about an axis it never sees the flange turn about). Both words are
  defined once, in ``calibration.quality_words``.

Every failed check carries advice on what to do next at the station.
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ...base import HandEyeError, brief
from ...calibration import EYE_IN_HAND, HandEyeProblem
from ...calibration import (
    AXIS_SPREAD_NAME,
    MAX_AXIS_SPREAD_DEG,
    MEDIAN_ANGLE_NAME,
    POSTURE_RESIDUAL_NAME,
    AxisCoverage,
    DOrg,
    kept_postures,
    result_d_org,
    rotation_axis_coverage,
)

if TYPE_CHECKING:
    from ...calibration import CalibrationResult
    from ..config.station import StationConfig
    from .units_advice import UnitsAdvice

__all__ = [
    "CHECK_LABELS",
    "Check",
    "QualityFigures",
    "QualityThresholds",
    "ThresholdError",
    "Verdict",
    "MotionShortfall",
    "camera_too_near",
    "meets",
    "motion_shortfalls",
    "config_thresholds",
    "load_thresholds",
    "quality_figures",
    "verdict",
]


class ThresholdError(HandEyeError):
    """A quality-threshold mapping or file is malformed (unknown key, bad value)."""


@dataclass(frozen=True)
class QualityThresholds:
    """Limits a calibration must meet to PASS (the defaults suit an NDT station with a Bumblebee XB3
    at 0.7-1.2 m from a 13x8 board on an IRB 1400, 30 planned postures).

    Attributes
    ----------
    max_d_org_mm : float
        Largest ``d_org`` (eq. 22, ``calibration.quality_words.result_d_org``): mean distance of a board point in ``base``
        from its mean position, over the postures the result kept, every board corner of each (the
        three compact points when the session holds board poses only). It adds up the camera's 3-D
        corner noise (~0.15-0.4 mm for the XB3 wide pair at 1 m), the robot's repeatability and any kinematic or stereo calibration
        error. Default 1.0 mm: above it something systematic is wrong (stereo model, robot not at rest,
        tool0 poses from the wrong frame).
    max_posture_residual_mm : float
        Largest posture residual of the postures kept in the solution (``quality_words``: the mean
        distance of its board points in the fixed frame from their mean positions over the kept
        postures, the same for every method). Default 2.0 mm: a posture above it is most likely a misdetected or
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
        Smallest rotation-axis spread (``calibration.quality_words.rotation_axis_spread``) of the
        kept postures: how far the relative rotation axes rise out of the plane they lie closest to
        (asin of the RMS sine of that elevation, weighted by ``sin^2(angle / 2)`` so that small
        rotations count little). 0 when the flange only ever turned about axes in one plane, 35.3 deg
        when the axes cover the sphere evenly. Default 10 deg (the synthetic 30-posture plan reaches
        ~19 deg); the capture plan warns below it too.
    min_median_rotation_deg : float
        Smallest median relative rotation angle between two kept postures
        (``calibration.quality_words.relative_rotation_angles_deg``). Default 15 deg: small rotations leave the
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
    def from_dict(cls, mapping: object, source: str = "thresholds") -> QualityThresholds:
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


def load_thresholds(path: str | Path) -> QualityThresholds:
    """Thresholds from a YAML file: a mapping of threshold keys, or a station config whose ``quality``
    section holds them (the rest of such a file is ignored here).

    Raises
    ------
    ThresholdError
        File missing or unreadable, not YAML, or a bad key or value (see :meth:`QualityThresholds.from_dict`).
    """
    from ...base import parse_yaml, read_text_file

    path = Path(path)
    text = read_text_file(path, "thresholds file", ThresholdError, missing=f"thresholds file not found: {path}")
    data = parse_yaml(text, path, ThresholdError, "; write 'key: number' lines")
    if isinstance(data, dict) and isinstance(data.get("quality"), dict):
        return QualityThresholds.from_dict(data["quality"], f"{path} (quality)")
    return QualityThresholds.from_dict(data if data is not None else {}, str(path))


def direction_name(direction: np.ndarray, frame: str) -> str:
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
    "max_posture_residual_mm": (f"largest {POSTURE_RESIDUAL_NAME} of a posture kept in the solution", "mm", "{:.3f}"),
    "max_sigma_translation_mm": ("camera position uncertainty, largest one-sigma axis", "mm", "{:.3f}"),
    "max_sigma_rotation_deg": ("camera rotation uncertainty, largest one-sigma axis", "deg", "{:.4f}"),
    "min_inlier_postures": ("consistent postures (not outliers)", "", "{:.0f}"),
    "max_outlier_fraction": ("share of postures rejected as outliers", "", "{:.0%}"),
    "min_rotation_axis_spread_deg": (AXIS_SPREAD_NAME, "deg", "{:.1f}"),
    "min_median_rotation_deg": (MEDIAN_ANGLE_NAME, "deg", "{:.1f}"),
    "min_camera_offset_mm": ("camera frame's distance from the flange (not inside it)", "mm", "{:.1f}"),
    "max_camera_offset_mm": ("camera frame's distance from the flange (not far off)", "mm", "{:.1f}"),
}


def format_check_value(name: str, value: object) -> str:
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


def meets(key: str, value: float, limit: float) -> bool:
    """Whether ``value`` meets the threshold ``key`` = ``limit``: at most a ``max_`` one, at least any other.
    The one rule of every check of the verdict, the plan and guided capture."""
    return bool(value <= limit if key.startswith("max_") else value >= limit)


def _check(name: str, value, limit, advice_if_failed: str, note: str = "") -> Check:
    if value is None:
        return Check(name, None, limit, False, advice_if_failed)
    passed = meets(name, value, limit)
    return Check(name, float(value), limit, bool(passed), note if passed else advice_if_failed)


@dataclass(frozen=True)
class QualityFigures:
    """The quality words of one result, computed once (``calibration.quality_words``) for the verdict
    and every presenter.

    Attributes
    ----------
    d_org : DOrg
        ``result_d_org``: eq. 22 over the kept postures, every board point.
    coverage : AxisCoverage
        Rotation-axis coverage of the kept postures (spread, least exercised direction, angles).
    units : UnitsAdvice or None
        What to tell the operator when the poses' lengths do not look like millimetres
        (``station.report.units_advice``); ``None`` when they do.
    """

    d_org: DOrg
    coverage: AxisCoverage
    units: UnitsAdvice | None


def quality_figures(problem: HandEyeProblem, result: CalibrationResult) -> QualityFigures:
    """:class:`QualityFigures` of ``result`` on ``problem``."""
    from .units_advice import units_advice

    return QualityFigures(result_d_org(problem, result),
                          rotation_axis_coverage(problem, kept_postures(problem, result)), units_advice(problem))


def config_thresholds(config: StationConfig) -> QualityThresholds:
    """The thresholds of a station configuration's ``quality`` section (defaults for keys left out)."""
    return QualityThresholds.from_dict(config.quality)


def verdict(result: CalibrationResult, problem: HandEyeProblem, thresholds: QualityThresholds | None = None,
            figures: QualityFigures | None = None) -> Verdict:
    """Judge a calibration against thresholds.

    Parameters
    ----------
    result : CalibrationResult
        From ``calibration.solve.calibrate`` on ``problem``.
    problem : HandEyeProblem
    thresholds : QualityThresholds, optional
        Defaults when omitted.
    figures : QualityFigures, optional
        The result's quality words when already computed (``station.report.assessment`` does); computed
        here when omitted.

    Returns
    -------
    Verdict
        ``passed`` and one :class:`Check` per threshold, in the order of :class:`QualityThresholds`
        (the camera-offset pair eye-in-hand only). When the poses' lengths do not look like millimetres
        (``station.report.units_advice``) every failed check's advice, and the verdict's ``cause``, say which
        units to fix instead of what to re-capture.
    """
    t = thresholds or QualityThresholds()
    figures = figures or quality_figures(problem, result)
    outliers = [int(i) for i in result.outliers]
    checks = (_consistency_checks(result, problem, t, figures.d_org)
              + _precision_checks(result, t, figures.d_org.postures)
              + _motion_checks(result, problem, t, figures)
              + _placement_checks(result, problem, t))
    passed = all(c.passed for c in checks)
    units = figures.units
    if units is None:
        return Verdict(passed, checks, t)
    checks = [_with_units(c, units, outliers) for c in checks]
    return Verdict(passed, checks, t, cause="" if passed else units.text)


def _inlier_residuals(result, problem: HandEyeProblem) -> list:
    """``[(posture, residual mm)]`` of the kept postures, largest first."""
    outliers = {int(i) for i in result.outliers}
    residuals = {int(k): float(v) for k, v in result.residuals_mm.items()}
    return sorted(((i, residuals[i]) for i in (int(i) for i in problem.posture_ids)
                   if i in residuals and i not in outliers), key=lambda item: -item[1])


def _consistency_checks(result, problem: HandEyeProblem, t: QualityThresholds, scatter: DOrg) -> list:
    """``max_d_org_mm`` and ``max_posture_residual_mm``: the board points' consistency under X."""
    worst = _inlier_residuals(result, problem)
    high = [(i, r) for i, r in worst if r > t.max_posture_residual_mm]
    d_org_value = scatter.mm if math.isfinite(scatter.mm) else None
    blame = (f"postures {_postures_text(high[:5])} stand out: re-capture or remove them first" if high else
             "all postures share it: check the stereo calibration (STEREO.yaml, baseline in mm), that the robot "
             "stood still (fine point) at each capture, and that tool0 poses come from CRobT with tool0/wobj0")
    return [
        _check("max_d_org_mm", d_org_value, t.max_d_org_mm,
               f"board points scatter {d_org_value or 0.0:.2f} mm in the fixed frame "
               f"(d_org {scatter.basis()}); {blame}"),
        _check("max_posture_residual_mm", worst[0][1] if worst else 0.0, t.max_posture_residual_mm,
               f"check postures {_postures_text(high[:8])}: board partly hidden or misdetected, robot not at rest, "
               f"or pose and image from different postures? re-capture or delete them"),
    ]


def _precision_checks(result, t: QualityThresholds, n_in: int) -> list:
    """``max_sigma_translation_mm`` and ``max_sigma_rotation_deg``: the one-sigma uncertainty of X."""
    u = result.uncertainty
    if u is None:
        no_sigma = (f"method {result.method} gives no uncertainty; run without --method (the default) "
                    f"to judge the precision")
        return [_check("max_sigma_translation_mm", None, t.max_sigma_translation_mm, no_sigma),
                _check("max_sigma_rotation_deg", None, t.max_sigma_rotation_deg, no_sigma)]
    st, sr = np.asarray(u["translation_mm"], float), np.asarray(u["rotation_deg"], float)
    more = (f"; with {n_in} postures, more postures shrink it roughly as 1/sqrt(n) (the plan takes 30)"
            if n_in < 30 else "")
    return [
        _check("max_sigma_translation_mm", float(st.max()), t.max_sigma_translation_mm,
               f"camera position uncertain to +-{st.max():.3f} mm along camera {'xyz'[int(st.argmax())]}: add postures "
               f"with larger rotations (20-45 deg) about different axes and the board nearer (0.7-0.9 m){more}"),
        _check("max_sigma_rotation_deg", float(sr.max()), t.max_sigma_rotation_deg,
               f"camera rotation uncertain to +-{sr.max():.4f} deg about camera {'xyz'[int(sr.argmax())]}: add postures "
               f"that tilt the camera further (20-45 deg) about different axes, with the board filling the image{more}"),
    ]


class MotionShortfall(NamedTuple):
    """A motion word of a set of flange poses below its threshold (:func:`motion_shortfalls`).

    ``key`` is the threshold's key, ``word`` the quality word's name
    (``calibration.quality_words``), ``value`` its figure (deg) and ``required`` the threshold (deg).
    """

    key: str
    word: str
    value: float
    required: float


def motion_shortfalls(coverage, thresholds: QualityThresholds) -> list:
    """The one check of the motion words that the plan, guided capture and the verdict all make: the
    rotation-axis spread and the median relative rotation angle of ``coverage`` (an
    ``AxisCoverage``) against ``min_rotation_axis_spread_deg`` and ``min_median_rotation_deg``.

    Returns
    -------
    list of MotionShortfall
        Those below their threshold, spread first; each caller adds its own advice.
    """
    words = (("min_rotation_axis_spread_deg", AXIS_SPREAD_NAME, coverage.spread_deg),
             ("min_median_rotation_deg", MEDIAN_ANGLE_NAME, coverage.median_angle_deg))
    return [MotionShortfall(key, word, float(value), float(getattr(thresholds, key)))
            for key, word, value in words if not meets(key, value, getattr(thresholds, key))]


def _motion_checks(result, problem: HandEyeProblem, t: QualityThresholds, figures: QualityFigures) -> list:
    """Postures and outliers, then the rotation-axis spread and the median relative rotation angle
    (``calibration.quality_words``) of the kept postures."""
    n, n_in = problem.n, figures.d_org.postures
    outliers = [int(i) for i in result.outliers]
    residuals = {int(k): float(v) for k, v in result.residuals_mm.items()}
    outlier_text = _postures_text((i, residuals.get(i, float("nan"))) for i in outliers)
    one = len(outliers) == 1
    checks = [
        _check("min_inlier_postures", n_in, t.min_inlier_postures,
               f"only {n_in} consistent postures: capture at least {t.min_inlier_postures - n_in} more "
               f"(the capture plan takes 30)"),
        _check("max_outlier_fraction", len(outliers) / n if n else 0.0, t.max_outlier_fraction,
               f"{len(outliers)} of {n} postures rejected ({outlier_text}): that many hints at a systematic problem; "
               f"check that each pose and image belong to the same posture, units (mm) and the board orientation, "
               f"then re-capture",
               note=(f"{'posture' if one else 'postures'} {outlier_text} {'was' if one else 'were'} left out of the "
                     f"solution; check {'it' if one else 'them'} (board partly hidden or misdetected?)")
               if outliers else ""),
    ]
    if n_in < 2:
        return checks + [
            _check("min_rotation_axis_spread_deg", None, t.min_rotation_axis_spread_deg,
                   "too few consistent postures to judge the rotation axes"),
            _check("min_median_rotation_deg", None, t.min_median_rotation_deg,
                   "too few consistent postures to judge the rotations")]
    coverage = figures.coverage
    direction = direction_name(coverage.weakest_direction, coverage.frame)
    hint = " (axis 6 alone turns the flange about tool0 z)" if direction == "tool0 z" else ""
    return checks + [
        _check("min_rotation_axis_spread_deg", coverage.spread_deg, t.min_rotation_axis_spread_deg,
               f"the flange hardly ever rotated about the {direction} axis: add postures rotating about it{hint}, "
               f"keeping the board in view"),
        _check("min_median_rotation_deg", coverage.median_angle_deg, t.min_median_rotation_deg,
               f"postures differ by only {coverage.median_angle_deg:.1f} deg of rotation (median): turn the flange "
               f"by 20-45 deg between postures, keeping the board in view")]


def camera_too_near(offset_mm: float, thresholds: QualityThresholds) -> str:
    """Why an eye-in-hand camera frame sits nearer the flange than ``min_camera_offset_mm``, in words.

    Metres only when the offset, read as metres, is a camera offset the thresholds admit in mm (at most
    ``max_camera_offset_mm`` / 1000: 0.165 is a 165 mm mount in metres); a larger one (14 mm) cannot be
    metres (14 m) and is a camera frame too near the flange: a wrong frame or set-up.
    """
    if offset_mm * 1000.0 <= thresholds.max_camera_offset_mm:
        return (f"the camera frame is {offset_mm:.1f} mm from the flange, inside it (quality.min_camera_offset_mm "
                f"{thresholds.min_camera_offset_mm:g}): the session's lengths look like metres; lengths must be in mm "
                "(robot poses, board points and the stereo baseline)")
    return (f"the camera frame is {offset_mm:.1f} mm from the flange, nearer than quality.min_camera_offset_mm "
            f"({thresholds.min_camera_offset_mm:g}): too near for a camera on its bracket, and not metres (that would be "
            f"{offset_mm:.0f} m); check the set-up: eye-in-hand with the camera on the flange, tool0 poses from CRobT "
            "with tool0/wobj0 (not the camera's tool), board points in the camera frame; or lower "
            "min_camera_offset_mm if the camera really sits that close")


def _placement_checks(result, problem: HandEyeProblem, t: QualityThresholds) -> list:
    """Eye-in-hand: the camera frame's distance from the flange (not inside it, not far off)."""
    if problem.setup != EYE_IN_HAND:
        return []
    offset = float(np.linalg.norm(result.x[:3, 3]))
    return [
        _check("min_camera_offset_mm", offset, t.min_camera_offset_mm, camera_too_near(offset, t)),
        _check("max_camera_offset_mm", offset, t.max_camera_offset_mm,
               f"the camera frame is {offset:.0f} mm from the flange, more than {t.max_camera_offset_mm:g} mm: check the "
               f"session's units (mm on both sides) and set-up (eye-in-hand?), or raise max_camera_offset_mm if the "
               f"camera really sits that far"),
    ]


def _with_units(check: Check, units, outliers) -> Check:
    """A check whose advice names the units problem: instead of the advice when it failed on a figure
    (a figure that is not available keeps its own advice); added to the note on outliers when the
    postures in another unit were left out (the result may then be right)."""
    if not check.passed and check.value is not None:
        return check._replace(advice=units.text)
    if check.name == "max_outlier_fraction" and units.postures and set(units.postures) <= set(outliers):
        return check._replace(advice=f"{check.advice}; {units.text}" if check.advice else units.text)
    return check
