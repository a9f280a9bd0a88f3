"""Refuse a session whose poses no rigid camera mount can explain, before any solver answers.

A solver returns *a* pose for any input; when the robot poses are the base in the flange, the board
poses the camera in the board, the set-up is the other one or a rotation convention is wrong, that
pose is confidently wrong. The X-free invariants of ``AX = XB`` (``invariants``) tell, without
``X``, whether any rigid mount fits the whole set:

- the rotation angles of the relative motions of robot and board agree (median gap);
- one rotation carries every board rotation axis onto the robot's (median axis misfit);
- one translation then fits (median translation misfit, as a fraction of the motions).

Medians over all posture pairs: a few outlier postures (the robust solver removes them) leave them
small; only a set that is inconsistent as a whole is refused. A few GROSS postures (robot and camera
poses swapped, one posture's quaternions in another order, a posture of another station) can still
throw the linear fit behind the medians; :func:`consistent_majority` then names them from two X-free
per-posture figures (the median, over its pairs, of the rotation-angle gap and of the screw-pitch
gap, ``invariants``) with the robust median/MAD rule of the outlier step, never more than a
minority, and leaves them out when the rest passes. Otherwise the whole set's diagnosis stands. Real sets and noisy synthetic ones
(up to 20 mm of camera noise, the paper's worst) stay far below the limits; a wrong direction or
set-up gives axis misfits of 15-40 deg and translation misfits of 40-150 %.

Two readings fit the invariants exactly as well as the right one (inverting both pose sets; or
inverting the board poses together with the other set-up): they swap the camera mount with the
board's place. Physics tells them apart, and so does this check, only where it is clear:

- the object on the flange (the camera eye-in-hand, the board eye-to-hand) is not several times
  farther from the flange than the fixed object is from the base (over 500 mm and 2.5 times);
- the board is not behind the camera (its median direction over 120 deg from the optical axis +z,
  and not within 50 deg of +x, the forward axis of ROS body frames).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..base import CalibrationError
from .invariants import (MIN_MOTION_DEG, fit_hand_eye, pair_indices, posture_medians, relative_transforms,
                         screw_pitches)
from .refine import keep_majority, robust_outliers
from ..geometry import invert_transforms

__all__ = ["ConsistencyLimits", "InconsistentPosesError", "consistency_figures", "check_consistent", "posture_gaps",
           "consistent_majority"]


@dataclass(frozen=True)
class ConsistencyLimits:
    """When a whole set is inconsistent (defaults: real sets reach 1.2 deg, 2.6 deg and 6 %).

    Attributes
    ----------
    max_gap_deg : float
        Median angle gap above this: a rotation convention is wrong.
    min_axis_spread_deg : float
        Below this spread of the robot's rotation axes (all about one axis, as ``solve.check_motion``
        measures it) ``X`` is not determined: the other checks are left to the motion check.
    axis_floor_deg, axis_noise_factor : float
        Axis misfit above ``max(axis_floor_deg, axis_noise_factor x gap)``: no rigid mount fits the
        rotations under the session's set-up.
    max_translation : float
        Translation misfit (fraction of the median motion) above this: no rigid mount fits the
        translations.
    min_translation_mm : float
        ... unless the misfit is also under this (tiny motions).
    mount_ratio, mount_min_mm : float
        The object on the flange farther than both ``mount_min_mm`` and ``mount_ratio`` times the
        fixed object's distance from the base: the pose sets look inverted.
    behind_deg, x_forward_deg : float
        The board's median direction in the camera frame farther than ``behind_deg`` from the
        optical axis +z, and not within ``x_forward_deg`` of +x (a ROS body frame's forward axis):
        the board is behind the camera.
    gross_gap_deg, gross_pitch_mm : float
        When the whole set fails, a posture whose median angle gap or screw-pitch gap to the others
        stands out (robust z-score, ``refine.robust_outliers``) and exceeds this floor is a gross
        posture (real sets and 20 mm of camera noise: under 1.5 deg and 13 mm).
    """

    max_gap_deg: float = 5.0
    min_axis_spread_deg: float = 2.0
    axis_floor_deg: float = 8.0
    axis_noise_factor: float = 6.0
    max_translation: float = 0.3
    min_translation_mm: float = 5.0
    mount_ratio: float = 2.5
    mount_min_mm: float = 500.0
    behind_deg: float = 120.0
    x_forward_deg: float = 50.0
    gross_gap_deg: float = 2.0
    gross_pitch_mm: float = 10.0


class InconsistentPosesError(CalibrationError):
    """The session's robot and board poses fit no rigid camera mount."""


_PAIRS = 2000


def consistency_figures(hand: np.ndarray, target2cam: np.ndarray) -> dict:
    """The invariant misfits under the session's set-up and with the hand poses inverted (the other
    set-up, or robot poses stored the other way round).

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
        The frame-neutral hand poses (``problem.hand``) and board poses, mm.

    Returns
    -------
    dict
        ``axis_spread_deg`` (how far the robot's rotation axes stray from one line), ``gap_deg``, ``axis_deg``, ``translation``, ``translation_mm``, ``other_axis_deg``,
        ``other_translation`` (NaN where no pair rotates enough); ``x_mm`` and ``g_mm``, the distances
        of the fitted ``X`` and ``G`` (camera from flange and board from base eye-in-hand, camera from
        base and board from flange eye-to-hand); ``board_from_z_deg``, ``board_from_x_deg``, the
        board's median direction in the camera frame.
    """
    pairs = pair_indices(len(hand), _PAIRS)
    fit = fit_hand_eye(hand, target2cam, pairs)
    other = fit_hand_eye(invert_transforms(np.asarray(hand, float)), target2cam, pairs)
    rel = invert_transforms(np.asarray(hand, float)[pairs[:, 0]]) @ np.asarray(hand, float)[pairs[:, 1]]
    vectors = Rotation.from_matrix(rel[:, :3, :3]).as_rotvec()
    norms = np.linalg.norm(vectors, axis=1)
    axes = vectors[norms > np.radians(MIN_MOTION_DEG)] / norms[norms > np.radians(MIN_MOTION_DEG), None]
    spread = float("nan")
    if len(axes):
        largest = np.linalg.eigvalsh(axes.T @ axes / len(axes))[-1]
        spread = float(np.degrees(np.arcsin(np.sqrt(max(1.0 - largest, 0.0)))))
    t = np.asarray(target2cam, float)[:, :3, 3]
    direction = np.median(t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12), axis=0)
    direction = direction / max(np.linalg.norm(direction), 1e-12)
    return {"axis_spread_deg": spread, "gap_deg": fit.angle_gap_deg, "axis_deg": fit.axis_deg, "translation": fit.translation_ratio,
            "translation_mm": fit.translation, "other_axis_deg": other.axis_deg,
            "other_translation": other.translation_ratio, "x_mm": float(np.linalg.norm(fit.x[:3, 3])),
            "g_mm": float(np.linalg.norm(fit.g[:3, 3])),
            "board_from_z_deg": float(np.degrees(np.arccos(np.clip(direction[2], -1, 1)))),
            "board_from_x_deg": float(np.degrees(np.arccos(np.clip(direction[0], -1, 1))))}


