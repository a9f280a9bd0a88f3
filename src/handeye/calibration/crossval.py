"""Posture-level cross-validation: how well a calibration predicts the board at postures it has not seen.

The postures are split into ``k`` folds (posture ``i`` in fold ``i mod k``, so each fold samples
the whole capture). For every fold, ``X`` is solved from the other folds and the held-out postures'
board points are carried into the frame the board is fixed in; the prediction error of a posture
is the mean distance of its points from where the training postures put them, the mean point of
eq. 21 over the training postures (a held-out d_org, eq. 22). The board points are the board's
corners as fitted at each posture (the board pose ``target2cam`` applied to the board grid), or the
three compact points of sessions that hold board poses: a single corner's detection noise is a
property of one measurement (reported with the noise levels), not of the calibration. The same
definition serves every method, so their figures compare.

Random noise makes this error about as large as the noise model predicts (the posture's own noise
plus the uncertainty of ``X`` and of the mean point). Errors that depend on the posture -- a robot
whose kinematics differ from the nominal model, a camera bracket that bends or slips, a wrong
stereo scale -- are not averaged away by more postures and make it larger: the ratio of the two is
the honest check of a calibration's accuracy figure.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .metrics import fixed_points

if TYPE_CHECKING:
    from collections.abc import Callable
    from .problem import HandEyeProblem

__all__ = [
    "DEFAULT_FOLDS",
    "SYSTEMATIC_RATIO",
    "SYSTEMATIC_ADVICE",
    "CrossValidation",
    "fold_assignment",
    "board_points",
    "held_out_errors",
    "cross_validate",
]

DEFAULT_FOLDS = 5
#: Observed / predicted RMS above which the error is called systematic.
SYSTEMATIC_RATIO = 1.5
SYSTEMATIC_ADVICE = (
    "held-out postures are predicted worse than the measurement noise explains: the error depends on the posture "
    "and is systematic, not random. Usual causes: robot kinematics differing from the nominal model (link lengths, "
    "joint offsets, gravity sag: calibrate the robot or use postures closer together), a camera bracket that bends "
    "or slips between postures (tighten or stiffen it), or a stereo calibration with the wrong scale or baseline "
    "(recalibrate the head). The one-sigma values of the camera pose cover random errors only")


@dataclass(frozen=True)
class CrossValidation:
    """Held-out prediction errors of one method on one data set.

    Attributes
    ----------
    folds : int
    errors_mm : ndarray, shape (n,)
        Per posture (in posture order): mean distance of its points from their predicted places.
        NaN for postures not held out (outliers of the method, when excluded).
    points : str
        ``corners`` (the fitted board corners) or ``compact`` (three board points).
    predicted_rms_mm : float or None
        What the method's noise model expects for the RMS point error (``None`` without a model).
    """

    folds: int
    errors_mm: np.ndarray
    points: str
    rms_sq_mm2: np.ndarray
    predicted_rms_mm: float | None = None

    @property
    def mean_mm(self) -> float:
        return float(np.nanmean(self.errors_mm))

    @property
    def rms_mm(self) -> float:
        """RMS distance of a held-out point from its predicted place (over points and postures)."""
        return float(np.sqrt(np.nanmean(self.rms_sq_mm2)))

    @property
    def ratio(self) -> float | None:
        if not self.predicted_rms_mm:
            return None
        return self.rms_mm / self.predicted_rms_mm

    @property
    def systematic(self) -> bool:
        ratio = self.ratio
        return ratio is not None and ratio > SYSTEMATIC_RATIO

    def to_dict(self, posture_ids: Iterable[int] | None = None) -> dict:
        """The ``cross_validation`` mapping of the result JSON."""
        ids = range(len(self.errors_mm)) if posture_ids is None else posture_ids
        out = {
            "folds": int(self.folds),
            "points": self.points,
            "mean_mm": round(self.mean_mm, 6),
            "rms_mm": round(self.rms_mm, 6),
            "per_posture_mm": {str(int(i)): round(float(e), 6) for i, e in zip(ids, self.errors_mm) if np.isfinite(e)},
            "definition": "each posture held out in turn (k folds): mean distance of its fitted board points, carried "
                          "by the flange pose and X into the fixed frame, from the mean of the training postures' points "
                          "(eq. 21-22 out of sample)",
        }
        ratio = self.ratio
        if self.predicted_rms_mm is not None:
            out["predicted_rms_mm"] = round(float(self.predicted_rms_mm), 6)
        if ratio is not None:
            out["ratio"] = round(float(ratio), 4)
            out["systematic"] = bool(self.systematic)
            if self.systematic:
                out["advice"] = SYSTEMATIC_ADVICE
        return out


def fold_assignment(n: int, folds: int = DEFAULT_FOLDS) -> np.ndarray:
    """Fold of each posture, ``i mod k`` with ``k = min(folds, n)``; shape ``(n,)``."""
    return np.arange(n) % max(1, min(folds, n))


def held_out_errors(hand: np.ndarray, x: np.ndarray, points_cam: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per posture: mean and mean-square distance of ``hand_i X points_i`` from ``reference``.

    Parameters
    ----------
    hand : ndarray, shape (h, 4, 4)
    x : ndarray, shape (4, 4)
    points_cam : ndarray, shape (h, m, 3)
    reference : ndarray, shape (m, 3)
        Predicted fixed-frame places of the points.

    Returns
    -------
    mean_mm, mean_sq_mm2 : ndarray, shape (h,)
    """
    dist = np.linalg.norm(fixed_points(hand, x, points_cam) - reference[None], axis=-1)
    return dist.mean(axis=1), (dist**2).mean(axis=1)


