"""The quality words: every figure the operator reads about a calibration's data, defined once.

Whatever prints one of these words (the capture plan, the refusal of ``calibrate``, the verdict, the
text summary, the HTML report) computes it here, so one word is one number wherever it is read.

Relative rotations
------------------
Between two postures ``i < j`` the hand turns by ``A_ij = A_i^-1 A_j``, in the hand frame (``tool0``
eye-in-hand, ``base`` eye-to-hand). Its quaternion ``Q_A^ij = conj(Q_i) * Q_j`` (Algorithm 1, step
2), taken with ``w >= 0``, is ``(S_A, V_A) = (cos(a/2), sin(a/2) n)`` with ``a`` in [0, 180] deg
and ``n`` the unit rotation axis. ``AX = XB`` sees ``X`` only through these axes (eq. 30:
``S_A = S_B``, ``V_A = Q_X * V_B * conj(Q_X)``): it is blind about a direction no axis leans towards.

The words
---------
relative rotation angle (deg)
    ``a_ij = 2 acos(S_A)`` of every pair ``i < j`` (:func:`relative_rotation_angles_deg`). The verdict
    judges their median (``min_median_rotation_deg``); the capture plan reports the median and the
    smallest.
rotation-axis spread (deg)
    How far the rotation axes rise out of the plane they lie closest to
    (:func:`rotation_axis_spread`): ``asin(sqrt(l_min))``, ``l_min`` the smallest eigenvalue of the
    weighted axis scatter ``sum(|V_A|^2 n n^T) / sum(|V_A|^2)`` over the pairs turning at least
    :data:`MIN_AXIS_ANGLE_DEG` (weights ``|V_A|^2 = sin^2(a/2)``: small rotations count little). In
    words: the RMS sine of the axes' elevation out of that plane, as an angle. Its eigenvector is
    the least exercised direction. 0 deg: every axis in one plane (``X`` poorly determined about
    its normal); :data:`MAX_AXIS_SPREAD_DEG` (35.3 deg): axes spread evenly over the sphere. The
    verdict's ``min_rotation_axis_spread_deg`` and the capture plan's score are this figure.
rotation-axis divergence (deg)
    How far the rotation axes stray from one line (:func:`rotation_axis_divergence_deg`):
    ``asin(sqrt(1 - l_max))`` of the unweighted scatter ``mean(n n^T)`` of the axes of pairs turning
    at least :data:`MIN_AXIS_ANGLE_DEG`: the RMS sine of the axes' angle from their common direction,
    as an angle. 0 deg: all axes parallel, and ``AX = XB`` cannot determine ``X`` (refused below
    :data:`MIN_AXIS_DIVERGENCE_DEG` by ``solve.check_motion`` and the classic solvers); 54.7 deg at
    most. Every usable pair counts alike: any second axis does determine ``X`` on exact data.
rotation-axis coverage
    :class:`AxisCoverage`: the axes and angles, the spread and the least exercised direction, and the
    RMS rotation about each axis of the hand frame (the report's hemispheres and bars).
distance spread (mm)
    How far apart the nearest and the farthest view of the board are: ``max - min`` over the postures
    of the distance from the camera to the board's centre (the mean of its points in the camera
    frame; :func:`distance_spread_mm`). Point consistency likes the board near and far.
board position in the image
    Which cells of a 3 x 3 grid over the reference camera's image the board's corners have been seen
    in, over the postures (:func:`image_cells`, named by :data:`IMAGE_CELL_NAMES`: ``upper left`` ..
    ``lower right``): the board seen all over the image, not always in the middle.
d_org (mm)
    Eq. 22, the mean distance of a board point in the fixed frame from its mean position, over the
    postures the chosen result kept (its inliers), on every board point of the session (the board
    corners, or the three compact points when the session holds board poses only); the same postures
    and points for every method compared (:func:`result_d_org`). Over every posture, outliers
    included, it is :data:`D_ORG_ALL_NAME`.
posture residual (mm)
    Posture ``i``'s term of d_org, the same for every method (:func:`posture_residuals`): the mean
    distance of its board points, carried into the fixed frame through ``X`` (``A_i X p_ik``, eq. 13),
    from their mean positions over the postures the result kept (eq. 21-22). The points are d_org's:
    the board corners, or the three compact points when the session holds board poses only
    (:data:`RESIDUAL_POINTS`); an outlier's residual is its distance from the same mean, so it shows
    how far off it is. The mean of the kept postures' residuals is d_org. The verdict judges the
    largest kept one (``max_posture_residual_mm``); :func:`posture_residual_meaning` is the one text
    of it that the text summary, the HTML report and the JSON print. (The estimators judge outliers
    on figures of their own fit, e.g. the compact points against the fitted board: those are not
    this word and are not reported as it.)
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .invariants import bounded_pairs
from .metrics import d_org, fixed_points
from .metrics import posture_residuals as metrics_posture_residuals
from .problem import EYE_IN_HAND, HandEyeProblem
from ..geometry import canonical_quaternions, quaternion_conjugate, quaternion_from_matrix, quaternion_multiply

if TYPE_CHECKING:
    from .solve import CalibrationResult

__all__ = [
    "AXIS_SPREAD_NAME",
    "MEDIAN_ANGLE_NAME",
    "D_ORG_ALL_NAME",
    "METRIC_MEANINGS",
    "POSTURE_RESIDUAL_NAME",
    "RESIDUAL_POINTS",
    "posture_residuals",
    "posture_residual_meaning",
    "residual_points",
    "IMAGE_CELL_NAMES",
    "board_distances_mm",
    "distance_spread_mm",
    "image_cells",
    "MAX_AXIS_SPREAD_DEG",
    "MIN_AXIS_ANGLE_DEG",
    "MIN_AXIS_DIVERGENCE_DEG",
    "AxisCoverage",
    "DOrg",
    "hand_frame",
    "hand_axis_coverage",
    "kept_postures",
    "relative_rotation_angles_deg",
    "relative_rotation_quaternions",
    "result_d_org",
    "rotation_axis_coverage",
    "rotation_axis_divergence_deg",
    "rotation_axis_spread",
    "usable_axes",
]

#: Relative rotations smaller than this have no usable axis (noise): left out of the axis words.
MIN_AXIS_ANGLE_DEG = 2.0
#: The largest rotation-axis spread (axes spread evenly over the sphere): asin(sqrt(1/3)), 35.26 deg.
MAX_AXIS_SPREAD_DEG = math.degrees(math.asin(math.sqrt(1.0 / 3.0)))
#: Below this rotation-axis divergence the axes count as parallel and ``X`` as undetermined.
MIN_AXIS_DIVERGENCE_DEG = 2.0
#: What the compact points of a session of board poses are.
_COMPACT_POINTS = "board centre and one point along each board axis, from the board poses"
#: The name of d_org over every posture, outliers included.
D_ORG_ALL_NAME = "d_org incl. outliers"
#: The name of a posture's term of d_org (see the module's words), for every method alike.
POSTURE_RESIDUAL_NAME = "posture residual"
#: What each figure of a solution means, in the words both presenters (text summary, HTML report) print.
METRIC_MEANINGS = {
    POSTURE_RESIDUAL_NAME: "mean distance of a posture's board points, carried into the fixed frame through X, from "
                           "their mean positions over the kept postures (its term of d_org, eq. 22)",
    "d_org": "mean distance of a board point from its mean position in the fixed frame (eq. 22)",
    D_ORG_ALL_NAME: "d_org over every posture, the outliers included",
    "d_back": "mean distance between the same board point seen from two postures (eq. 23)",
    "dR": "rotation residual of AX = XB, ||R_A R_X - R_X R_B||_F, RMS over posture pairs (eq. 16)",
    "dt": "translation residual of AX = XB, RMS over posture pairs (eq. 16)",
}
#: The names the operator reads for the two motion words, in the plan, guided capture and the verdict.
AXIS_SPREAD_NAME = "rotation-axis spread"
MEDIAN_ANGLE_NAME = "relative rotation angle (median)"


# ------------------------------------------------------------------------------ relative rotations
def relative_rotation_quaternions(hand: ArrayLike, pairs: ArrayLike | None = None) -> np.ndarray:
    """``Q_A^ij = conj(Q_i) * Q_j`` (Algorithm 1, step 2) of every pair ``i < j``, ``w >= 0``.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (only their rotations are used).
    pairs : array-like of int, shape (p, 2), optional
        Only these pairs (e.g. ``invariants.bounded_pairs`` of a large set); default every pair.

    Returns
    -------
    ndarray, shape (n(n-1)/2, 4) or (p, 4)
        Unit quaternions ``(w, x, y, z)``, pairs in lexicographic order (``np.triu_indices``).
    """
    q = quaternion_from_matrix(np.asarray(hand, float)[:, :3, :3])
    i, j = np.triu_indices(len(q), k=1) if pairs is None else np.asarray(pairs, dtype=int).reshape(-1, 2).T
    return canonical_quaternions(quaternion_multiply(quaternion_conjugate(q[i]), q[j]))


def relative_rotation_angles_deg(q_rel: ArrayLike) -> np.ndarray:
    """Relative rotation angles ``a = 2 acos(S_A)`` in [0, 180] deg.

    Parameters
    ----------
    q_rel : array-like, shape (p, 4)
        Relative rotations with ``w >= 0`` (:func:`relative_rotation_quaternions`).

    Returns
    -------
    ndarray, shape (p,)
    """
    return np.degrees(2.0 * np.arccos(np.clip(np.asarray(q_rel, float)[:, 0], -1.0, 1.0)))


def usable_axes(q_rel: ArrayLike) -> np.ndarray:
    """Unit rotation axes ``n`` of the pairs turning at least :data:`MIN_AXIS_ANGLE_DEG`.

    Parameters
    ----------
    q_rel : array-like, shape (p, 4)

    Returns
    -------
    ndarray, shape (k, 3)
    """
    q_rel = np.asarray(q_rel, float)
    vectors = q_rel[relative_rotation_angles_deg(q_rel) >= MIN_AXIS_ANGLE_DEG, 1:]
    return vectors / np.linalg.norm(vectors, axis=1, keepdims=True) if len(vectors) else np.zeros((0, 3))


# ------------------------------------------------------------------------------------ axis words
def rotation_axis_spread(q_rel: ArrayLike) -> tuple[float, np.ndarray]:
    """The rotation-axis spread (deg) and the least exercised direction (see the module's words).

    Parameters
    ----------
    q_rel : array-like, shape (p, 4)
        Relative rotations with ``w >= 0``; pairs below :data:`MIN_AXIS_ANGLE_DEG` are left out.

    Returns
    -------
    spread_deg : float
        ``asin(sqrt(l_min))`` of the ``sin^2(a/2)``-weighted scatter of the axes, in
        [0, :data:`MAX_AXIS_SPREAD_DEG`]; 0 when no pair turns enough.
    weakest_direction : ndarray, shape (3,)
        The scatter's eigenvector of ``l_min`` (the normal of the axes' best-fitting plane), sign
        chosen with its largest component > 0; ``(0, 0, 1)`` when no pair turns enough.
    """
    q_rel = np.asarray(q_rel, float)
    vectors = q_rel[relative_rotation_angles_deg(q_rel) >= MIN_AXIS_ANGLE_DEG, 1:]  # V_A = sin(a/2) n (eq. 30)
    weight = float(np.sum(vectors**2))
    if not weight > 0:
        return 0.0, np.array([0.0, 0.0, 1.0])
    scatter = vectors.T @ vectors / weight  # sum of sin^2(a/2) n n^T over the sum of sin^2(a/2)
    eigenvalues, eigenvectors = np.linalg.eigh(scatter)
    weakest = eigenvectors[:, 0]
    weakest = weakest * np.sign(weakest[np.argmax(np.abs(weakest))])
    return math.degrees(math.asin(math.sqrt(min(max(eigenvalues[0], 0.0), 1.0)))), weakest


def rotation_axis_divergence_deg(axes: ArrayLike) -> float:
    """The rotation-axis divergence (deg): how far unit axes stray from one line (sign-free).

    Parameters
    ----------
    axes : array-like, shape (k, 3)
        Unit rotation axes (:func:`usable_axes`); each counts alike.

    Returns
    -------
    float
        ``asin(sqrt(1 - l_max))`` of ``mean(n n^T)``: 0 when all axes are parallel (or none is
        given), at most 54.7 deg.
    """
    axes = np.asarray(axes, float)
    if not len(axes):
        return 0.0
    largest = np.linalg.eigvalsh(axes.T @ axes / len(axes))[-1]
    return float(np.degrees(np.arcsin(np.sqrt(np.clip(1.0 - largest, 0.0, 1.0)))))


@dataclass(frozen=True)
class AxisCoverage:
    """The rotation-axis coverage of a set of hand poses (all posture pairs; a bounded sample of them,
    ``invariants.bounded_pairs``, for a large set).

    Attributes
    ----------
    axes : ndarray, shape (k, 3)
        Unit rotation axes of the pairs turning at least :data:`MIN_AXIS_ANGLE_DEG`, in the hand frame.
    angles_deg : ndarray, shape (k,)
        Rotation angles of those pairs, in [0, 180].
    all_angles_deg : ndarray, shape (p,)
        The relative rotation angle of every pair (also those too small for an axis).
    spread_deg : float
        The rotation-axis spread (:func:`rotation_axis_spread`).
    weakest_direction : ndarray, shape (3,)
        The least exercised direction.
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
        """Median relative rotation angle over every pair (0 without pairs)."""
        return float(np.median(self.all_angles_deg)) if self.all_angles_deg.size else 0.0

    @property
    def min_angle_deg(self) -> float:
        """Smallest relative rotation angle over every pair (0 without pairs)."""
        return float(np.min(self.all_angles_deg)) if self.all_angles_deg.size else 0.0