def check_consistent(hand: np.ndarray, target2cam: np.ndarray, setup: str, limits: ConsistencyLimits = ConsistencyLimits()) -> None:
    """Refuse poses that no rigid camera mount fits, naming the likely cause.

    Raises
    ------
    InconsistentPosesError
        One line: the figures and what to do (re-import letting ``handeye import`` infer the
        conventions, or the flag to check).
    """
    if len(hand) < 3:
        return
    f = consistency_figures(hand, target2cam)
    fix = "re-import the log with handeye import (it infers the conventions) or check its flags"
    if np.isfinite(f["gap_deg"]) and f["gap_deg"] > limits.max_gap_deg:
        raise InconsistentPosesError(
            f"the robot and board poses fit no rigid camera mount: the relative rotations of robot and board differ by "
            f"a median {f['gap_deg']:.1f} deg where they must be equal; a rotation convention is wrong (Euler order, "
            f"degrees/radians, rotation vector read as angles); {fix} (--euler)")
    if not np.isfinite(f["axis_deg"]) or not f["axis_spread_deg"] >= limits.min_axis_spread_deg:
        return  # too little rotation, or about one axis only: X is not determined, check_motion refuses such data
    axis_limit = max(limits.axis_floor_deg, limits.axis_noise_factor * f["gap_deg"])
    if f["axis_deg"] > axis_limit:
        other_fits = np.isfinite(f["other_axis_deg"]) and f["other_axis_deg"] <= axis_limit and (
            f["other_translation"] <= limits.max_translation)
        other = "eye_to_hand" if setup == "eye_in_hand" else "eye_in_hand"
        if other_fits:
            cause = (f"they fit {other} (or the robot poses inverted: base in flange), {f['other_axis_deg']:.2f} deg; "
                     f"the set-up or a pose direction is wrong; {fix} (--setup, --robot-pose, --camera-pose)")
        else:
            cause = (f"the robot and board rotations are in different conventions or directions; {fix} "
                     f"(--euler, --quaternion-order, --robot-pose, --camera-pose)")
        raise InconsistentPosesError(
            f"the robot and board poses fit no rigid camera mount as {setup}: one rotation cannot carry the board's "
            f"rotation axes onto the robot's (median misfit {f['axis_deg']:.1f} deg); {cause}")
    if f["translation"] > limits.max_translation and f["translation_mm"] > limits.min_translation_mm:
        raise InconsistentPosesError(
            f"the robot and board poses fit no rigid camera mount as {setup}: the rotations fit but the translations do "
            f"not (median misfit {100 * f['translation']:.0f} % of the motion, {f['translation_mm']:.0f} mm); "
            f"quaternions read in the wrong order (wxyz/xyzw) on both sides, or positions and rotations from different "
            f"frames; {fix} (--quaternion-order, --euler)")
    flange_object, fixed_object = ("camera", "board") if setup == "eye_in_hand" else ("board", "camera")
    mount, fixed = (f["x_mm"], f["g_mm"]) if setup == "eye_in_hand" else (f["g_mm"], f["x_mm"])
    if mount > max(limits.mount_min_mm, limits.mount_ratio * fixed):
        raise InconsistentPosesError(
            f"the {flange_object} would be {mount:.0f} mm from the flange and the {fixed_object} "
            f"{fixed:.0f} mm from the base: both pose sets look inverted (robot base in flange and camera in "
            f"target), which fits the data exactly as well; {fix} (--robot-pose, --camera-pose)")
    if f["board_from_z_deg"] > limits.behind_deg and f["board_from_x_deg"] > limits.x_forward_deg:
        raise InconsistentPosesError(
            f"the board is behind the camera (its median direction {f['board_from_z_deg']:.0f} deg from the optical axis "
            f"+z): the board poses look inverted (camera in target), which with the other set-up fits the data exactly as "
            f"well; {fix} (--camera-pose, --setup)")


