"""Synthetic pose pairs drawn like OpenCV's own hand-eye test (pose noise instead of point noise).

OpenCV's ``modules/calib3d/test/test_calibration_hand_eye.cpp`` (``simulateData``) draws random
poses, in metres there and in millimetres here:

- ``cam2gripper``: rotation vector ``θ u`` with ``θ`` uniform in 10-50 deg and ``u`` uniform in
  ``[-1, 1]^3`` (not normalised, so the angle is ``θ |u|``), translation components uniform in
  50-500 mm, every sign random;
- ``target2base``: the same with 5-85 deg and 500-3500 mm;
- per pose ``gripper2base``: 5-45 deg and 500-1500 mm; ``target2cam`` follows;
- noise: ``N(0, 0.002 rad)`` on each rotation-vector component and ``N(0, 5 mm)`` on each
  translation component of ``target2cam``; ``N(0, 0.001 rad)`` and ``N(0, 1 mm)`` on
  ``gripper2base``.

In OpenCV's file the gripper noise is written into a copy of the pose that is never handed to the
solver, so its robot poses are in fact exact; here both noises are applied (``robot_noise=False``
reproduces OpenCV's data exactly in distribution).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .compact_points import compact_points_from_poses
from .problem import EYE_IN_HAND, HandEyeProblem
from ..geometry import invert_transforms, transform_from_rotation_translation

__all__ = ["OPENCV_TEST_NOISE", "random_pose", "opencv_test_problem"]

#: (target2cam rotation rad, target2cam translation mm, gripper2base rotation rad, gripper2base translation mm)
OPENCV_TEST_NOISE = (0.002, 5.0, 0.001, 1.0)


def random_pose(rng: np.random.Generator, theta_deg: tuple[float, float], t_mm: tuple[float, float]) -> np.ndarray:
    """One pose as OpenCV's ``generatePose`` with random signs; ``theta_deg``, ``t_mm``: (low, high)."""
    axis = rng.uniform(-1.0, 1.0, 3)
    theta = np.radians(rng.uniform(*theta_deg)) * np.sign(rng.uniform(-1.0, 1.0))
    t = rng.uniform(*t_mm, 3) * np.sign(rng.uniform(-1.0, 1.0, 3))
    return transform_from_rotation_translation(Rotation.from_rotvec(theta * axis).as_matrix(), t)


def _noisy(rng, pose, sigma_rad, sigma_mm) -> np.ndarray:
    rotvec = Rotation.from_matrix(pose[:3, :3]).as_rotvec() + rng.normal(0.0, sigma_rad, 3)
    return transform_from_rotation_translation(Rotation.from_rotvec(rotvec).as_matrix(),
                                               pose[:3, 3] + rng.normal(0.0, sigma_mm, 3))


def opencv_test_problem(rng: np.random.Generator, poses: int = 10, noise: tuple[float, float, float, float] | None = OPENCV_TEST_NOISE,
                        robot_noise: bool = True) -> tuple[HandEyeProblem, dict]:
    """An eye-in-hand problem of board poses only, drawn as OpenCV's test does.

    Parameters
    ----------
    rng : numpy.random.Generator
    poses : int
    noise : tuple of float or None
        :data:`OPENCV_TEST_NOISE` or ``None`` for exact data.
    robot_noise : bool
        Apply the gripper2base noise (OpenCV's file does not, see the module docstring).

    Returns
    -------
    problem : HandEyeProblem
        Board poses with the compact points origin, (L, 0, 0), (0, L, 0), L = 100 mm.
    truth : dict
        ``{'x': cam2gripper, 'target2fixed': target2base}``.
    """
    cam2gripper = random_pose(rng, (10.0, 50.0), (50.0, 500.0))
    target2base = random_pose(rng, (5.0, 85.0), (500.0, 3500.0))
    hand, boards = [], []
    for _ in range(poses):
        gripper2base = random_pose(rng, (5.0, 45.0), (500.0, 1500.0))
        target2cam = invert_transforms(cam2gripper) @ invert_transforms(gripper2base) @ target2base
        if noise is not None:
            target2cam = _noisy(rng, target2cam, noise[0], noise[1])
            if robot_noise:
                gripper2base = _noisy(rng, gripper2base, noise[2], noise[3])
        hand.append(gripper2base)
        boards.append(target2cam)
    compact = compact_points_from_poses(np.array(boards), 100.0)
    problem = HandEyeProblem(EYE_IN_HAND, np.array(hand), compact, compact.points, np.arange(poses),
                             compact.target_points)
    return problem, {"x": cam2gripper, "target2fixed": target2base}
