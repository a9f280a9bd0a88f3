"""When a change found by ``handeye verify`` matters: beyond the noise AND beyond a practical tolerance.

The test (``calibration.verification.drift_test``) says whether the revisited postures disagree with
the calibration beyond its noise. With a well-measured station that is true of changes far too small
to act on (0.05 mm of thermal drift against a calibration whose own one-sigma is 0.03 mm is
detectable at once). A check says DRIFT only when the change is also larger than the station's
tolerance: its size is the best explanation's (``calibration.drift_causes``: the camera's or the
board's shift and turn, a joint zero's turn), compared with ``verify.tolerance_mm`` and
``verify.tolerance_deg`` of the station config, by default the station's quality thresholds
``max_sigma_translation_mm`` / ``max_sigma_rotation_deg`` (a change smaller than the uncertainty a
passing calibration may have is within what the calibration itself claims).

A discrepancy that no single explanation accounts for has no size to compare: it stays DRIFT.

The controller's camera tooldata is held to the same tolerance (:func:`tool_difference`): one that
differs from SESSION's beyond the last written digit is a finding, DRIFT only when the difference
(its translation or its rotation) is larger than the tolerance; both are stated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2 as chi2_dist

__all__ = ["DriftSize", "DriftTolerance", "ToolDifference", "drift_size", "drift_tolerance", "explained",
           "tool_difference", "verdict_reason"]


@dataclass(frozen=True)
class DriftTolerance:
    """The smallest change a check acts on, and where the values come from.

    Attributes
    ----------
    translation_mm, rotation_deg : float
    source : str
        ``verify.tolerance_mm / verify.tolerance_deg`` or the quality thresholds' keys.
    """

    translation_mm: float
    rotation_deg: float
    source: str

    def text(self) -> str:
        return f"{self.translation_mm:g} mm / {self.rotation_deg:g} deg"

    def to_json(self) -> dict:
        return {"translation_mm": self.translation_mm, "rotation_deg": self.rotation_deg, "source": self.source}

    def exceeded_by(self, translation_mm: float, rotation_deg: float) -> bool:
        """Whether a change of this size is larger than the tolerance in translation or rotation."""
        return bool(translation_mm > self.translation_mm or rotation_deg > self.rotation_deg)


@dataclass(frozen=True)
class DriftSize:
    """The size of a detected change: the best explanation's, and whether it accounts for the discrepancy.

    Attributes
    ----------
    cause : str
        The explanation's name (``camera``, ``board``, ``joint 3``).
    translation_mm, rotation_deg : float
    explained : bool
        Its fit leaves no more than the noise (else the size understates the change).
    beyond : bool
        Larger than the tolerance in translation or rotation, or not explained.
    """

    cause: str
    translation_mm: float
    rotation_deg: float
    explained: bool
    beyond: bool

    def text(self) -> str:
        return f"{self.cause} {self.translation_mm:.3f} mm / {self.rotation_deg:.4f} deg"

    def to_json(self) -> dict:
        return {"cause": self.cause, "translation_mm": round(self.translation_mm, 4),
                "rotation_deg": round(self.rotation_deg, 5), "explained": self.explained,
                "beyond_tolerance": self.beyond}


def drift_tolerance(config, thresholds=None) -> DriftTolerance:
    """The station's tolerance: ``config.verify`` where set, else the quality thresholds' sigmas
    (``thresholds``, default ``station.report.quality.config_thresholds(config)``)."""
    from ..report.quality import config_thresholds  # noqa: PLC0415

    settings = config.verify
    thresholds = thresholds if thresholds is not None else config_thresholds(config)
    mm, deg = settings.tolerance_mm, settings.tolerance_deg
    source = {(False, False): "the quality thresholds max_sigma_translation_mm / max_sigma_rotation_deg",
              (True, True): "verify.tolerance_mm / tolerance_deg",
              (True, False): "verify.tolerance_mm / the quality threshold max_sigma_rotation_deg",
              (False, True): "the quality threshold max_sigma_translation_mm / verify.tolerance_deg"}[
        (mm is not None, deg is not None)]
    return DriftTolerance(float(thresholds.max_sigma_translation_mm if mm is None else mm),
                          float(thresholds.max_sigma_rotation_deg if deg is None else deg), source)


def explained(best, test) -> bool:
    """Whether explanation ``best`` leaves no more than the noise of the drift test ``test``: its
    ``χ²`` below the ``1 - level`` point of a chi-square on the degrees of freedom it leaves."""
    return bool(best.chi2 < float(chi2_dist.ppf(1.0 - test.level, max(test.degrees - len(best.parameters), 1))))


def drift_size(explanations, test, tolerance: DriftTolerance) -> DriftSize | None:
    """The detected change's size against ``tolerance``; None when the test found nothing.

    Parameters
    ----------
    explanations : list of Explanation
        Best first (``calibration.drift_causes.explain``).
    test : DriftTest
    tolerance : DriftTolerance
    """
    if test is None or not test.drift:
        return None
    best = next((e for e in explanations if e.cause != "none"), None)
    if best is None:
        return DriftSize("unexplained", 0.0, 0.0, False, True)
    fits = explained(best, test)
    beyond = not fits or tolerance.exceeded_by(best.translation_mm, best.rotation_deg)
    return DriftSize(best.name, best.translation_mm, best.rotation_deg, fits, beyond)


def verdict_reason(test, size: DriftSize | None, tolerance: DriftTolerance) -> str:
    """The verdict's one line: the statistic, and the size against the tolerance."""
    statistic = (f"discrepancy chi2 {test.statistic:.1f} on {test.degrees} degrees of freedom, "
                 f"p = {test.p_value:.3g}")
    if size is None:
        return f"{statistic} (above the level {test.level:g}: within the noise)"
    detected = f"{statistic} (below the level {test.level:g}: beyond the noise)"
    if not size.explained:
        return (f"{detected}; no single explanation accounts for it (the closest: {size.text()}), so its size "
                f"cannot be held to the tolerance {tolerance.text()}")
    if size.beyond:
        return f"{detected}; {size.text()}, beyond the tolerance {tolerance.text()}"
    return f"{detected}, statistically detectable; {size.text()}, within the tolerance {tolerance.text()}: too small to act on"