def posture_gaps(hand: ArrayLike, target2cam: ArrayLike, pairs: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two X-free figures per posture: how far its relative motions to the others break ``AX = XB``.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
        The frame-neutral hand poses and board poses, mm.
    pairs : array-like of int, shape (m, 2), optional
        Default: the pairs :func:`consistency_figures` uses.

    Returns
    -------
    angle_gap_deg, pitch_gap_mm : ndarray, shape (n,)
        Medians over the posture's pairs of ``|angle(A_ij) - angle(B_ij)|`` and of the screw-pitch
        gap ``|d(A_ij) - d(B_ij)|`` (pairs turning by ``MIN_MOTION_DEG`` .. 180 - ``MIN_MOTION_DEG``
        only; NaN for a posture without such a pair). Neither depends on ``X`` or on the set-up.
    """
    h, b = np.asarray(hand, float), np.asarray(target2cam, float)
    pairs = pair_indices(len(h), _PAIRS) if pairs is None else np.asarray(pairs, int)
    rel_a, rel_b = relative_transforms(h, b, pairs)
    angle_a, pitch_a = screw_pitches(rel_a)
    angle_b, pitch_b = screw_pitches(rel_b)
    usable = np.all([angle_a > MIN_MOTION_DEG, angle_a < 180.0 - MIN_MOTION_DEG,
                     angle_b > MIN_MOTION_DEG, angle_b < 180.0 - MIN_MOTION_DEG], axis=0)
    pitch_gap = np.where(usable, np.abs(pitch_a - pitch_b), np.nan)
    return posture_medians(np.abs(angle_a - angle_b), pairs, len(h)), posture_medians(pitch_gap, pairs, len(h))


def _gross_reason(gap: float, pitch: float, typical_gap: float, typical_pitch: float) -> str:
    pitch_text = (f"; screw-pitch gap {pitch:.0f} mm, typically {typical_pitch:.1f}"
                  if np.isfinite(pitch) and np.isfinite(typical_pitch) else "")
    return (f"its robot and board motions disagree with the other postures' (median rotation-angle gap {gap:.1f} deg, "
            f"typically {typical_gap:.2f}{pitch_text}): robot and camera poses swapped, another rotation convention "
            f"or a posture of another session; check its file")


def consistent_majority(hand: np.ndarray, target2cam: np.ndarray, setup: str, ids: Iterable[int] | None = None,
                        limits: ConsistencyLimits = ConsistencyLimits()) -> dict:
    """The gross postures to leave out so that the rest fits a rigid camera mount, with the reason.

    The whole set is checked first (:func:`check_consistent`): when it passes, nothing is left out
    (single outliers are the solver's outlier step's). When it fails, the postures whose
    :func:`posture_gaps` stand out (``refine.robust_outliers`` above the floors of ``limits``; never
    more than a minority, ``refine.keep_majority``) are left out if the rest then passes.

    Parameters
    ----------
    hand, target2cam : array-like, shape (n, 4, 4)
        The frame-neutral hand poses and board poses, mm.
    setup : str
    ids : sequence of int, optional
        Posture indices as written in the session (default 0..n-1).

    Returns
    -------
    dict
        ``{posture index: reason}`` of the postures left out (empty when the whole set is consistent).

    Raises
    ------
    InconsistentPosesError
        With the whole set's diagnosis (:func:`check_consistent`) when no consistent majority exists.
    """
    try:
        check_consistent(hand, target2cam, setup, limits)
        return {}
    except InconsistentPosesError as whole:
        refusal = whole
    h, b = np.asarray(hand, float), np.asarray(target2cam, float)
    ids = list(range(len(h))) if ids is None else [int(i) for i in ids]
    gap, pitch = posture_gaps(h, b)
    pitch_known = np.isfinite(pitch)
    gross = robust_outliers(gap, limits.gross_gap_deg)
    if pitch_known.sum() >= 3:
        gross[pitch_known] |= robust_outliers(pitch[pitch_known], limits.gross_pitch_mm)
    gross = keep_majority(gross)
    if not gross.any():
        raise refusal
    try:
        check_consistent(h[~gross], b[~gross], setup, limits)
    except InconsistentPosesError:
        raise refusal from None
    kept_pitch = pitch[~gross & pitch_known]
    typical_gap, typical_pitch = float(np.median(gap[~gross])), float(np.median(kept_pitch)) if kept_pitch.size else np.nan
    return {ids[k]: _gross_reason(gap[k], pitch[k], typical_gap, typical_pitch) for k in np.flatnonzero(gross)}