def hand_frame(setup: str) -> str:
    """The frame the hand's rotation axes are expressed in: ``tool0`` eye-in-hand, else ``base``."""
    return "tool0" if setup == EYE_IN_HAND else "base"


def hand_axis_coverage(hand: np.ndarray, frame: str = "tool0") -> AxisCoverage:
    """:class:`AxisCoverage` of hand poses.

    Parameters
    ----------
    hand : array-like, shape (n, 4, 4)
        Hand poses ``A_i`` (``tool02base`` eye-in-hand).
    frame : str
        Name of the hand frame, for the labels.
    """
    # every pair up to ALL_PAIRS_UP_TO of them, else neighbours in time and random partners
    q = relative_rotation_quaternions(hand, bounded_pairs(len(hand))) if len(hand) else np.zeros((0, 4))
    angles = relative_rotation_angles_deg(q)
    vectors = q[:, 1:]
    rotvec_deg = angles[:, None] * vectors / np.maximum(np.linalg.norm(vectors, axis=1, keepdims=True), 1e-15)
    rms = np.sqrt(np.mean(rotvec_deg**2, axis=0)) if len(angles) else np.zeros(3)
    keep = angles >= MIN_AXIS_ANGLE_DEG
    spread, weakest = rotation_axis_spread(q)
    return AxisCoverage(usable_axes(q), angles[keep], angles, spread, weakest, rms, frame)


