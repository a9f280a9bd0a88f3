"""Stereo calibration of the head with OpenCV: each camera's intrinsics, then the pair, checked view by view.

Input: the board's corners in each image of a set of stereo pairs (canonical order, see
:mod:`.checkerboard`; a pair may hold the board in one image only). A ChArUco view may hold part of the
board: its corners carry their ids (``ViewCorners.left_ids``), each view's object points are the board
points of its ids, and a pair is calibrated on the ids both images saw (matched by id; a pair whose common
corners cannot fix the board's pose, ``geometry.view_refusal``, is left out of the pair saying why). Steps:

1. **Swap check** (before anything is solved): a left camera sees every point further right than the
   right camera does (for a side-by-side head the raw disparity ``x_left - x_right`` is
   ``f B / Z`` > 0, 118 px even at 2 m for an XB3 wide pair). When the board's mean column is
   smaller in the "left" image than in the "right" one in most pairs, the two image sets are
   swapped and the calibration is refused with what to do; a single pair that disagrees with the
   others is dropped (its files are swapped, or the images are not one frame).
2. **Intrinsics per camera** (``cv2.calibrateCameraExtended``) from every view in which that camera
   saw the board, pairs or not (views at the image borders, which the other camera cannot share,
   pin the distortion down). A view whose RMS reprojection error is far above the others'
   (more than :data:`DROP_RATIO` x the median and more than :data:`DROP_FLOOR_PX`) is dropped with
   the reason and the camera calibrated again, worst view first.
3. **The pair** (``cv2.stereoCalibrateExtended``) with ``CALIB_FIX_INTRINSIC`` on the pairs that
   kept the board in both images; pairs whose stereo error is far above the median (the board moved
   between the two exposures, images of different moments) are dropped the same way. Then, unless
   turned off, a **refinement pass** (``CALIB_USE_INTRINSIC_GUESS``: intrinsics and extrinsics
   together), kept when it lowers the error without moving the baseline by more than 1 % or a
   focal length by more than 2 %.
4. **Checks and figures**: RMS reprojection error (px) of each camera and of the pair, the baseline
   (mm), the RMS epipolar error (px: distance of each undistorted corner from the epipolar line of
   its match, both ways) and ``T``'s direction (camera 2 must sit to the right, ``T[0] < 0``).

Object points are in millimetres (``square_mm``), so ``T`` is in mm, as ``STEREO.yaml`` wants.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dataclasses import dataclass, field

import cv2
import numpy as np

from ...geometry import BoardGeometry, board_corners, view_refusal
from .errors import CameraError, StereoModelError
from .pnp import pose_from_rvec
from .stereo import StereoModel

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "StereoCalibrationError",
    "StereoSwapped",
    "ViewCorners",
    "ViewReport",
    "CameraIntrinsics",
    "StereoCalibration",
    "DISTORTION_MODELS",
    "calibrate_stereo",
    "epipolar_errors",
    "swap_votes",
]

#: Distortion models: name -> OpenCV flags.
DISTORTION_MODELS = {
    "k1k2p1p2k3": 0,
    "k1k2p1p2": cv2.CALIB_FIX_K3,
    "rational": cv2.CALIB_RATIONAL_MODEL,
}
#: Coefficients each model keeps (OpenCV may return up to 14, the rest zero).
COEFFICIENTS = {"k1k2p1p2k3": 5, "k1k2p1p2": 5, "rational": 8}
#: A view is dropped when its RMS error exceeds DROP_RATIO x the median and DROP_FLOOR_PX.
DROP_RATIO = 3.0
DROP_FLOOR_PX = 0.5
#: At most this fraction of the views is dropped (beyond it the data, not a view, is at fault).
MAX_DROPPED_FRACTION = 1 / 3
#: Fewest views per camera and fewest pairs for the pair.
MIN_VIEWS = 5
MIN_PAIRS = 5
#: The refinement pass is kept when it moves the baseline by at most this fraction, a focal length by at most FOCAL_SHIFT.
BASELINE_SHIFT = 0.01
FOCAL_SHIFT = 0.02
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
#: The joint pass has many more unknowns; OpenCV's Levenberg-Marquardt needs more iterations there.
REFINE_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 300, 1e-12)


class StereoCalibrationError(CameraError):
    """The pairs cannot be calibrated: too few views, degenerate views, an implausible result."""


class StereoSwapped(StereoCalibrationError):
    """The images given as left are the right camera's (and the other way round)."""


