"""Camera view points around a board: pinhole visibility and reachable postures (eye-in-hand).

Used by the synthetic scenes and by the station's posture planner, so both make the same kind of
postures: the camera looks at the board from a cone of directions around the board normal, at a
usable distance, rolled about its optical axis, with the aim point moved so the board appears all
over the image; each view becomes a robot posture by inverse kinematics from a seed configuration
and is kept only when the joints stay inside their limits with a margin and every camera of the
head sees the whole board.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from .kinematics import RobotModel, inverse_kinematics
from ..geometry import invert_transforms, transform_from_rotation_translation

__all__ = [
    "PinholeView",
    "NOMINAL_XB3_LEFT",
    "NOMINAL_XB3_RIGHT",
    "NOMINAL_XB3",
    "ViewSampling",
    "look_at",
    "board_visible",
    "corners_in_view",
    "sample_eye_in_hand_postures",
    "ik_from_standard_seeds",
]


@dataclass(frozen=True)
class PinholeView:
    """An undistorted pinhole camera placed in the reference camera frame.

    Attributes
    ----------
    width, height : int
        Image size in pixels.
    f_px, cx, cy : float
        Focal length and principal point in pixels.
    view2camera : ndarray, shape (4, 4)
        This camera's pose in the reference camera frame (identity for the reference itself).
    """

    width: int
    height: int
    f_px: float
    cx: float
    cy: float
    view2camera: np.ndarray = field(default_factory=lambda: np.eye(4))

    def project(self, points_cam: ArrayLike) -> np.ndarray:
        """Pixel coordinates ``(m, 2)`` of points ``(m, 3)`` in the reference camera frame (NaN behind)."""
        pts = np.asarray(points_cam, float)
        local = (pts - self.view2camera[:3, 3]) @ self.view2camera[:3, :3]
        z = np.where(local[:, 2] > 1e-9, local[:, 2], np.nan)
        return np.stack([self.f_px * local[:, 0] / z + self.cx, self.f_px * local[:, 1] / z + self.cy], axis=1)

    def sees(self, points_cam: ArrayLike, margin_px: float = 25.0, min_depth_mm: float = 100.0) -> bool:
        """True when every point is in front (beyond ``min_depth_mm``) and inside the image margin."""
        return bool(np.all(self.sees_each(points_cam, margin_px, min_depth_mm)))

    def sees_each(self, points_cam: ArrayLike, margin_px: float = 25.0, min_depth_mm: float = 100.0) -> np.ndarray:
        """Bool ``(m,)``: which points ``(m, 3)`` are in front (beyond ``min_depth_mm``) and inside the margin."""
        pts = np.asarray(points_cam, float)
        local_z = ((pts - self.view2camera[:3, 3]) @ self.view2camera[:3, :3])[:, 2]
        with np.errstate(invalid="ignore"):
            uv = self.project(pts)
            inside = ((uv[:, 0] > margin_px) & (uv[:, 0] < self.width - margin_px)
                      & (uv[:, 1] > margin_px) & (uv[:, 1] < self.height - margin_px))
        return inside & (local_z >= min_depth_mm)


#: Nominal rectified XB3 wide pair (3.8 mm lenses, 1280x960): f 983 px, baseline 239.98 mm.
NOMINAL_XB3_LEFT = PinholeView(1280, 960, 983.0, 643.6, 493.4)
NOMINAL_XB3_RIGHT = PinholeView(1280, 960, 983.0, 643.6, 493.4,
                                transform_from_rotation_translation(np.eye(3), [239.98, 0.0, 0.0]))
NOMINAL_XB3 = (NOMINAL_XB3_LEFT, NOMINAL_XB3_RIGHT)


def look_at(camera_position: ArrayLike, target_position: ArrayLike, roll_rad: float,
            up: Sequence[float] = (0.0, 0.0, 1.0)) -> np.ndarray:
    """cam2base with z towards the target, x right and y down in the image, rolled about z."""
    z = np.asarray(target_position, float) - np.asarray(camera_position, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    if np.linalg.norm(x) < 1e-6:
        x = np.cross(z, [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    base = np.stack([x, y, z], axis=1)
    roll = Rotation.from_rotvec([0.0, 0.0, roll_rad]).as_matrix()
    return transform_from_rotation_translation(base @ roll, camera_position)


def board_visible(target2cam: ArrayLike, corners_target: ArrayLike, views: Sequence[PinholeView] = (NOMINAL_XB3_LEFT,),
                  margin_px: float = 25.0) -> bool:
    """True when every view sees every corner ``(m, 3)`` (target frame) of a board at ``target2cam``."""
    pts = np.asarray(corners_target, float) @ np.asarray(target2cam)[:3, :3].T + np.asarray(target2cam)[:3, 3]
    return all(view.sees(pts, margin_px) for view in views)


def corners_in_view(target2cam: ArrayLike, corners_target: ArrayLike, views: Sequence[PinholeView] = (NOMINAL_XB3_LEFT,),
                    margin_px: float = 25.0) -> np.ndarray:
    """Bool ``(m,)``: the corners ``(m, 3)`` (target frame) of a board at ``target2cam`` that every view sees
    (a partial view of a ChArUco board holds these)."""
    pts = np.asarray(corners_target, float) @ np.asarray(target2cam)[:3, :3].T + np.asarray(target2cam)[:3, 3]
    seen = np.ones(len(pts), bool)
    for view in views:
        seen &= view.sees_each(pts, margin_px)
    return seen


@dataclass(frozen=True)
class ViewSampling:
    """How view points are drawn around the board.

    Attributes
    ----------
    distance_mm : tuple of float
        Camera-to-board-centre distance range.
    cone_deg : float
        Largest angle between the viewing direction and the board normal.
    roll_deg : float
        Largest roll about the optical axis, either way.
    aim_mm : float
        Standard deviation of the aim point about the board centre (moves the board in the image;
        point consistency needs the board seen at different places of the image).
    margin_px : float
        Border the corners must keep from the image edge.
    joint_margin_deg : float
        Margin to keep from every joint limit.
    side : tuple of float
        Horizontal direction (base frame) the camera stays on, e.g. towards the robot.
    max_joint_jump_deg : float
        Largest change of any axis from the seed configuration (no flips of arm or wrist).
    """

    distance_mm: tuple = (700.0, 1200.0)
    cone_deg: float = 35.0
    roll_deg: float = 40.0
    aim_mm: float = 80.0
    margin_px: float = 25.0
    joint_margin_deg: float = 5.0
    side: tuple = (-1.0, 0.0, 0.0)
    max_joint_jump_deg: float = 150.0


SEED_CONFIGURATIONS = ([0, 10, 20, 0, 60, 0], [0, 0, 0, 0, 45, 0], [0, 20, 30, 0, -60, 180], [0, -10, 10, 90, 60, -90])


def ik_from_standard_seeds(robot: RobotModel, tool02base: np.ndarray, margin_deg: float) -> np.ndarray | None:
    """Joints reaching ``tool02base`` from a few standard seeds (least wrist twist wins), or ``None``."""
    best = None
    for seed in SEED_CONFIGURATIONS:
        ik = inverse_kinematics(robot, tool02base, seed, margin_deg=margin_deg)
        if ik.success and (best is None or np.abs(ik.joints_deg[[3, 5]]).sum() < np.abs(best[[3, 5]]).sum()):
            best = ik.joints_deg
    return best


def _view_point(rng: np.random.Generator, sampling: ViewSampling, centre, normal_out, frame, side) -> np.ndarray:
    """One drawn camera pose ``cam2base``: within the cone about the board's outward normal (``frame``: two
    unit vectors across it), on the robot's ``side``, at a drawn distance, rolled, aimed near the centre."""
    e1, e2 = frame
    distance = rng.uniform(*sampling.distance_mm)
    tilt = np.radians(sampling.cone_deg) * np.sqrt(rng.uniform())
    azimuth = rng.uniform(0, 2 * np.pi)
    roll = np.radians(rng.uniform(-sampling.roll_deg, sampling.roll_deg))
    aim = rng.normal(0.0, sampling.aim_mm, 3)
    direction = np.cos(tilt) * normal_out + np.sin(tilt) * (np.cos(azimuth) * e1 + np.sin(azimuth) * e2)
    lateral = direction - (direction @ normal_out) * normal_out
    if lateral @ side < 0:  # keep the camera on the robot's side of the board
        direction = direction - 2 * (lateral @ side) / (side @ side) * side
    return look_at(centre + distance * direction, centre + aim, roll + np.pi / 2, up=(1.0, 0.0, 0.0))