def rotation_axis_coverage(problem: HandEyeProblem, kept: ArrayLike | None = None) -> AxisCoverage:
    """:class:`AxisCoverage` of a problem's hand motions, over the postures ``kept`` (all by default).

    Parameters
    ----------
    problem : HandEyeProblem
    kept : array-like of bool, shape (n,), optional
        The postures to include (e.g. :func:`kept_postures` of a result).
    """
    hand = problem.hand if kept is None else problem.hand[np.asarray(kept, bool)]
    return hand_axis_coverage(hand, hand_frame(problem.setup))


# ------------------------------------------------------------------------------- where the board was
#: The cells of the 3 x 3 image grid, by row (top first) and column (left first).
IMAGE_CELL_NAMES = (("upper left", "upper middle", "upper right"), ("middle left", "centre", "middle right"),
                    ("lower left", "lower middle", "lower right"))


def board_distances_mm(points_cam: ArrayLike) -> np.ndarray:
    """Camera-to-board-centre distance of each posture, mm.

    Parameters
    ----------
    points_cam : array-like, shape (n, m, 3)
        The board's points in the camera frame, per posture.

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.linalg.norm(np.asarray(points_cam, float).mean(axis=1), axis=1)


def distance_spread_mm(distances_mm: ArrayLike) -> float:
    """The distance spread: ``max - min`` of the camera-to-board distances (0 for fewer than two)."""
    d = np.asarray(distances_mm, float)
    return float(d.max() - d.min()) if d.size >= 2 else 0.0


def image_cells(points_px: ArrayLike, width: int, height: int) -> set:
    """The cells ``(row, col)`` of the 3 x 3 image grid that image points fall in (points outside the
    image or behind the camera count for none).

    Parameters
    ----------
    points_px : array-like, shape (m, 2)
        Board corners in the reference camera's image (u right, v down), of one posture or many.
    width, height : int
        Image size in pixels.
    """
    uv = np.asarray(points_px, float).reshape(-1, 2)
    uv = uv[np.all(np.isfinite(uv), axis=1) & (uv[:, 0] >= 0) & (uv[:, 0] < width) & (uv[:, 1] >= 0) & (uv[:, 1] < height)]
    cols = np.clip((uv[:, 0] * 3 // width).astype(int), 0, 2)
    rows = np.clip((uv[:, 1] * 3 // height).astype(int), 0, 2)
    return {(int(r), int(c)) for r, c in zip(rows, cols)}


# ------------------------------------------------------------------------------------------ d_org
def kept_postures(problem: HandEyeProblem, result: CalibrationResult) -> np.ndarray:
    """Boolean mask ``(n,)`` of the postures ``result`` kept (all but its outliers)."""
    outliers = {int(i) for i in result.outliers}
    return np.array([int(i) not in outliers for i in problem.posture_ids], dtype=bool)


@dataclass(frozen=True)
class DOrg:
    """``d_org`` of a result (see :func:`result_d_org`).

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
                  f"{self.points_per_posture} compact points per posture ({_COMPACT_POINTS})")
        return f"{postures}, {points}"