def board_points(problem: HandEyeProblem) -> np.ndarray:
    """The fitted board points of every posture in the camera frame, ``(n, m, 3)``.

    The board grid (``problem.target_points``) under the fitted pose ``target2cam`` when the
    session holds corners, else the three compact points.
    """
    model = problem.target_points
    if model is not None and problem.points_cam.shape[1] == len(model) and len(model) > 3:
        pose = problem.target2cam
        return np.einsum("nij,mj->nmi", pose[:, :3, :3], model) + pose[:, None, :3, 3]
    return problem.compact.points


def cross_validate(problem: HandEyeProblem, solver: Callable[[HandEyeProblem], np.ndarray], folds: int = DEFAULT_FOLDS, keep: ArrayLike | None = None) -> CrossValidation:
    """k-fold posture cross-validation of any solver.

    Parameters
    ----------
    problem : HandEyeProblem
    solver : callable
        ``solver(training_problem) -> X (4, 4)``; may raise (the fold then counts as NaN).
    folds : int
    keep : array-like of bool, shape (n,), optional
        Postures taking part (training and held out); the others get NaN.
    """
    n = problem.n
    keep = np.ones(n, bool) if keep is None else np.asarray(keep, bool)
    pts = board_points(problem)
    kind = "corners" if pts.shape[1] > 3 else "compact"
    index = np.flatnonzero(keep)
    fold = np.full(n, -1)
    fold[index] = fold_assignment(len(index), folds)
    k = int(fold.max()) + 1 if len(index) else 0
    mean = np.full(n, np.nan)
    mean_sq = np.full(n, np.nan)
    for f in range(k):
        train = keep & (fold != f)
        test = fold == f
        try:
            x = solver(problem.subset(train))
        except Exception:  # noqa: BLE001 - a solver failing on a fold leaves its postures unscored
            continue
        if not np.all(np.isfinite(x)):
            continue
        reference = fixed_points(problem.hand[train], x, pts[train]).mean(axis=0)
        mean[test], mean_sq[test] = held_out_errors(problem.hand[test], x, pts[test], reference)
    return CrossValidation(k, mean, kind, mean_sq)
