"""The model of the maximum-likelihood estimator: what a session's postures are to the fit.

``A_i X B_i = T`` with both sides noisy (the package docstring, eq. 13): :func:`observations` turns a
:class:`~handeye.calibration.problem.HandEyeProblem` into the hand and board poses, the board model
points and the variance components (:class:`Component`) of each posture's covariance
``S_i = F_i + sum_k θ_k G_ik``: the board fit's own covariance from the stereo corner noise, or, for
sessions of board poses only, tilt, spin, depth and position components in the board frame; the
flange's joint-noise Jacobian when the session holds joint angles, else flange rotation and
translation noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from ..noise import (
    CornerNoise,
    adjoint,
    corner_noise,
    fit_board_poses,
    flange_jacobian,
    inverse_covariances,
    kinematic_jacobian,
    shape_eigen,
    stereo_point_shape,
    twist_between,
)
from ..joint_match import joint_mismatch
from ..problem import EYE_IN_HAND, HandEyeProblem
from ...geometry import invert_transforms


@dataclass(frozen=True)
class Component:
    """One variance component ``θ G_i`` of the posture covariance.

    Attributes
    ----------
    name : str
        ``joint`` (deg²), ``flange_rotation`` (rad²), ``flange_translation`` (mm²),
        ``camera_rotation`` (rad²), ``camera_translation`` (mm²).
    side : str
        ``hand``: ``structure`` is a local covariance of the hand pose, carried to the residual
        frame by ``Ad_{(X B_i)^-1}``; ``board``: already in the residual (board) frame.
    structure : ndarray, shape (n, 6, 6)
        ``G`` per unit variance.
    """

    name: str
    side: str
    structure: np.ndarray


@dataclass(frozen=True)
class Observations:
    """A problem prepared for the ML fit.

    Attributes
    ----------
    hand : ndarray, shape (n, 4, 4)
    board : ndarray, shape (n, 4, 4)
        Fitted board poses ``B_i`` (``target2cam``).
    board_cov : ndarray, shape (n, 6, 6)
        Fixed camera covariance of ``B_i`` (board frame twist); zeros for sessions of board poses.
    components : tuple of Component
        The variance components to estimate.
    mode : str
        ``corners`` (points fitted, camera noise from the fits) or ``poses``.
    corner : CornerNoise or None
    points : ndarray, shape (n, m, 3)
        Measured points (camera frame) used by the point measures.
    model_points : ndarray, shape (m, 3)
        The same points in the target frame.
    point_cov : ndarray, shape (n, m, 3, 3) or None
        Corner covariances (corner sessions).
    kinematic : ndarray, shape (n, 6, q) or None
        Hand-local twist per unit deviation of each DH entry of the robot model (sessions with
        joints): the arm's kinematic errors, the same at every posture (``noise.kinematic_jacobian``).
    kinematic_kinds : ndarray of int, shape (q,) or None
        0 for a length (mm), 1 for an angle (deg).
    """

    hand: np.ndarray
    board: np.ndarray
    board_cov: np.ndarray
    components: tuple
    mode: str
    corner: CornerNoise | None
    points: np.ndarray
    model_points: np.ndarray
    point_cov: np.ndarray | None = None
    kinematic: np.ndarray | None = None
    kinematic_kinds: np.ndarray | None = None
    notes: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.hand.shape[0])

    def subset(self, keep: ArrayLike) -> "Observations":
        keep = np.asarray(keep)
        comps = tuple(replace(c, structure=c.structure[keep]) for c in self.components)
        return replace(self, hand=self.hand[keep], board=self.board[keep], board_cov=self.board_cov[keep],
                       components=comps, points=self.points[keep],
                       point_cov=None if self.point_cov is None else self.point_cov[keep],
                       kinematic=None if self.kinematic is None else self.kinematic[keep])


def _board_data(problem: HandEyeProblem) -> tuple[np.ndarray, np.ndarray, bool]:
    """Measured points, their target-frame model and whether they are corners (more than 3)."""
    model = problem.target_points
    pts = problem.points_cam
    if model is not None and pts.shape[1] == len(model) and pts.shape[1] > 3:
        return pts, np.asarray(model, float), True
    return problem.compact.points, np.asarray(problem.compact.target_points, float), False


def _hand_components(problem: HandEyeProblem, notes: dict) -> tuple:
    """Robot-side components in the hand's local frame, and the kinematic-deviation Jacobian.

    With joint angles and a robot model: joint noise through the flange Jacobian, and the DH
    deviations (``noise.kinematic_jacobian``); otherwise flange rotation and translation noise. When
    joint angles do not reproduce the flange poses, ``notes["joint_mismatch"]`` says which postures.
    """
    n = problem.n
    tool02base = problem.hand if problem.setup == EYE_IN_HAND else invert_transforms(problem.hand)
    to_hand = np.broadcast_to(np.eye(6), (n, 6, 6)) if problem.setup == EYE_IN_HAND else -adjoint(tool02base)
    # eye-to-hand: hand = tool02base^-1, so (T ⊕ ξ)^-1 = T^-1 ⊕ (-Ad_T ξ)
    robot, mismatch = _robot_for(problem, tool02base)
    if mismatch is not None:
        notes["joint_mismatch"] = mismatch.line()
    if robot is not None and problem.joints_deg is not None:  # _robot_for gives a robot only with joints
        jac = flange_jacobian(robot, problem.joints_deg)
        g = to_hand @ (jac @ np.swapaxes(jac, 1, 2)) @ np.swapaxes(to_hand, 1, 2)
        kin, kinds = kinematic_jacobian(robot, problem.joints_deg)
        # joint noise, and a position noise of the flange for what joint noise cannot shape
        # (a jittering bracket, elastic deflection)
        trans = np.zeros((6, 6))
        trans[:3, :3] = np.eye(3)
        comps = (Component("joint", "hand", g),
                 Component("flange_translation", "hand", to_hand @ trans @ np.swapaxes(to_hand, 1, 2)))
        return comps, (to_hand @ kin, kinds)
    rot = np.zeros((6, 6))
    rot[3:, 3:] = np.eye(3)
    trans = np.zeros((6, 6))
    trans[:3, :3] = np.eye(3)
    g_rot = to_hand @ rot @ np.swapaxes(to_hand, 1, 2)
    g_trans = to_hand @ trans @ np.swapaxes(to_hand, 1, 2)
    return (Component("flange_rotation", "hand", g_rot), Component("flange_translation", "hand", g_trans)), None


def _robot_for(problem: HandEyeProblem, tool02base: np.ndarray):
    """The robot model of the problem's joints when its kinematics reproduce the flange poses, and the
    postures whose joints do not (``joint_match.JointMismatch``; None when they all do)."""
    joints = getattr(problem, "joints_deg", None)
    robot_name = getattr(problem, "robot", None)
    if joints is None or robot_name is None:
        return None, None
    from ...robot import load_robot  # noqa: PLC0415 (only sessions with joints need it)

    try:
        robot = load_robot(robot_name)
    except ValueError:
        return None, None
    joints = np.asarray(joints, float)
    if joints.shape != (problem.n, robot.dof):
        return None, None
    mismatch = joint_mismatch(robot, joints, tool02base, problem.posture_ids)
    return (None, mismatch) if mismatch is not None else (robot, None)


def observations(problem: HandEyeProblem, stereo: tuple | None = None) -> Observations:
    """Board poses, their covariance and the variance components of a problem.

    Parameters
    ----------
    problem : HandEyeProblem
    stereo : (f_px, baseline_mm), optional
        Rectified stereo geometry behind triangulated corners (default: the nominal XB3 wide pair).
    """
    pts, model, corners = _board_data(problem)
    n = problem.n
    if corners:
        start = problem.target2cam
    else:  # board poses from the three compact points (Horn, eq. 24-29)
        from ..absolute_orientation import absolute_orientation  # noqa: PLC0415
        from ...geometry import matrix_from_quaternion  # noqa: PLC0415

        fit = absolute_orientation(np.broadcast_to(model, pts.shape), pts)
        start = np.tile(np.eye(4), (n, 1, 1))
        start[:, :3, :3] = matrix_from_quaternion(fit.quaternion)
        start[:, :3, 3] = fit.translation
    notes: dict = {}
    hand_comps, kin = _hand_components(problem, notes)
    kinematic, kinematic_kinds = (None, None) if kin is None else kin
    if corners:
        f_px, baseline = stereo if stereo is not None else (None, None)
        kwargs = {} if f_px is None else {"f_px": f_px, "baseline_mm": baseline}
        shapes = stereo_point_shape(pts, **kwargs)
        eigen = shape_eigen(shapes)
        seen = getattr(problem, "seen", None)  # partial views (ChArUco): the unseen corners weigh nothing
        mask = None if seen is None else np.asarray(seen, float)[..., None, None]

        def weights(w):
            return w if mask is None else w * mask

        fit = fit_board_poses(pts, model, start, None if mask is None else weights(np.eye(3)), iterations=2)
        noise = corner_noise(fit.residuals, eigen, seen=seen)  # unweighted first: residuals for the components
        fit = fit_board_poses(pts, model, fit.target2cam, weights(inverse_covariances(noise, eigen)), iterations=1)
        noise = corner_noise(fit.residuals, eigen, seen=seen)
        fit = fit_board_poses(pts, model, fit.target2cam, weights(inverse_covariances(noise, eigen)), iterations=1)
        cov = noise.covariances(shapes)
        board_cov = np.linalg.inv(fit.information)
        return Observations(problem.hand, fit.target2cam, board_cov, hand_comps, "corners", noise, pts, model, cov,
                            kinematic=kinematic, kinematic_kinds=kinematic_kinds, notes=notes)
    return Observations(problem.hand, start, np.zeros((n, 6, 6)), _pose_components(hand_comps, start, model), "poses",
                        None, pts, model, kinematic=kinematic, kinematic_kinds=kinematic_kinds, notes=notes)


def _pose_components(hand_comps: tuple, target2cam: np.ndarray, model: np.ndarray) -> tuple:
    """Components of sessions of board poses: the robot's, the board's rotation, a position noise
    and the board's extra depth noise (along the camera's optical axis, as from a monocular pose).

    An isotropic position noise of the flange and one of the board give the residual the same
    covariance (``Ad`` only rotates it): one component ``position`` stands for both.
    """
    n = len(target2cam)
    tilt = np.zeros((n, 6, 6))
    tilt[:, 3, 3] = tilt[:, 4, 4] = 1.0  # about the board's in-plane axes: poorly seen by one camera
    spin = np.zeros((n, 6, 6))
    spin[:, 5, 5] = 1.0                  # about the board normal: well seen
    pos = np.zeros((n, 6, 6))
    pos[:, :3, :3] = np.eye(3)
    axis = target2cam[:, 2, :3]  # the camera z axis in the board frame: row 2 of R_B
    depth = np.zeros((n, 6, 6))
    depth[:, :3, :3] = axis[:, :, None] * axis[:, None, :]
    hand_comps = tuple(c for c in hand_comps if c.name != "flange_translation")
    return hand_comps + (Component("camera_tilt", "board", tilt), Component("camera_spin", "board", spin),
                         Component("position", "board", pos), Component("camera_depth", "board", depth))