def result_d_org(problem: HandEyeProblem, result: CalibrationResult, x: ArrayLike | None = None) -> DOrg:
    """THE d_org: eq. 22 over the postures ``result`` kept, on every board point of the session.

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
    fixed = fixed_points(problem.hand, x, problem.points_cam)  # eq. 13: board points in the fixed frame
    n_kept = int(kept.sum())
    value = d_org(fixed[kept]) if n_kept >= 1 else float("nan")  # eq. 22
    left_out = problem.n - n_kept
    return DOrg(value, d_org(fixed) if left_out else None, n_kept, left_out, int(problem.points_cam.shape[1]),
                residual_points(problem) == "corners")


# ------------------------------------------------------------------------------- posture residual
#: The points a posture residual (and d_org) is measured on, by ``CalibrationResult.residuals_on``.
RESIDUAL_POINTS = {"corners": "the board corners", "compact": f"the three compact points ({_COMPACT_POINTS})"}


def residual_points(problem: HandEyeProblem) -> str:
    """The key of :data:`RESIDUAL_POINTS` of a problem's points: ``corners`` when it holds the measured
    board corners, ``compact`` when it holds board poses only (three points per posture)."""
    return "corners" if problem.points_cam.shape[1] > 3 else "compact"


def posture_residuals(problem: HandEyeProblem, x: ArrayLike, kept: np.ndarray | None = None) -> np.ndarray:
    """THE posture residual of every posture, for any method's ``X`` (see the module's words).

    Parameters
    ----------
    problem : HandEyeProblem
    x : array-like, shape (4, 4)
        The solution.
    kept : array-like of bool, shape (n,), optional
        The postures the result kept (:func:`kept_postures`); all by default. Their mean board points
        are the reference for every posture, outliers included.

    Returns
    -------
    ndarray, shape (n,)
        mm; its mean over ``kept`` is :func:`result_d_org`'s ``mm``.
    """
    fixed = fixed_points(problem.hand, np.asarray(x, float), problem.points_cam)  # eq. 13, (n, m, 3)
    return metrics_posture_residuals(fixed, kept)  # eq. 21-22 per posture


def posture_residual_meaning(points: str) -> str:
    """The one text of what a result's posture residuals are: ``points`` a key of :data:`RESIDUAL_POINTS`
    (``CalibrationResult.residuals_on``)."""
    return (f"{POSTURE_RESIDUAL_NAME}: {METRIC_MEANINGS[POSTURE_RESIDUAL_NAME]}, on "
            f"{RESIDUAL_POINTS.get(points, points)}")
