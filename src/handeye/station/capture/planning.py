"""Posture planning for guided capture.

From a start posture where the camera sees the board, the planner knows roughly where the board is
(the start measurement carried into the base frame through the nominal camera mount). It then:

1. draws view points on a cone around the board normal at a usable distance, rolled about the optical
   axis and aimed so the board appears all over the image (``robot.views``), turns each into
   a posture by inverse kinematics from the start configuration, and keeps those inside the joint
   limits with a margin from which every camera of the head sees the whole board;
2. orders them for short motions: nearest neighbour by synchronised motion time (the slowest axis,
   from the axis speeds), then 2-opt;
3. with a cell (``station.cell.plan``): refuses a start posture inside (or within the margin of) a
   keep-out volume, vetoes postures closer than the margin to the cell while drawing them, and
   repairs the order so every move, sampled along the joint-interpolated path ``MoveAbsJ`` runs,
   keeps the margin: blocked moves are avoided by the order, postures at blocked moves replaced by new
   draws, or dropped; fewer postures than asked are accepted down to the verdict's
   ``min_inlier_postures``, below that the plan is refused with the reasons;
4. scores the plan with the verdict's own quality words (``calibration.quality_words``): the
   rotation-axis spread and the relative rotation angles between postures, so the plan shows the
   numbers the verdict will judge; and the accuracy to expect, by solving a few simulated sessions
   of this very plan with the configured noise.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from types import SimpleNamespace

import numpy as np

from ...geometry import BoardGeometry, board_corners
from ...base import CalibrationError, HandEyeError
from ...robot import RobotModel
from ...calibration import hand_axis_coverage
from ...calibration import calibrate, problem_from_session
from ...calibration import NoiseConfig, Scene, SceneConfig, sample_session
from ...geometry import invert_transforms
from ...robot import NOMINAL_XB3, ViewSampling, sample_eye_in_hand_postures
from ..board_square import known_square_mm
from ..cell.plan import CellCheck, PostureVeto, Rejections, base_problem, board_problem, clear_route, start_problem
from ..report.quality import QualityThresholds, motion_shortfalls
from .partial_plan import number_partial_postures, widen_with_partial_views

__all__ = [
    "PlanScore",
    "PlanningError",
    "PosturePlan",
    "board_distance_and_tilt",
    "motion_time_s",
    "order_for_short_motions",
    "plan_postures",
    "score_plan",
]


class PlanningError(HandEyeError):
    """No usable plan: the board cannot be seen from enough reachable postures."""


@dataclass(frozen=True)
class PlanScore:
    """How good a posture set is for hand-eye calibration.

    Attributes
    ----------
    rotation_axis_spread_deg : float
        The rotation-axis spread of the planned flange motions (``calibration.quality_words``): how
        far the relative rotation axes rise out of the plane they lie closest to; 0 = all in one
        plane, 35.3 = even over the sphere. The verdict checks the same figure of the kept postures
        against ``min_rotation_axis_spread_deg``.
    min_pair_angle_deg, median_pair_angle_deg : float
        Relative rotation angles between postures (every pair).
    predicted_sigma_mm, predicted_sigma_deg : float
        RMS error of the camera pose over simulated sessions of this plan (the default estimator).
    motion_time_s : float
        Sum of the synchronised move times along the order.
    rejected_postures, rejected_moves : int
        Postures the cell check refused while drawing them, and moves between postures it found
        blocked (each cost a posture, replaced or dropped).
    rejections : tuple of str
        Why, most frequent first (``3 postures: camera too close to 'fixture'``).
    """

    rotation_axis_spread_deg: float
    min_pair_angle_deg: float
    median_pair_angle_deg: float
    predicted_sigma_mm: float
    predicted_sigma_deg: float
    motion_time_s: float
    rejected_postures: int = 0
    rejected_moves: int = 0
    rejections: tuple = ()

    def to_dict(self) -> dict:
        """YAML-ready: the figures as floats and counts, the reasons as a list."""
        out = {k: float(v) for k, v in asdict(self).items() if k not in ("rejected_postures", "rejected_moves", "rejections")}
        return {**out, "rejected_postures": int(self.rejected_postures), "rejected_moves": int(self.rejected_moves),
                "rejections": list(self.rejections)}

    @classmethod
    def from_dict(cls, data: dict) -> "PlanScore":
        """The score :meth:`to_dict` wrote (a plan read back from ``session.yaml``); TypeError when it is not one."""
        return cls(**{**data, "rejections": tuple(data.get("rejections", ()))})

    def verdict(self, thresholds: QualityThresholds | None = None) -> list[str]:
        """Warnings an operator should read before moving (empty when the plan looks good): the
        plan's figures below the verdict's thresholds (defaults when omitted)."""
        coverage = SimpleNamespace(spread_deg=self.rotation_axis_spread_deg, median_angle_deg=self.median_pair_angle_deg)
        advice = {"min_rotation_axis_spread_deg": "widen the cone or the roll", "min_median_rotation_deg": "widen the cone"}
        return [f"{s.word} {s.value:.1f} deg < {s.required:g} deg ({s.key}): {advice[s.key]}"
                for s in motion_shortfalls(coverage, thresholds or QualityThresholds())]


@dataclass(frozen=True)
class PosturePlan:
    """An ordered list of approved postures.

    Attributes
    ----------
    joints_deg : ndarray, shape (n, 6)
        Controller angles, in capture order.
    board2base : ndarray, shape (4, 4)
        Board pose the plan was made for (estimated).
    cam2tool0 : ndarray, shape (4, 4)
        Nominal camera mount used for planning.
    score : PlanScore
    start_joints_deg : ndarray, shape (6,)
    board : BoardGeometry
    notes : list of str
        Warnings for the operator.
    cell : CellCheck or None
        The cell the plan was checked against.
    partial : list of PartialPosture
        Postures planned with the board partly out of view (ChArUco only, ``station.capture.partial_plan``),
        numbered in capture order, each with the line that says so.
    """

    joints_deg: np.ndarray
    board2base: np.ndarray
    cam2tool0: np.ndarray
    score: PlanScore
    start_joints_deg: np.ndarray
    board: BoardGeometry
    notes: list = field(default_factory=list)
    cell: CellCheck | None = None
    partial: list = field(default_factory=list)


def motion_time_s(robot: RobotModel, a, b) -> np.ndarray:
    """Synchronised move time between joint configurations (the slowest axis at full speed)."""
    delta = np.abs(np.asarray(a, float) - np.asarray(b, float))
    return np.max(delta / robot.max_speed_deg_s, axis=-1)


def order_for_short_motions(robot: RobotModel, joints: np.ndarray, start, blocked=None) -> np.ndarray:
    """Visiting order (indices) starting next to ``start``: nearest neighbour, then 2-opt.

    ``blocked`` (``(n + 1, n + 1)`` bool over ``[start, *joints]``, optional): moves that cost
    infinitely much (not clear of the cell); the order avoids them when it can.
    """
    n = len(joints)
    nodes = np.vstack([np.asarray(start, float)[None], joints])
    cost = motion_time_s(robot, nodes[:, None, :], nodes[None, :, :])
    if blocked is not None:
        cost = np.where(blocked, np.inf, cost)
    route = [0]
    left = set(range(1, n + 1))
    while left:
        here = route[-1]
        nxt = min(left, key=lambda k: cost[here, k])
        route.append(nxt)
        left.remove(nxt)
    route = np.array(route)
    improved = True
    while improved:  # 2-opt on an open path that starts at the start posture
        improved = False
        for i in range(1, n):
            for j in range(i + 1, n + 1):
                a, b = route[i - 1], route[i]
                c = route[j]
                d = route[j + 1] if j + 1 <= n else None
                before = cost[a, b] + (cost[c, d] if d is not None else 0.0)
                after = cost[a, c] + (cost[b, d] if d is not None else 0.0)
                if after < before - 1e-12:
                    route[i:j + 1] = route[i:j + 1][::-1]
                    improved = True
    return route[1:] - 1


def score_plan(robot: RobotModel, joints: np.ndarray, board2base: np.ndarray, cam2tool0: np.ndarray,
               board: BoardGeometry, start, noise: NoiseConfig = NoiseConfig(0.005, 0.3, "gaussian"),
               trials: int = 5) -> PlanScore:
    """Score a plan (see :class:`PlanScore`); ``noise`` is what the simulated sessions carry."""
    coverage = hand_axis_coverage(robot.forward_transform(joints), "tool0")  # eye-in-hand: hand = tool02base
    nodes = np.vstack([np.asarray(start, float)[None], joints])
    total = float(motion_time_s(robot, nodes[:-1], nodes[1:]).sum())
    scene = Scene(SceneConfig(postures=len(joints), corners=board.corners, square_mm=known_square_mm(board), robot=robot.name),
                  robot, cam2tool0, board2base, np.asarray(joints, float), board)
    errors_mm, errors_deg = [], []
    for trial in range(trials):
        session = sample_session(scene, NoiseConfig(noise.sigma_rob_deg, noise.sigma_cam_mm, noise.camera_model,
                                                    noise.joint_offset_deg, seed=trial))
        result = calibrate(problem_from_session(session), None, {"x": cam2tool0, "target2fixed": board2base})
        errors = result.truth_errors
        if errors is None:  # calibrate judges against the truth it is given
            raise CalibrationError("the plan's simulated calibration came back without its errors against the truth")
        errors_mm.append(errors["translation_error_mm"])
        errors_deg.append(errors["rotation_error_deg"])
    return PlanScore(coverage.spread_deg, coverage.min_angle_deg, coverage.median_angle_deg,
                     float(np.sqrt(np.mean(np.square(errors_mm)))),
                     float(np.sqrt(np.mean(np.square(errors_deg)))), total)


def plan_postures(
    robot: RobotModel,
    start_joints_deg,
    target2cam_at_start,
    cam2tool0_nominal,
    board: BoardGeometry,
    count: int = 30,
    sampling: ViewSampling | None = None,
    views=NOMINAL_XB3,
    seed: int = 0,
    noise: NoiseConfig = NoiseConfig(0.005, 0.3, "gaussian"),
    max_attempts: int | None = None,
    thresholds: QualityThresholds | None = None,
    cell: CellCheck | None = None,
    partial_views: bool = True,
) -> PosturePlan:
    """Plan ``count`` postures around the board seen from the start posture.

    Parameters
    ----------
    robot : RobotModel
    start_joints_deg : array-like, shape (6,)
        A posture from which the camera sees the board.
    target2cam_at_start : ndarray, shape (4, 4)
        The board measured there (camera frame, mm).
    cam2tool0_nominal : ndarray, shape (4, 4)
        The camera mount from the drawing (planning only; the calibration measures the real one).
    board : BoardGeometry
    count : int
    sampling : ViewSampling, optional
        Default: distances 0.7-1.2 m, 35 deg cone, 40 deg roll, the camera on the robot's side.
    views : sequence of PinholeView
        Cameras that must see the whole board (default: the XB3 wide pair).
    seed : int
    noise : NoiseConfig
        Noise of the simulated sessions that predict the accuracy.
    max_attempts : int, optional
        View points to try before giving up (default ``200 * count``).
    thresholds : QualityThresholds, optional
        The verdict's thresholds the plan is warned against (the defaults when omitted).
    cell : CellCheck, optional
        The cell every posture and move must keep clear of (its board stand from the board estimate).
    partial_views : bool
        A ChArUco board may be partly out of view where that widens the rotation spread (``partial_plan``).

    Raises
    ------
    PlanningError
        No plan (with the reasons), or a start posture inside or within the margin of the cell.
    """
    start = np.asarray(start_joints_deg, float)
    if robot.limit_violations(start):
        raise PlanningError(f"start posture outside the joint limits: {'; '.join(robot.limit_violations(start))}")
    board2base = robot.forward_transform(start) @ cam2tool0_nominal @ np.asarray(target2cam_at_start, float)
    if sampling is None:
        centre = board2base[:3, 3]
        side = -np.array([centre[0], centre[1], 0.0])
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-6 else np.array([-1.0, 0.0, 0.0])
        sampling = ViewSampling(side=tuple(side))
    corners = board_corners(board.corners, known_square_mm(board))
    rng = np.random.default_rng(seed)
    thresholds = thresholds or QualityThresholds()
    widen = _widener(robot, cam2tool0_nominal, board2base, board, corners, rng, sampling, views, start, partial_views)
    if cell is None:
        joints = _draw(robot, cam2tool0_nominal, board2base, corners, count, rng, sampling, views, start, max_attempts)
        joints, partial = widen(joints)
        joints = joints[order_for_short_motions(robot, joints, start)]
        rejections = Rejections()
    else:
        joints, rejections, partial = _draw_clear_of_cell(robot, cam2tool0_nominal, board2base, board, corners, count,
                                                           rng, sampling, views, start, max_attempts, cell, thresholds,
                                                           widen)
    partial = number_partial_postures(joints, partial)
    score = score_plan(robot, joints, board2base, cam2tool0_nominal, board, start, noise)
    score = replace(score, rejected_postures=sum(rejections.postures.values()),
                    rejected_moves=sum(rejections.moves.values()), rejections=tuple(rejections.lines()))
    notes = score.verdict(thresholds)
    if len(joints) < count:
        notes.append(f"only {len(joints)} of {count} postures keep clear of the cell: {rejections.summary()}")
    return PosturePlan(joints, board2base, np.asarray(cam2tool0_nominal, float), score, start, board, notes, cell, partial)


def _widener(robot, cam2tool0, board2base, board, corners, rng, sampling, views, start, enabled: bool):
    """``widen(joints, veto=None, pose_veto=None) -> (joints, partial)``: the partial views swapped in where
    they widen the rotation spread (``partial_plan``), or nothing when ``enabled`` is false."""
    def widen(joints, veto=None, pose_veto=None):
        if not enabled:
            return joints, []
        return widen_with_partial_views(robot, joints, cam2tool0, board2base, board, corners, rng, sampling, views,
                                        start, veto=veto, pose_veto=pose_veto)
    return widen


def _draw(robot, cam2tool0, board2base, corners, count, rng, sampling, views, start, max_attempts, veto=None,
          min_count=None) -> np.ndarray:
    """``sample_eye_in_hand_postures``, its RuntimeError a PlanningError saying what to do."""
    try:
        return sample_eye_in_hand_postures(robot, cam2tool0, board2base, corners, count, rng, sampling, views,
                                           seed_joints=start, max_attempts=max_attempts, veto=veto, min_count=min_count)
    except RuntimeError as exc:
        raise PlanningError(f"{exc}; move the start posture so the board is centred at about 0.9 m") from None


def _draw_clear_of_cell(robot, cam2tool0, board2base, board, corners, count, rng, sampling, views, start, max_attempts,
                        cell: CellCheck, thresholds: QualityThresholds, widen) -> tuple[np.ndarray, Rejections, list]:
    """Postures and their order clear of the cell (``station.cell.plan``), at least the verdict's
    ``min_inlier_postures`` of them, why the others were rejected, and the partial views ``widen``
    swapped in (before the route repair, with the same vetoes)."""
    guard = cell.guard(robot, board2base, board)
    problem = (board_problem(cell.model, board2base, board, sampling.distance_mm, sampling.cone_deg)
               or base_problem(robot, cell.model.volumes(board2base, board), cell.margin_mm, cell.model.keep_out)
               or start_problem(guard, start))
    if problem is not None:
        raise PlanningError(problem)
    rejections = Rejections()
    veto = PostureVeto(guard, rejections)
    fewest = min(count, thresholds.min_inlier_postures)
    try:
        joints = sample_eye_in_hand_postures(robot, cam2tool0, board2base, corners, count, rng, sampling, views,
                                             seed_joints=start, max_attempts=max_attempts, veto=veto, min_count=fewest,
                                             pose_veto=veto.pose)
    except RuntimeError as exc:
        found = int(str(exc).split()[1])  # "only N of M postures found; ..."
        raise PlanningError(_too_few(f"only {found} of {count} postures keep clear of the cell", fewest, rejections)) \
            from None
    joints, partial = widen(joints, veto=veto, pose_veto=veto.pose)

    def redraw(m: int) -> np.ndarray:
        return sample_eye_in_hand_postures(robot, cam2tool0, board2base, corners, m, rng, sampling, views,
                                           seed_joints=start, max_attempts=200 * m, veto=veto, min_count=0,
                                           pose_veto=veto.pose)

    joints = clear_route(robot, guard, start, joints, redraw, rejections, order_for_short_motions)
    if len(joints) < fewest:
        raise PlanningError(_too_few(f"only {len(joints)} of {count} postures keep clear of the cell with clear moves "
                                     "between them", fewest, rejections))
    return joints, rejections, partial


def _too_few(found: str, fewest: int, rejections: Rejections) -> str:
    return (f"{found}, fewer than the {fewest} the verdict needs (min_inlier_postures): {rejections.summary()}; "
            "move the board or the keep-out volumes, or widen plan.distance_mm / plan.cone_deg")


def board_distance_and_tilt(plan: PosturePlan, robot: RobotModel) -> np.ndarray:
    """Per planned posture: camera-to-board-centre distance (mm) and board tilt (deg), ``(n, 2)``."""
    cams = robot.forward_transform(plan.joints_deg) @ plan.cam2tool0
    target2cam = invert_transforms(cams) @ plan.board2base
    centre = board_corners(plan.board.corners, known_square_mm(plan.board)).mean(axis=0)
    distance = np.linalg.norm(target2cam[:, :3, :3] @ centre + target2cam[:, :3, 3], axis=1)
    tilt = np.degrees(np.arccos(np.clip(np.abs(target2cam[:, 2, 2]), 0, 1)))
    return np.stack([distance, tilt], axis=1)