@dataclass(frozen=True)
class ViewCorners:
    """The board in one stereo pair.

    Attributes
    ----------
    name : str
        The pair's name in reports (file stem or capture number).
    left, right : ndarray, shape (nx*ny, 2), or None
        Canonical corners in the raw left/right image, ``None`` where the board was not found.
    left_note, right_note : str
        Why the board is missing in that image (the detector's message).
    left_ids, right_ids : ndarray of int, shape (k,), or None
        The corner ids (target indices) of ``left`` / ``right`` when the image saw part of the board
        (ChArUco); None: every corner, in index order.
    """

    name: str
    left: np.ndarray | None
    right: np.ndarray | None
    left_note: str = ""
    right_note: str = ""
    left_ids: np.ndarray | None = None
    right_ids: np.ndarray | None = None

    def ids(self, side: str, count: int) -> np.ndarray:
        """The corner ids of ``side``'s corners (``arange(count)`` for a whole view)."""
        given = getattr(self, f"{side}_ids")
        return np.arange(count) if given is None else np.asarray(given, int)

    def common(self, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ids, left, right)``: the ids both images saw (ascending) and their corners in each image."""
        li, ri = self.ids("left", count), self.ids("right", count)
        ids, a, b = np.intersect1d(li, ri, assume_unique=True, return_indices=True)
        return ids, np.asarray(self.left)[a], np.asarray(self.right)[b]


@dataclass
class ViewReport:
    """How one pair was used.

    Attributes
    ----------
    name : str
    used_left, used_right, used_pair : bool
        Whether the view entered the left/right intrinsics and the pair's calibration.
    left_rms_px, right_rms_px : float or None
        Reprojection RMS in each camera's own calibration.
    pair_rms_px : float or None
        Reprojection RMS (both images) under the stereo calibration.
    reasons : list of str
        Why a part of the view was not used.
    """

    name: str
    used_left: bool = False
    used_right: bool = False
    used_pair: bool = False
    left_rms_px: float | None = None
    right_rms_px: float | None = None
    pair_rms_px: float | None = None
    reasons: list = field(default_factory=list)

    def to_json(self) -> dict:
        r = lambda v: None if v is None else round(float(v), 4)  # noqa: E731
        return {"name": self.name, "used_left": self.used_left, "used_right": self.used_right,
                "used_pair": self.used_pair, "left_rms_px": r(self.left_rms_px), "right_rms_px": r(self.right_rms_px),
                "pair_rms_px": r(self.pair_rms_px), "reasons": list(self.reasons)}


@dataclass
class CameraIntrinsics:
    """One camera's calibration: ``K`` (3x3), ``D``, the RMS error (px), the standard deviations of
    ``fx, fy, cx, cy`` (px), and the board pose ``target2cam`` of each view used (by name)."""

    K: np.ndarray
    D: np.ndarray
    rms_px: float
    std_px: np.ndarray
    poses: dict


@dataclass
class StereoCalibration:
    """The result of :func:`calibrate_stereo`.

    Attributes
    ----------
    model : StereoModel
    rms_px : float
        RMS reprojection error of the pair (both images, ``stereoCalibrate``'s figure).
    left, right : CameraIntrinsics
    epipolar_rms_px : float
        RMS distance of the undistorted corners from their matches' epipolar lines.
    baseline_mm : float
    pairs_used : int
    refined : bool
        Whether the refinement pass (intrinsics and extrinsics together) was kept.
    views : list of ViewReport
    warnings : list of str
        Things the operator should know (few views, a refinement pass not kept).
    """

    model: StereoModel
    rms_px: float
    left: CameraIntrinsics
    right: CameraIntrinsics
    epipolar_rms_px: float
    baseline_mm: float
    pairs_used: int
    refined: bool
    views: list
    warnings: list = field(default_factory=list)

    def to_json(self) -> dict:
        """The figures of the calibration as plain JSON values."""
        def cam(c: CameraIntrinsics) -> dict:
            return {"rms_px": round(c.rms_px, 4), "fx": float(c.K[0, 0]), "fy": float(c.K[1, 1]),
                    "cx": float(c.K[0, 2]), "cy": float(c.K[1, 2]), "dist": [float(v) for v in c.D],
                    "std_fx_fy_cx_cy_px": [round(float(v), 4) for v in c.std_px], "views": len(c.poses)}
        m = self.model
        return {
            "rms_px": round(self.rms_px, 4),
            "baseline_mm": round(self.baseline_mm, 4),
            "epipolar_rms_px": round(self.epipolar_rms_px, 4),
            "pairs_used": self.pairs_used,
            "refined": self.refined,
            "image_size": list(m.image_size),
            "left": cam(self.left),
            "right": cam(self.right),
            "R": m.R.tolist(),
            "T_mm": m.T.tolist(),
            "rotation_deg": float(np.degrees(np.linalg.norm(cv2.Rodrigues(m.R)[0]))),
            "views": [v.to_json() for v in self.views],
            "warnings": list(self.warnings),
        }


def swap_votes(views) -> tuple[int, int, list]:
    """Pairs whose board sits further right in the left image than in the right one, pairs where it
    does not, and the names of the latter. A left camera sees every point further right (of a partial
    view, the corners both images saw)."""
    agree, disagree, names = 0, 0, []
    for v in views:
        if v.left is None or v.right is None:
            continue
        if v.left_ids is None and v.right_ids is None:
            left, right = v.left, v.right
        else:
            _, left, right = v.common(1 + int(max(np.max(v.ids("left", 1)), np.max(v.ids("right", 1)))))
        if not len(left):
            continue
        if float(np.mean(left[:, 0]) - np.mean(right[:, 0])) > 0:
            agree += 1
        else:
            disagree += 1
            names.append(v.name)
    return agree, disagree, names


def _swap_message(agree: int, disagree: int, why: str) -> str:
    return (f"the images given as left are the RIGHT camera's: {why} (in {disagree} of {agree + disagree} pairs the "
            f"board sits further left in the 'left' image than in the 'right' one, but a left camera sees every point "
            f"further right); swap the left and right images (--swap)")


def _objects(board: BoardGeometry) -> np.ndarray:
    if board.square_mm is None:
        raise StereoCalibrationError("the square size is needed to calibrate (--square-mm)")
    return np.asarray(board.grid(board.square_mm), np.float32)  # index = corner id (any kind of target)


def _outlier(errors: np.ndarray, n_dropped: int, n_total: int, min_keep: int) -> tuple[int, float] | None:
    """Index of the view to drop next (worst first) and the median, or ``None``."""
    errors = np.asarray(errors, float)
    median = float(np.median(errors))
    worst = int(np.argmax(errors))
    if errors[worst] <= max(DROP_RATIO * median, DROP_FLOOR_PX):
        return None
    if len(errors) - 1 < min_keep or n_dropped + 1 > MAX_DROPPED_FRACTION * n_total:
        return None
    return worst, median


def _calibrate_camera(side: str, items: list, obj: np.ndarray, size, flags: int, reports: dict) -> CameraIntrinsics:
    """``calibrateCameraExtended`` on ``items = [(name, corners, ids)]`` (each view's object points: the
    board points ``obj`` of its ids), dropping far-off views one at a time."""
    if len(items) < MIN_VIEWS:
        raise StereoCalibrationError(
            f"the board was found in only {len(items)} {side} image(s); at least {MIN_VIEWS} are needed (15-25 "
            f"recommended): capture more pairs with the whole board in view, spread over the image and tilted")
    items = list(items)
    total, dropped = len(items), 0
    while True:
        try:
            # K, D None: OpenCV allocates them (its stubs omit None)
            rms, k, d, rvecs, tvecs, std_in, _, per_view = cv2.calibrateCameraExtended(  # pyright: ignore[reportCallIssue]
                [obj[ids] for _, _, ids in items], [c.astype(np.float32).reshape(-1, 1, 2) for _, c, _ in items], size,
                None, None, flags=flags, criteria=CRITERIA)  # pyright: ignore[reportArgumentType]
        except cv2.error as exc:
            raise StereoCalibrationError(
                f"OpenCV could not calibrate the {side} camera ({str(exc).strip().splitlines()[-1][:120]}): the views "
                f"are probably too alike; tilt the board (20-45 deg) and move it over the whole image") from None
        errors = per_view.ravel()
        drop = _outlier(errors, dropped, total, MIN_VIEWS)
        if drop is None:
            break
        index, median = drop
        name = items[index][0]
        reports[name].reasons.append(
            f"{side}: RMS {errors[index]:.2f} px is {errors[index] / max(median, 1e-9):.1f}x the median {median:.2f} px "
            f"(blur, a misread corner or a moving board)")
        del items[index]
        dropped += 1
    if not np.all(np.isfinite(k)) or k[0, 0] <= 0 or k[1, 1] <= 0:
        raise StereoCalibrationError(f"the {side} camera's calibration diverged; capture more varied views")
    poses = {}
    for (name, _, _), rvec, tvec, err in zip(items, rvecs, tvecs, errors):
        poses[name] = pose_from_rvec(rvec, tvec)
        setattr(reports[name], f"used_{side}", True)
        setattr(reports[name], f"{side}_rms_px", float(err))
    return CameraIntrinsics(k, d.ravel(), float(rms), np.asarray(std_in).ravel()[:4], poses)


def _stereo(obj, pairs, left: CameraIntrinsics, right: CameraIntrinsics, size, flags, criteria=CRITERIA):
    """``cv2.stereoCalibrateExtended`` on the corners both images of each pair saw (matched by id)."""
    common = [p.common(len(obj)) for p in pairs]
    # R, T None: OpenCV allocates them (its stubs omit None)
    return cv2.stereoCalibrateExtended(  # pyright: ignore[reportCallIssue]
        [obj[ids] for ids, _, _ in common], [a.astype(np.float32).reshape(-1, 1, 2) for _, a, _ in common],
        [b.astype(np.float32).reshape(-1, 1, 2) for _, _, b in common],
        left.K.copy(), left.D.copy(), right.K.copy(), right.D.copy(), size,
        None, None, flags=flags, criteria=criteria)  # pyright: ignore[reportArgumentType]


def _per_pair_rms(errors, pairs) -> np.ndarray:
    """Per pair RMS (px) of ``stereoCalibrateExtended``'s per-view errors ``(n, 2)`` (both images)."""
    return np.sqrt(np.mean(np.asarray(errors, float).reshape(len(pairs), -1) ** 2, axis=1))


def epipolar_errors(model: StereoModel, left_px: npt.ArrayLike, right_px: npt.ArrayLike) -> np.ndarray:
    """Distances (px) of undistorted corners from the epipolar lines of their matches, ``(2n,)``.

    The points of both images are undistorted to pixel coordinates of their own camera matrix and
    ``F = K2^-T [T]x R K1^-1``; the distance of each right point from the line of its left point and
    the other way round.
    """
    left = np.asarray(left_px, np.float64).reshape(-1, 1, 2)
    right = np.asarray(right_px, np.float64).reshape(-1, 1, 2)
    ul = cv2.undistortPoints(left, model.K1, model.D1, P=model.K1).reshape(-1, 2)
    ur = cv2.undistortPoints(right, model.K2, model.D2, P=model.K2).reshape(-1, 2)
    tx = np.array([[0, -model.T[2], model.T[1]], [model.T[2], 0, -model.T[0]], [-model.T[1], model.T[0], 0]])
    f = np.linalg.inv(model.K2).T @ tx @ model.R @ np.linalg.inv(model.K1)
    hl = np.column_stack([ul, np.ones(len(ul))])
    hr = np.column_stack([ur, np.ones(len(ur))])
    lines_r = hl @ f.T   # l' = F x
    lines_l = hr @ f     # l = F^T x'
    d_r = np.abs(np.sum(lines_r * hr, axis=1)) / np.hypot(lines_r[:, 0], lines_r[:, 1])
    d_l = np.abs(np.sum(lines_l * hl, axis=1)) / np.hypot(lines_l[:, 0], lines_l[:, 1])
    return np.concatenate([d_r, d_l])


def _stereo_without_outlier_pairs(obj, pairs: list, left, right, size, flags: int, reports: dict):
    """The fixed-intrinsics stereo fit (``cv2.stereoCalibrate`` output) and its per-pair RMS (px), after
    dropping, one at a time, pairs far above the median (:func:`_outlier`); ``pairs`` loses them and their
    reports say why."""
    total, dropped = len(pairs), 0
    fixed = cv2.CALIB_FIX_INTRINSIC | flags  # the model flags too: RATIONAL_MODEL keeps its 8 coefficients
    while True:
        out = _stereo(obj, pairs, left, right, size, fixed)
        per_pair = _per_pair_rms(out[-1], pairs)
        drop = _outlier(per_pair, dropped, total, MIN_PAIRS)
        if drop is None:
            return out, per_pair
        index, median = drop
        reports[pairs[index].name].reasons.append(
            f"pair: RMS {per_pair[index]:.2f} px under the pair's geometry is {per_pair[index] / max(median, 1e-9):.1f}x "
            f"the median {median:.2f} px (the board moved between the two exposures?): not used for the pair")
        del pairs[index]
        dropped += 1


def _refined_stereo(obj, pairs: list, left, right, size, flags: int, out, per_pair, warnings: list):
    """The joint refinement (intrinsics and extrinsics together) of the fit ``out`` when it lowers the RMS
    without moving the baseline or a focal length beyond :data:`BASELINE_SHIFT` / :data:`FOCAL_SHIFT`.

    Returns ``(out, per_pair, refined)``: the refined fit and its per-pair RMS, or the given ones (a
    refinement that moved too far adds a warning to ``warnings``)."""
    rms, k1, _, k2, _, _, t = out[:7]
    ref = _stereo(obj, pairs, left, right, size, flags | cv2.CALIB_USE_INTRINSIC_GUESS, REFINE_CRITERIA)
    r_rms, r_k1, _, r_k2, _, _, r_t = ref[:7]
    baseline_shift = abs(np.linalg.norm(r_t) - np.linalg.norm(t)) / np.linalg.norm(t)
    focal_shift = max(abs(r_k1[0, 0] / k1[0, 0] - 1), abs(r_k2[0, 0] / k2[0, 0] - 1),
                      abs(r_k1[1, 1] / k1[1, 1] - 1), abs(r_k2[1, 1] / k2[1, 1] - 1))
    if not (np.isfinite(r_rms) and r_rms < rms):
        return out, per_pair, False  # no better: the per-camera intrinsics stand
    if baseline_shift <= BASELINE_SHIFT and focal_shift <= FOCAL_SHIFT:
        return ref, _per_pair_rms(ref[-1], pairs), True
    warnings.append(
        f"the joint refinement moved the baseline by {100 * baseline_shift:.1f} % and a focal length by "
        f"{100 * focal_shift:.1f} %: kept the per-camera intrinsics (capture more varied views to refine)")
    return out, per_pair, False


def _pair_fixes_pose(view: ViewCorners, board: BoardGeometry, report: ViewReport) -> bool:
    """True when the corners both images of a pair saw (by id) fix the board's pose (``geometry.view_refusal``:
    a whole view always); else the report says why the pair is left out."""
    if view.left_ids is None and view.right_ids is None:
        return True
    ids, _, _ = view.common(board.count)
    why = view_refusal(ids, board)
    if why:
        report.reasons.append(f"pair: the corners both images saw (matched by id): {why}; not used for the pair")
    return not why


def _view_reports(views: list) -> tuple[dict, tuple]:
    """A :class:`ViewReport` per view name, saying which images show no board and which pairs look
    swapped, and the swap votes ``(agree, disagree, wrong)`` (:func:`swap_votes`).

    Raises
    ------
    StereoSwapped
        When most pairs say the left and right images are swapped.
    """
    reports = {v.name: ViewReport(v.name) for v in views}
    for v in views:
        for side in ("left", "right"):
            if getattr(v, side) is None:
                reports[v.name].reasons.append(f"{side}: {getattr(v, side + '_note') or 'board not found'}")
    agree, disagree, wrong = swap_votes(views)
    if disagree > agree and disagree >= 2:
        raise StereoSwapped(_swap_message(agree, disagree, "the board's columns say so"))
    for v in views:
        if v.name in wrong:
            reports[v.name].reasons.append(
                "pair: the board sits further left in the left image than in the right one (this pair's files are "
                "swapped, or the two images are not one frame): not used")
    return reports, (agree, disagree, wrong)


def calibrate_stereo(views, board: BoardGeometry, image_size, *, distortion: str = "k1k2p1p2k3",
                     refine: bool = True, name: str = "") -> StereoCalibration:
    """Calibrate the stereo head from the board's corners in a set of pairs (see the module docstring).

    Parameters
    ----------
    views : sequence of ViewCorners
    board : BoardGeometry
        With ``square_mm`` (the unit of ``T``).
    image_size : (width, height)
    distortion : str
        A key of :data:`DISTORTION_MODELS`.
    refine : bool
        Try the refinement pass (intrinsics and extrinsics together) after the fixed-intrinsics pass.
    name : str
        The model's name (e.g. where the images came from).

    Returns
    -------
    StereoCalibration

    Raises
    ------
    StereoSwapped
        The left and right images are swapped.
    StereoCalibrationError
        Too few views or pairs, a diverging calibration, a vertical pair.
    """
    if distortion not in DISTORTION_MODELS:
        raise StereoCalibrationError(f"distortion model must be one of {', '.join(DISTORTION_MODELS)}; got {distortion!r}")
    flags = DISTORTION_MODELS[distortion]
    size = (int(image_size[0]), int(image_size[1]))
    obj = _objects(board)
    views = list(views)
    names = [v.name for v in views]
    if len(set(names)) != len(names):
        raise StereoCalibrationError("two pairs have the same name; name each pair once")
    reports, (agree, disagree, wrong) = _view_reports(views)
    usable = [v for v in views if v.name not in wrong]
    m = len(obj)
    left = _calibrate_camera("left", [(v.name, v.left, v.ids("left", m)) for v in usable if v.left is not None], obj,
                             size, flags, reports)
    right = _calibrate_camera("right", [(v.name, v.right, v.ids("right", m)) for v in usable if v.right is not None],
                              obj, size, flags, reports)
    pairs = [v for v in usable if reports[v.name].used_left and reports[v.name].used_right
             and _pair_fixes_pose(v, board, reports[v.name])]
    if len(pairs) < MIN_PAIRS:
        raise StereoCalibrationError(
            f"only {len(pairs)} pair(s) show the board in both images; at least {MIN_PAIRS} are needed (15-25 "
            f"recommended): hold the board where both cameras see it")
    out, per_pair = _stereo_without_outlier_pairs(obj, pairs, left, right, size, flags, reports)
    warnings = []
    out, per_pair_final, refined = (_refined_stereo(obj, pairs, left, right, size, flags, out, per_pair, warnings)
                                    if refine else (out, per_pair, False))
    rms, k1, d1, k2, d2, r, t = out[:7]
    t = np.asarray(t, float).ravel()
    if t[0] > 0 and abs(t[0]) > abs(t[1]):
        raise StereoSwapped(_swap_message(agree, disagree, f"T = ({t[0]:.1f}, {t[1]:.1f}, {t[2]:.1f}) mm puts camera 2 "
                                                          f"to the left of camera 1"))
    n = COEFFICIENTS[distortion]
    d1, d2 = np.asarray(d1, float).ravel()[:n], np.asarray(d2, float).ravel()[:n]
    try:
        model = StereoModel(size, k1, d1, k2, d2, r, t,
                            name=name or f"stereo calibration of {len(pairs)} pairs")
    except StereoModelError as exc:
        raise StereoCalibrationError(f"the calibration is not a usable side-by-side head: {exc}") from None
    for p, err in zip(pairs, per_pair_final):
        reports[p.name].used_pair = True
        reports[p.name].pair_rms_px = float(err)
    common = [p.common(m) for p in pairs]
    epi = epipolar_errors(model, np.concatenate([a for _, a, _ in common]), np.concatenate([b for _, _, b in common]))
    if len(pairs) < 10:
        warnings.append(f"only {len(pairs)} pairs were used; 15-25 well spread pairs give a steadier calibration")
    left_final = CameraIntrinsics(k1, d1.ravel(), left.rms_px, left.std_px, left.poses)
    right_final = CameraIntrinsics(k2, d2.ravel(), right.rms_px, right.std_px, right.poses)
    return StereoCalibration(model, float(rms), left_final, right_final, float(np.sqrt(np.mean(epi**2))),
                             float(np.linalg.norm(t)), len(pairs), refined, [reports[n] for n in names], warnings)
