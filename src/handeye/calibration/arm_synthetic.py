"""Synthetic sessions from an arm that is not its DH table: a truth for the kinematic identification.

The controller reports the joints and the NOMINAL flange pose (its own model); the camera sees the
board from the TRUE flange (the table changed by known deviations, ``arm_parameters`` order), its
corners triangulated by the XB3 pair with ``sigma_px`` of pixel noise (``noise.stereo_point_shape``:
far noisier in depth than sideways); the joints carry ``sigma_joint_deg`` of repeatability.
"""

from __future__ import annotations

import numpy as np

from .arm_parameters import corrected_robot
from ..geometry import board_corners
from .noise import stereo_point_shape
from .session import Posture, Session
from .synthetic import Scene
from ..geometry import invert_transforms

__all__ = ["deviated_session", "random_deviation"]


def random_deviation(rng: np.random.Generator, zero_deg: float = 0.05, link_mm: float = 0.3, dof: int = 6,
                     axes=(2, 3, 4, 5), links=("a1", "a2", "a3", "d4")) -> np.ndarray:
    """Deviations ``(4 dof,)`` uniform in ``±zero_deg`` on the zeros of ``axes`` and ``±link_mm`` on ``links``."""
    from .arm_parameters import parameter_names  # noqa: PLC0415

    names = parameter_names(dof)
    values = np.zeros(len(names))
    for axis in axes:
        values[names.index(f"zero{axis}")] = rng.uniform(-zero_deg, zero_deg)
    for name in links:
        values[names.index(name)] = rng.uniform(-link_mm, link_mm)
    return values


def deviated_session(scene: Scene, deviation, sigma_px: float = 0.1, sigma_joint_deg: float = 0.002,
                     seed: int = 0, joints_deg=None) -> Session:
    """A session of ``scene`` (eye-in-hand) whose true arm differs from the nominal by ``deviation``.

    Parameters
    ----------
    scene : Scene
    deviation : array-like, shape (4 dof,)
        ``arm_parameters.parameter_names`` order (mm, deg).
    sigma_px : float
        Pixel noise of the stereo pair (the corners' covariance follows from it).
    sigma_joint_deg : float
        Repeatability: the arm stands this far (one sigma, per axis) from its reported angles.
    joints_deg : array-like, shape (n, k), optional
        Postures (default: the scene's).
    """
    rng = np.random.default_rng(seed)
    joints = scene.joints_deg if joints_deg is None else np.asarray(joints_deg, float)
    true_arm = corrected_robot(scene.robot, deviation)
    standing = joints + rng.normal(0.0, sigma_joint_deg, joints.shape)
    cam2base = true_arm.forward_transform(standing) @ scene.x_true
    target2cam = invert_transforms(cam2base) @ scene.target2fixed
    if scene.board.square_mm is None:
        raise ValueError("a synthetic scene's board needs its square size")
    corners = board_corners(scene.board.corners, scene.board.square_mm)
    points = np.einsum("nij,mj->nmi", target2cam[:, :3, :3], corners) + target2cam[:, None, :3, 3]
    shape = stereo_point_shape(points) * sigma_px ** 2
    chol = np.linalg.cholesky(shape + 1e-12 * np.eye(3))
    points = points + (chol @ rng.normal(size=points.shape + (1,)))[..., 0]
    reported = scene.robot.forward_transform(joints)
    postures = [Posture(index=i, tool0_in_base=reported[i], joints_deg=joints[i], points_mm=points[i])
                for i in range(len(joints))]
    return Session(setup="eye_in_hand", robot=scene.robot.name, target=scene.board, postures=postures)