def _posture_near(robot: RobotModel, tool02base, anchor, sampling: ViewSampling):
    """Joints reaching ``tool02base`` from ``anchor`` (or the standard seeds), within ``max_joint_jump_deg``
    of the anchor; None when there are none."""
    if anchor is None:
        return ik_from_standard_seeds(robot, tool02base, sampling.joint_margin_deg)
    ik = inverse_kinematics(robot, tool02base, anchor, margin_deg=sampling.joint_margin_deg)
    found = ik.joints_deg if ik.success else ik_from_standard_seeds(robot, tool02base, sampling.joint_margin_deg)
    if found is None or np.any(np.abs(found - anchor) > sampling.max_joint_jump_deg):
        return None
    return found


def _board_view_frame(board: np.ndarray, corners: np.ndarray):
    """``(centre, outward normal, e1, e2)`` of the board in base: a frame around the outward normal
    (the printed face looks along -z of the target frame) in which a viewing direction is tilted."""
    centre = board[:3, :3] @ corners.mean(axis=0) + board[:3, 3]
    normal_out = -board[:3, 2]
    e1 = np.cross([0.0, 1.0, 0.0] if abs(normal_out[1]) < 0.9 else [1.0, 0.0, 0.0], normal_out)
    e1 /= np.linalg.norm(e1)
    return centre, normal_out, e1, np.cross(normal_out, e1)


