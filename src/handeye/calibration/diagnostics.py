"""Oddities of real hand-eye data, found before solving: one finding, one line.

Every check here uses only robot poses ``tool0_in_base`` and board poses ``target_in_camera`` (mm),
so it runs on any session, imported or captured, before any solver. The checks rest on quantities
that do not depend on the unknown ``X``:

- **Rotation angle of relative motions.** With ``A_ij = A_i^-1 A_j`` (hand) and ``B_ij = B_i B_j^-1``
  (board in camera), ``A_ij = X B_ij X^-1`` (AX = XB), so ``A_ij`` and ``B_ij`` rotate by the same
  angle whatever ``X`` is. ``gap_ij = |angle(A_ij) - angle(B_ij)|`` measures how well postures ``i``
  and ``j`` agree with each other; a posture whose median gap stands out is inconsistent with the
  rest (a gross outlier), and when turning its board pose by 180 deg about the board normal closes
  the gap, the board's orientation was read the wrong way round (ambiguous board).
- **Screw pitch** ``d = n . t`` (translation along the rotation axis) of ``A_ij`` and ``B_ij`` agree
  for the same reason, so their ratio measures the scale between robot and camera lengths: ~1 when
  both are in mm, ~1000 when one of them was written in metres.
- **Set-up.** The angle and the pitch of ``A_ij`` are the SAME under both set-ups (``T_i^-1 T_j`` is
  conjugate to the inverse of ``T_i T_j^-1``), so they cannot tell eye-in-hand from eye-to-hand. The
  rotation axes can: under the right set-up one rotation ``R_X`` carries every axis of ``B_ij`` onto
  the axis of ``A_ij``. :func:`setup_rotation_residuals` fits ``R_X`` (least squares on rotation
  vectors, Park-Martin style) under each set-up and returns the median residual angle; the wrong
  set-up leaves residuals of tens of degrees. Inverted board poses (camera in target instead of
  target in camera) under one set-up fit exactly like correct poses under the other (the two
  unknowns, camera mount and board placement, swap roles), so that is one finding, not two.

- **Translations.** A quick linear fit of ``AX = XB`` (rotation from the axes, translation by least
  squares) must leave translation residuals small against the motions; quaternions read in the
  wrong order on BOTH sides keep every rotation check happy and only fail here.

Plain magnitude checks complete the list: duplicated robot poses, repeated (stale) board poses,
translations whose size does not fit millimetres.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import warnings
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import KDTree
from scipy.spatial.transform import Rotation

from ..base import brief
from .invariants import bounded_pairs, posture_medians as posture_median_gaps, relative_transforms
from .problem import EYE_IN_HAND, EYE_TO_HAND, SETUPS, hand_poses
from ..geometry import rotation_error_deg

if TYPE_CHECKING:
    from .session import Session

__all__ = [
    "Finding",
    "DiagnosticLimits",
    "relative_angle_gaps",
    "posture_angle_gaps",
    "pair_angle_gaps",
    "posture_median_gaps",
    "screw_pitch_scale",
    "setup_rotation_residuals",
    "hand_eye_fit",
    "find_duplicates",
    "find_unit_problems",
    "find_inconsistent_postures",
    "find_setup_mismatch",
    "find_model_mismatch",
    "diagnose",
    "diagnose_session",
]


@dataclass(frozen=True)
class Finding:
    """One oddity found in the data.

    Attributes
    ----------
    kind : str
        ``duplicate_posture``, ``stale_target``, ``units``, ``flipped_target``, ``inconsistent_posture``,
        ``rotation_convention``, ``setup`` or ``model_mismatch``.
    message : str
        One line for the operator: what was found and what to do.
    postures : tuple of int
        Posture indices concerned (as written in the session).
    values : dict
        The figures behind the finding (for programs).
    """

    kind: str
    message: str
    postures: tuple = ()
    values: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class DiagnosticLimits:
    """Thresholds of the checks (defaults chosen on the real data sets of the project).

    Attributes
    ----------
    duplicate_mm, duplicate_deg : float
        Two robot (or board) poses closer than both are "the same pose".
    gap_floor_deg : float
        A posture's median angle gap below this is never suspect.
    gap_factor : float
        A posture is suspect when its median gap exceeds ``gap_factor`` times the typical (median) one.
    min_motion_deg : float
        Relative motions smaller than this (or closer than this to 180 deg) are left out of the axis
        fit and the pitch ratio: their axes are undefined or ambiguous.
    setup_ratio : float
        The other set-up is reported when the declared one's residual is this many times larger.
    convention_gap_deg : float
        When the typical median gap exceeds this, most postures disagree: a rotation convention
        (quaternion order, Euler order, radians/degrees) is wrong rather than single postures.
    scale_factor : float
        Robot/camera length ratios beyond ``1/scale_factor .. scale_factor`` are reported.
    translation_ratio : float
        The translations do not fit when the median translation residual of ``AX = XB`` exceeds
        this fraction of the median robot motion (real sets: 0.016-0.06; wrong quaternion order: ~1).
    """

    duplicate_mm: float = 0.5
    duplicate_deg: float = 0.1
    gap_floor_deg: float = 1.0
    gap_factor: float = 3.0
    min_motion_deg: float = 3.0
    setup_ratio: float = 3.0
    convention_gap_deg: float = 5.0
    scale_factor: float = 10.0
    translation_ratio: float = 0.25


def _check_poses(tool0_in_base, target_in_camera) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(tool0_in_base, dtype=float)
    b = np.asarray(target_in_camera, dtype=float)
    if a.ndim != 3 or a.shape[1:] != (4, 4) or b.shape != a.shape:
        raise ValueError(f"expected two (n, 4, 4) pose arrays of equal length; got {a.shape} and {b.shape}")
    return a, b


def relative_angle_gaps(tool0_in_base: np.ndarray, target_in_camera: np.ndarray) -> np.ndarray:
    """``|angle(A_ij) - angle(B_ij)|`` in degrees for every pair of postures.

    The angle of ``A_ij`` is the same for both set-ups, so no set-up is needed.

    Parameters
    ----------
    tool0_in_base, target_in_camera : array-like, shape (n, 4, 4)

    Returns
    -------
    ndarray, shape (n, n)
        Symmetric; NaN on the diagonal.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    ra, rb = a[:, :3, :3], b[:, :3, :3]
    angle_a = rotation_error_deg(ra[:, None], ra[None, :])  # angle of R_i^T R_j
    angle_b = rotation_error_deg(rb[:, None], rb[None, :])  # = angle of R_i R_j^T (conjugate)
    gaps = np.abs(angle_a - angle_b)
    np.fill_diagonal(gaps, np.nan)
    return gaps