@dataclass(frozen=True)
class ToolDifference:
    """How far the controller's camera tooldata is from SESSION's, against the tolerance.

    Attributes
    ----------
    translation_mm : float
        Distance between the two tframe origins, mm.
    rotation_deg : float
        Angle of the rotation between the two tframe orientations, deg (0..180).
    beyond : bool
        Larger than the tolerance in translation or rotation.
    """

    translation_mm: float
    rotation_deg: float
    beyond: bool

    def text(self) -> str:
        return f"{self.translation_mm:.3f} mm / {self.rotation_deg:.4f} deg"

    def to_json(self) -> dict:
        return {"translation_mm": round(self.translation_mm, 4), "rotation_deg": round(self.rotation_deg, 5),
                "beyond_tolerance": self.beyond}


def tool_difference(held, expected, tolerance: DriftTolerance) -> ToolDifference:
    """The difference between two tooldata (``position_mm`` (3,), ``quaternion_wxyz`` (4,), unit or not)
    against ``tolerance``."""
    from ...geometry import matrix_from_quaternion, rotation_error_deg  # noqa: PLC0415

    translation = float(np.linalg.norm(np.subtract(held.position_mm, expected.position_mm, dtype=float)))
    rotations = [matrix_from_quaternion(np.asarray(q, float) / np.linalg.norm(np.asarray(q, float)))
                 for q in (held.quaternion_wxyz, expected.quaternion_wxyz)]
    rotation = float(rotation_error_deg(*rotations))
    return ToolDifference(translation, rotation, tolerance.exceeded_by(translation, rotation))