def _view_ok(target2cam, corners, views, margin_px: float, accept_view) -> bool:
    """The whole board in every view, or (``accept_view``) a part of it that callable accepts."""
    if accept_view is None:
        return board_visible(target2cam, corners, views, margin_px)
    return bool(accept_view(corners_in_view(target2cam, corners, views, margin_px)))


def sample_eye_in_hand_postures(
    robot: RobotModel,
    cam2tool0: ArrayLike,
    target2base: ArrayLike,
    corners_target: ArrayLike,
    count: int,
    rng: np.random.Generator,
    sampling: ViewSampling = ViewSampling(),
    views: Sequence[PinholeView] = (NOMINAL_XB3_LEFT,),
    seed_joints: ArrayLike | None = None,
    max_attempts: int | None = None,
    veto: Callable[[np.ndarray], bool] | None = None,
    min_count: int | None = None,
    pose_veto: Callable[[np.ndarray], bool] | None = None,
    accept_view: Callable[[np.ndarray], bool] | None = None,
) -> np.ndarray:
    """Controller angles ``(count, k)`` of postures from which ``views`` see the whole board (or what ``accept_view`` takes).

    Parameters
    ----------
    robot : RobotModel
    cam2tool0 : ndarray, shape (4, 4)
        Camera mount (nominal when planning, the truth in a simulation).
    target2base : ndarray, shape (4, 4)
        Board pose (its target frame; z points into the board, away from the camera).
    corners_target : ndarray, shape (m, 3)
        Board corners in the target frame.
    count : int
    rng : numpy Generator
    sampling : ViewSampling
    views : sequence of PinholeView
        Every camera of the head that must see the board.
    seed_joints : array-like, shape (k,), optional
        Where the IK starts (default: found from standard seeds).
    max_attempts : int, optional
        Give up after this many view points (default ``200 * count``).
    veto : callable, optional
        ``veto(joints) -> bool``: True keeps a posture that passed every other test (the cell's
        clearance check); a vetoed one counts as an attempt and another is drawn.
    min_count : int, optional
        Fewest postures that will do when the attempts run out (default ``count``; then fewer rows).
    pose_veto : callable, optional
        ``pose_veto(tool02base) -> bool``: like ``veto``, on the flange pose, before the IK.
    accept_view : callable, optional
        ``accept_view(seen) -> bool`` on the corners all views see (``(m,)`` bool, :func:`corners_in_view`).

    Raises
    ------
    RuntimeError
        When fewer than ``min_count`` postures are found.
    """
    x = np.asarray(cam2tool0, float)
    board = np.asarray(target2base, float)
    corners = np.asarray(corners_target, float)
    centre, normal_out, e1, e2 = _board_view_frame(board, corners)
    side = np.asarray(sampling.side, float)
    anchor = None if seed_joints is None else np.asarray(seed_joints, float)
    joints = []
    attempts = 0
    limit = max_attempts if max_attempts is not None else 200 * count
    while len(joints) < count:
        attempts += 1
        if attempts > limit:
            if len(joints) >= (count if min_count is None else min_count):
                break
            raise RuntimeError(f"only {len(joints)} of {count} postures found; widen the distance or cone, or move the board")
        cam2base = _view_point(rng, sampling, centre, normal_out, (e1, e2), side)
        tool02base = cam2base @ invert_transforms(x)
        if not (robot.may_reach(tool02base[:3, 3])  # in this order: the vetoes count what they reject
                and _view_ok(invert_transforms(cam2base) @ board, corners, views, sampling.margin_px, accept_view)
                and (pose_veto is None or pose_veto(tool02base))):
            continue
        found = _posture_near(robot, tool02base, anchor, sampling)
        if found is None:
            continue
        if veto is not None and not veto(found):
            continue
        anchor = found if anchor is None else anchor
        joints.append(found)
    return np.array(joints).reshape(len(joints), robot.dof)