def posture_angle_gaps(gaps: ArrayLike) -> np.ndarray:
    """Median over ``j != i`` of a gap matrix ``(n, n)``; returns ``(n,)`` degrees."""
    return np.nanmedian(np.asarray(gaps, dtype=float), axis=1)


def pair_angle_gaps(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, pairs: ArrayLike) -> np.ndarray:
    """``|angle(A_ij) - angle(B_ij)|`` in degrees for the given pairs (as :func:`relative_angle_gaps`).

    Parameters
    ----------
    tool0_in_base, target_in_camera : array-like, shape (n, 4, 4)
    pairs : array-like of int, shape (m, 2)

    Returns
    -------
    ndarray, shape (m,)
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    i, j = np.asarray(pairs, dtype=int).reshape(-1, 2).T
    return np.abs(rotation_error_deg(a[i, :3, :3], a[j, :3, :3]) - rotation_error_deg(b[i, :3, :3], b[j, :3, :3]))


def _usable(rotvec_a, rotvec_b, limits: DiagnosticLimits) -> np.ndarray:
    lo, hi = np.radians(limits.min_motion_deg), np.radians(180.0 - limits.min_motion_deg)
    na, nb = np.linalg.norm(rotvec_a, axis=1), np.linalg.norm(rotvec_b, axis=1)
    return (na > lo) & (na < hi) & (nb > lo) & (nb < hi)


def _align(target_vectors, source_vectors) -> np.ndarray:
    """Rotation carrying ``source_vectors`` onto ``target_vectors`` (least squares), quietly: with
    (nearly) parallel vectors scipy warns that the answer is not unique, which the residuals show."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Rotation.align_vectors(target_vectors, source_vectors)[0].as_matrix()


def screw_pitch_scale(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, limits: DiagnosticLimits = DiagnosticLimits()) -> float | None:
    """Length ratio robot / camera from the screw pitches of the relative motions.

    ``d = n . t`` of ``A_ij`` equals that of ``B_ij`` whatever ``X`` and whatever the set-up, when
    both are in the same unit; the least-squares ratio ``sum(d_A d_B) / sum(d_B^2)`` is therefore ~1
    for consistent data and ~1000 (or ~0.001) when one side is in metres and the other in mm.

    Returns
    -------
    float or None
        ``None`` when no pair has a usable rotation or every camera pitch is zero.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    if len(a) < 2:
        return None
    pairs = bounded_pairs(len(a))
    rel_a, rel_b = relative_transforms(a, b, pairs)  # eye-in-hand form; the pitch is set-up free
    va = Rotation.from_matrix(rel_a[:, :3, :3]).as_rotvec()
    vb = Rotation.from_matrix(rel_b[:, :3, :3]).as_rotvec()
    ok = _usable(va, vb, limits)
    if not np.any(ok):
        return None
    na = va[ok] / np.linalg.norm(va[ok], axis=1, keepdims=True)
    nb = vb[ok] / np.linalg.norm(vb[ok], axis=1, keepdims=True)
    d_a = np.einsum("ni,ni->n", na, rel_a[ok, :3, 3])
    d_b = np.einsum("ni,ni->n", nb, rel_b[ok, :3, 3])
    denominator = float(np.sum(d_b**2))
    if denominator <= 0 or not np.isfinite(denominator):
        return None
    return float(np.sum(d_a * d_b) / denominator)


def setup_rotation_residuals(tool0_in_base: np.ndarray, target_in_camera: np.ndarray,
                             limits: DiagnosticLimits = DiagnosticLimits()) -> dict:
    """Median rotation residual of ``A_ij R_X = R_X B_ij`` under each set-up, degrees.

    ``R_X`` is fitted per set-up as the rotation carrying the rotation vectors of ``B_ij`` onto those
    of ``A_ij`` (least squares, as Park and Martin 1994); the residual of a pair is the angle of
    ``(R_A R_X)^T R_X R_B``. Pairs whose rotation is under ``min_motion_deg`` or within it of 180 deg
    are left out (undefined or sign-ambiguous axes).

    Returns
    -------
    dict
        ``{"eye_in_hand": deg, "eye_to_hand": deg}``; NaN for a set-up when fewer than 2 pairs
        are usable.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    out = {}
    pairs = bounded_pairs(len(a))
    for setup in SETUPS:
        if len(pairs) < 2:
            out[setup] = float("nan")
            continue
        rel_a, rel_b = relative_transforms(hand_poses(a, setup), b, pairs)
        va = Rotation.from_matrix(rel_a[:, :3, :3]).as_rotvec()
        vb = Rotation.from_matrix(rel_b[:, :3, :3]).as_rotvec()
        ok = _usable(va, vb, limits)
        if ok.sum() < 2:
            out[setup] = float("nan")
            continue
        rx = _align(va[ok], vb[ok])
        residual = rotation_error_deg(rel_a[ok, :3, :3] @ rx, rx @ rel_b[ok, :3, :3])
        out[setup] = float(np.median(residual))
    return out


def hand_eye_fit(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, setup: str,
                 limits: DiagnosticLimits = DiagnosticLimits()) -> dict:
    """A quick linear fit of ``AX = XB`` under one set-up, and how well it fits.

    The rotation ``R_X`` as in :func:`setup_rotation_residuals`, then the translation by linear least
    squares over all usable pairs, ``(R_A - I) t_X = R_X t_B - t_A`` (the rotation-then-translation
    scheme of Tsai-Lenz and Park-Martin). Not a calibration: a yardstick for the checks.

    Returns
    -------
    dict
        ``rotation_deg``: median rotation residual; ``translation_mm``: median
        ``|R_A t_X + t_A - R_X t_B - t_X|``; ``motion_mm``: median ``|t_A|``; ``pairs``: usable pairs.
        Values are NaN when fewer than 2 pairs are usable.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    nan = {"rotation_deg": float("nan"), "translation_mm": float("nan"), "motion_mm": float("nan"), "pairs": 0}
    pairs = bounded_pairs(len(a))
    if len(pairs) < 2:
        return nan
    rel_a, rel_b = relative_transforms(hand_poses(a, setup), b, pairs)
    va = Rotation.from_matrix(rel_a[:, :3, :3]).as_rotvec()
    vb = Rotation.from_matrix(rel_b[:, :3, :3]).as_rotvec()
    ok = _usable(va, vb, limits)
    if ok.sum() < 2:
        return nan
    rel_a, rel_b = rel_a[ok], rel_b[ok]
    rx = _align(va[ok], vb[ok])
    lhs = (rel_a[:, :3, :3] - np.eye(3)).reshape(-1, 3)
    rhs = (rel_b[:, :3, 3] @ rx.T - rel_a[:, :3, 3]).reshape(-1)
    tx = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    residual = np.einsum("nij,j->ni", rel_a[:, :3, :3], tx) + rel_a[:, :3, 3] - rel_b[:, :3, 3] @ rx.T - tx
    return {
        "rotation_deg": float(np.median(rotation_error_deg(rel_a[:, :3, :3] @ rx, rx @ rel_b[:, :3, :3]))),
        "translation_mm": float(np.median(np.linalg.norm(residual, axis=1))),
        "motion_mm": float(np.median(np.linalg.norm(rel_a[:, :3, 3], axis=1))),
        "pairs": int(ok.sum()),
    }


def _close_pairs(a, b, distance_mm: float) -> np.ndarray:
    """Pairs ``(i, j)``, ``i < j``, lexicographic, whose robot positions or board positions are within
    ``distance_mm``: the only pairs that can be duplicates, found in ``O(n log n)`` (a k-d tree), not by
    comparing every pair."""
    found = [np.zeros((0, 2), dtype=np.intp)]
    for poses in (a, b):
        finite = np.flatnonzero(np.all(np.isfinite(poses[:, :3, 3]), axis=1))
        if len(finite) > 1:
            close = KDTree(poses[finite, :3, 3]).query_pairs(distance_mm, output_type="ndarray")
            found.append(np.sort(finite[close], axis=1).reshape(-1, 2))
    pairs = np.concatenate(found)
    key = np.sort(pairs[:, 0].astype(np.int64) * len(a) + pairs[:, 1])
    key = key[np.r_[True, key[1:] != key[:-1]]] if len(key) else key
    return np.stack([key // len(a), key % len(a)], axis=1).astype(np.intp)


def _ids(ids, n):
    return [int(v) for v in (range(n) if ids is None else ids)]


def _groups(i, j, linked, n: int) -> list:
    """The groups of postures joined by the pairs ``(i[k], j[k])`` where ``linked[k]``, each a sorted list of
    positions (the connected components of those pairs with at least two members), by first member."""
    parent = list(range(n))

    def root(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for k in np.flatnonzero(linked):
        parent[root(int(j[k]))] = root(int(i[k]))
    members = {}
    for k in range(n):
        members.setdefault(root(k), []).append(k)
    return sorted((m for m in members.values() if len(m) > 1), key=lambda m: m[0])


def _names(ids) -> str:
    return ", ".join(str(v) for v in ids)


def _group_figures(group, i, j, figures) -> dict:
    """The largest of each figure over the pairs inside ``group`` (``figures``: name -> per-pair values)."""
    inside = np.isin(i, group) & np.isin(j, group)
    return {name: float(np.max(values[inside])) for name, values in figures.items()}


def _duplicate_finding(ids, f: dict, board_same: bool) -> Finding:
    """One finding for postures ``ids`` (positions' indices) that are the same robot pose."""
    board = ("the board pose too" if board_same else
             f"but the board poses differ by up to {f['board_mm']:.1f} mm, {f['board_deg']:.2f} deg (did the board or "
             f"camera move?)")
    if len(ids) == 2:
        head = f"postures {ids[0]} and {ids[1]}: the same robot pose ({f['robot_mm']:.2f} mm, {f['robot_deg']:.3f} deg apart)"
        tail = "a sample taken twice adds no motion; keep one"
    else:
        head = (f"postures {_names(ids[1:])} are the same robot pose as posture {ids[0]} (up to {f['robot_mm']:.2f} mm, "
                f"{f['robot_deg']:.3f} deg apart)")
        tail = f"a sample taken {len(ids)} times adds no motion; keep one"
    return Finding("duplicate_posture", f"{head}, {board}: {tail}", tuple(ids), f)


def _stale_finding(ids, f: dict, moved: dict) -> Finding:
    """One finding for postures ``ids`` that show the same board pose although the robot moved."""
    motion = f"{moved['robot_mm']:.1f} mm, {moved['robot_deg']:.2f} deg"
    if len(ids) == 2:
        message = (f"postures {ids[0]} and {ids[1]}: the same board pose ({f['board_mm']:.2f} mm, {f['board_deg']:.3f} "
                   f"deg apart) although the robot moved {motion}: a stale camera frame? drop posture {ids[1]} or "
                   f"re-measure it")
    else:
        message = (f"postures {_names(ids[1:])} show the same board pose as posture {ids[0]} (up to {f['board_mm']:.2f} "
                   f"mm, {f['board_deg']:.3f} deg apart) although the robot moved (at least {motion}): stale camera "
                   f"frames? drop postures {_names(ids[1:])} or re-measure them")
    return Finding("stale_target", message, tuple(ids), {**f, "robot_mm": moved["robot_mm"],
                                                           "robot_deg": moved["robot_deg"]})


def find_duplicates(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, ids: ArrayLike | None = None,
                    limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """Robot poses taken more than once, and board poses repeated while the robot moved (stale frames).

    One finding per group of equal poses (the postures joined by equal pairs), naming the group's
    first posture and the others: ``postures 3, 7, 12 are the same robot pose as posture 2``.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    ids = _ids(ids, len(a))
    findings = []
    if len(a) < 2:
        return findings
    pairs = _close_pairs(a, b, limits.duplicate_mm)
    i, j = pairs[:, 0], pairs[:, 1]
    figures = {"robot_mm": np.linalg.norm(a[i, :3, 3] - a[j, :3, 3], axis=1), "robot_deg": rotation_error_deg(a[i], a[j]),
               "board_mm": np.linalg.norm(b[i, :3, 3] - b[j, :3, 3], axis=1), "board_deg": rotation_error_deg(b[i], b[j])}
    same_a = (figures["robot_mm"] < limits.duplicate_mm) & (figures["robot_deg"] < limits.duplicate_deg)
    same_b = (figures["board_mm"] < limits.duplicate_mm) & (figures["board_deg"] < limits.duplicate_deg)
    for group in _groups(i, j, same_a, len(a)):
        inside = np.isin(i, group) & np.isin(j, group)
        findings.append(_duplicate_finding([ids[k] for k in group], _group_figures(group, i, j, figures),
                                           bool(np.all(same_b[inside]))))
    stale = same_b & ~same_a
    for group in _groups(i, j, stale, len(a)):
        inside = np.isin(i, group) & np.isin(j, group) & stale
        moved = {name: float(np.min(figures[name][inside])) for name in ("robot_mm", "robot_deg")}
        findings.append(_stale_finding([ids[k] for k in group], _group_figures(group, i, j, figures), moved))
    return findings


#: Plausible ranges (mm) of the median flange distance from the base and of the board distance
#: from the camera; outside them the values are probably in another unit.
_PLAUSIBLE_MM = {"robot": (20.0, 20000.0), "camera": (20.0, 20000.0)}


def find_unit_problems(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, ids: ArrayLike | None = None,
                       limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """Translations whose size does not fit millimetres, or robot and camera in different units.

    Three checks: the median flange distance from the base and the median board distance from the
    camera must be plausible in mm (20 mm .. 20 m); a single posture whose distance is 100x or more
    off the median is in another unit than the rest; the screw-pitch ratio robot/camera
    (:func:`screw_pitch_scale`) must be near 1.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    ids = _ids(ids, len(a))
    findings = []
    for name, poses, what in (("robot", a, "tool0_in_base (flange from base)"),
                              ("camera", b, "target_in_camera (board from camera)")):
        dist = np.linalg.norm(poses[:, :3, 3], axis=1)
        median = float(np.median(dist))
        lo, hi = _PLAUSIBLE_MM[name]
        if median < lo:
            findings.append(Finding(
                "units", f"{what}: median distance {median:.3g} mm is implausibly small: the values look like metres "
                         f"read as millimetres (import with --units m)", (), {"part": name, "median_mm": median}))
        elif median > hi:
            findings.append(Finding(
                "units", f"{what}: median distance {median:.4g} mm is implausibly large: the values look like "
                         f"millimetres read as metres (import with --units mm)", (), {"part": name, "median_mm": median}))
        if median > 0:
            ratio = dist / median
            for k in np.flatnonzero((ratio < 0.01) | (ratio > 100.0)):
                findings.append(Finding(
                    "units", f"posture {ids[k]}: {what} distance {dist[k]:.4g} mm against a median of {median:.4g} mm: "
                             f"this posture looks written in another unit than the others", (ids[k],),
                    {"part": name, "distance_mm": float(dist[k]), "median_mm": median}))
    scale = screw_pitch_scale(a, b, limits)
    if any(not f.postures for f in findings):
        return findings  # a side already implausible in mm: the pitch ratio would repeat it
    if scale is not None and scale > 0 and not (1.0 / limits.scale_factor < scale < limits.scale_factor):
        hint = ("the robot poses look like mm and the board poses like metres" if scale > 1
                else "the robot poses look like metres and the board poses like mm")
        findings.append(Finding(
            "units", f"robot and camera lengths disagree by a factor {scale:.4g} (screw pitches of the relative "
                     f"motions): {hint}; re-import with the right --units", (), {"pitch_ratio": scale}))
    return findings


def find_inconsistent_postures(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, ids: ArrayLike | None = None,
                               limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """Postures whose median angle gap stands out; says when a 180 deg board flip explains it.

    When the typical gap itself is large (over ``convention_gap_deg``) one ``rotation_convention``
    finding replaces the per-posture ones: the whole data set, not a posture, is at fault.

    A posture is suspect when its median gap exceeds ``max(gap_floor_deg, gap_factor x typical)``,
    typical = the median of all postures' median gaps. For a suspect posture the board pose is
    turned by 180 deg about the board normal (target z); when that brings its median gap under the
    threshold the finding is ``flipped_target``, otherwise ``inconsistent_posture``.
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    ids = _ids(ids, len(a))
    if len(a) < 4:
        return []
    pairs = bounded_pairs(len(a))  # every pair of a small session, neighbours and a sample of a large one
    per_posture = posture_median_gaps(pair_angle_gaps(a, b, pairs), pairs, len(a))
    typical = float(np.median(per_posture))
    if typical > limits.convention_gap_deg:
        return [Finding(
            "rotation_convention",
            f"robot and board relative rotations disagree for most postures (typical angle gap {typical:.1f} deg): "
            f"a rotation convention is wrong (quaternion order wxyz/xyzw, Euler order, degrees/radians); "
            f"check the import options", tuple(ids), {"typical_gap_deg": typical})]
    threshold = max(limits.gap_floor_deg, limits.gap_factor * typical)
    flip = np.diag([-1.0, -1.0, 1.0, 1.0])  # 180 deg about target z
    findings = []
    for k in np.flatnonzero(per_posture > threshold):
        flipped = b.copy()
        flipped[k] = b[k] @ flip
        mine = pairs[(pairs[:, 0] == k) | (pairs[:, 1] == k)]
        flipped_gap = float(posture_median_gaps(pair_angle_gaps(a, flipped, mine), mine, len(a))[k])
        values = {"median_gap_deg": float(per_posture[k]), "typical_gap_deg": typical,
                  "threshold_deg": threshold, "flipped_gap_deg": flipped_gap}
        if flipped_gap <= threshold:
            findings.append(Finding(
                "flipped_target",
                f"posture {ids[k]}: board pose looks flipped 180 deg about the board normal (median angle gap "
                f"{per_posture[k]:.2f} deg, {flipped_gap:.2f} deg once flipped, typical {typical:.2f} deg): "
                f"ambiguous board orientation; re-detect it or drop it", (ids[k],), values))
        else:
            findings.append(Finding(
                "inconsistent_posture",
                f"posture {ids[k]}: disagrees with the others (median angle gap |angle(A_ij) - angle(B_ij)| "
                f"{per_posture[k]:.2f} deg, typical {typical:.2f} deg): a gross outlier; check or drop it",
                (ids[k],), values))
    return findings


def find_setup_mismatch(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, setup: str,
                        limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """A finding when the data fit the other set-up clearly better than ``setup``.

    The rotation axes decide (:func:`setup_rotation_residuals`); the translations then confirm: when
    they fit the other set-up too, the finding is ``setup``; when they fit neither, the rotations of
    one side are read in another convention (a quaternion read xyzw for wxyz on one side only looks
    like the other set-up to the rotations) and the finding is ``rotation_convention``.
    """
    if setup not in SETUPS:
        raise ValueError(f"setup must be one of {', '.join(SETUPS)}; got {brief(setup)}")
    residuals = setup_rotation_residuals(tool0_in_base, target_in_camera, limits)
    other = EYE_TO_HAND if setup == EYE_IN_HAND else EYE_IN_HAND
    mine, theirs = residuals[setup], residuals[other]
    if not (np.isfinite(mine) and np.isfinite(theirs)):
        return []
    if not (mine > limits.setup_ratio * max(theirs, 0.05) and mine > limits.gap_floor_deg):
        return []
    values = {"declared": setup, "better": other, "residual_declared_deg": mine, "residual_other_deg": theirs}
    fit = hand_eye_fit(tool0_in_base, target_in_camera, other, limits)
    ratio = fit["translation_mm"] / fit["motion_mm"] if fit["motion_mm"] > 0 else float("nan")
    values.update({"translation_mm": fit["translation_mm"], "motion_mm": fit["motion_mm"]})
    if np.isfinite(ratio) and ratio > limits.translation_ratio:
        return [Finding(
            "rotation_convention",
            f"the rotations fit {other} better than the declared {setup} ({theirs:.2f} against {mine:.2f} deg) but the "
            f"translations fit neither (residual {fit['translation_mm']:.1f} mm for motions of {fit['motion_mm']:.1f} mm): "
            f"one side's rotations are in another convention (quaternion order wxyz/xyzw?)", (), values)]
    return [Finding(
        "setup",
        f"the data fit {other} much better than the declared {setup} (median rotation residual "
        f"{theirs:.2f} deg against {mine:.2f} deg): check --setup, or whether the board poses are inverted "
        f"(camera in target instead of target in camera), which looks the same", (), values)]


def find_model_mismatch(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, setup: str,
                        limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """A finding when the rotations fit ``AX = XB`` under ``setup`` but the translations do not.

    Reading both sides' quaternions in the wrong order (wxyz for xyzw) keeps every relative angle and
    even the set-up fit (the same wrong map on both sides amounts to another ``X``), so only the
    translations show it: their median residual becomes as large as the motion itself.
    """
    fit = hand_eye_fit(tool0_in_base, target_in_camera, setup, limits)
    if not np.isfinite(fit["translation_mm"]) or fit["motion_mm"] <= 0:
        return []
    ratio = fit["translation_mm"] / fit["motion_mm"]
    if ratio <= limits.translation_ratio:
        return []
    return [Finding(
        "model_mismatch",
        f"the rotations fit {setup} but the translations do not (median AX = XB translation residual "
        f"{fit['translation_mm']:.1f} mm for motions of {fit['motion_mm']:.1f} mm): quaternions read in the wrong "
        f"order (wxyz/xyzw) on both sides, or positions and rotations from different frames",
        (), {**fit, "ratio": ratio})]


def diagnose(tool0_in_base: np.ndarray, target_in_camera: np.ndarray, setup: str, ids: ArrayLike | None = None,
             limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """Every check on pose arrays (mm); a list of :class:`Finding` (empty when nothing is odd).

    Parameters
    ----------
    tool0_in_base, target_in_camera : array-like, shape (n, 4, 4)
        Flange poses in the base frame and board poses in the camera frame, mm.
    setup : str
        The declared set-up.
    ids : sequence of int, optional
        Posture indices to name in the messages (default 0..n-1).
    """
    a, b = _check_poses(tool0_in_base, target_in_camera)
    findings = find_duplicates(a, b, ids, limits)
    units = find_unit_problems(a, b, ids, limits)
    setup_findings = find_setup_mismatch(a, b, setup, limits)
    inconsistent = find_inconsistent_postures(a, b, ids, limits)
    findings += units + setup_findings + inconsistent
    if not units and not setup_findings and not any(f.kind == "rotation_convention" for f in inconsistent):
        findings += find_model_mismatch(a, b, setup, limits)  # only when nothing above explains it already
    return findings


def diagnose_session(session: Session, limits: DiagnosticLimits = DiagnosticLimits()) -> list:
    """:func:`diagnose` on a session (postures with joints or corner points are converted first).

    Raises
    ------
    CalibrationError
        When the session cannot be turned into poses (see ``solve.problem_from_session``).
    """
    from .solve import problem_from_session  # local: solve imports much of the package

    problem = problem_from_session(session, check_consistency=False)  # diagnose, do not refuse
    tool0 = hand_poses(problem.hand, session.setup)  # the map is its own inverse for either set-up
    return diagnose(tool0, problem.target2cam, session.setup, [int(i) for i in problem.posture_ids], limits)
