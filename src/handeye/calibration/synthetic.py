"""Synthetic hand-eye data like the paper's section 4.

A scene is an IRB 1400 with a camera at a known mount, an 8x13-corner board at a known place and a
set of postures (true controller angles) from which the camera sees the whole board at 0.7-1.2 m.
A session is drawn from a scene by adding noise:

- robot: ``N(0, sigma_rob)`` degrees on every reported joint angle (and an optional systematic
  offset per axis); the reported flange pose is the kinematics of the noisy angles;
- camera, the paper's model: each corner moves by ``N(0, sigma_cam) * U/|U|``, ``U`` uniform in
  ``[-1, 1]^3``; or plain Gaussian ``N(0, sigma_cam)`` on every coordinate.

The paper draws its 30 postures from a real session; here they are sampled from view points on a
cone above the board (eye-in-hand) or board poses in front of the fixed camera (eye-to-hand),
solved with inverse kinematics, and kept when reachable with margin and the board fully in view.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from ..geometry import STATION_BOARD, STATION_SQUARE_MM, BoardGeometry, board_corners
from ..robot import RobotModel, inverse_kinematics, load_robot
from ..robot import NOMINAL_XB3_LEFT, ViewSampling, board_visible, ik_from_standard_seeds, look_at, sample_eye_in_hand_postures
from .problem import EYE_IN_HAND, SETUPS
from .session import Posture, Session
from ..geometry import invert_transforms, pose_from_transform, transform_from_rotation_translation

__all__ = [
    "SceneConfig",
    "Scene",
    "NoiseConfig",
    "make_scene",
    "sample_session",
    "truth_dict",
    "camera_noise",
]



def _transform(rotvec_deg, translation) -> np.ndarray:
    return transform_from_rotation_translation(
        Rotation.from_rotvec(np.radians(rotvec_deg)).as_matrix(), np.asarray(translation, float))


@dataclass(frozen=True)
class SceneConfig:
    """Geometry of a synthetic station.

    Attributes
    ----------
    postures : int
    corners : tuple of int
        Inner corners along x (long side) and y.
    square_mm : float
    setup : str
    robot : str
    distance_mm : tuple of float
        Camera-to-board-centre distance range.
    cone_deg : float
        Largest tilt of the viewing direction from the board normal.
    roll_deg : float
        Largest roll about the optical axis (either way).
    aim_mm : float
        Standard deviation of the aim point around the board centre (moves the board in the image).
    seed : int
    self_clear_mm : float, optional
        Eye-in-hand: keep only postures whose arm and carried bodies (the camera and its bracket,
        ``cell.DEFAULT_CARRIED``) are this far from each other (the robot file's self-collision pairs),
        and whose joint moves from all axes at 0 and from every posture kept before stay clear of
        touching (the mock's motion supervision). None (default): not checked.
    """

    postures: int = 30
    corners: tuple = STATION_BOARD.corners
    square_mm: float = STATION_SQUARE_MM
    setup: str = EYE_IN_HAND
    robot: str = "IRB1400"
    distance_mm: tuple = (700.0, 1200.0)
    cone_deg: float = 35.0
    roll_deg: float = 40.0
    aim_mm: float = 80.0
    seed: int = 0
    self_clear_mm: float | None = None


@dataclass(frozen=True)
class Scene:
    """A synthetic station with its truth.

    Attributes
    ----------
    config : SceneConfig
    robot : RobotModel
    x_true : ndarray, shape (4, 4)
        ``cam2tool0`` (eye-in-hand) or ``cam2base`` (eye-to-hand).
    target2fixed : ndarray, shape (4, 4)
        Board in base (eye-in-hand) or in tool0 (eye-to-hand).
    joints_deg : ndarray, shape (n, 6)
        True controller angles of the postures.
    board : BoardGeometry
    """

    config: SceneConfig
    robot: RobotModel
    x_true: np.ndarray
    target2fixed: np.ndarray
    joints_deg: np.ndarray
    board: BoardGeometry

    def tool02base(self) -> np.ndarray:
        return self.robot.forward_transform(self.joints_deg)

    def target2cam(self, tool02base: np.ndarray | None = None) -> np.ndarray:
        """True board poses in the camera frame for the given (default: true) flange poses."""
        t = self.tool02base() if tool02base is None else tool02base
        if self.config.setup == EYE_IN_HAND:  # board fixed in base: target2cam = (tool02base X)^-1 target2base
            return invert_transforms(t @ self.x_true) @ self.target2fixed
        return invert_transforms(self.x_true) @ t @ self.target2fixed  # board on the flange


@dataclass(frozen=True)
class NoiseConfig:
    """Noise added when a session is drawn from a scene.

    Attributes
    ----------
    sigma_rob_deg : float
        Standard deviation of the joint-angle noise.
    sigma_cam_mm : float
        Camera noise scale (see ``camera_model``).
    camera_model : str
        ``paper`` (N(0, sigma) along a random direction U/|U|) or ``gaussian`` (per coordinate).
    joint_offset_deg : tuple of float
        Systematic offset added to every reported angle, per axis.
    seed : int
    """

    sigma_rob_deg: float = 0.0
    sigma_cam_mm: float = 0.0
    camera_model: str = "paper"
    joint_offset_deg: tuple = (0.0,) * 6
    seed: int = 0


def camera_noise(rng: np.random.Generator, shape: int | tuple[int, ...], sigma_mm: float, model: str = "paper") -> np.ndarray:
    """Noise vectors ``shape + (3,)`` for measured points.

    ``paper``: ``N(0, sigma) * U/|U|`` with ``U`` uniform in ``[-1, 1]^3`` (section 4);
    ``gaussian``: ``N(0, sigma)`` on each coordinate.
    """
    shape = tuple(np.atleast_1d(shape))
    if sigma_mm == 0:
        return np.zeros(shape + (3,))
    if model == "paper":
        u = rng.uniform(-1.0, 1.0, shape + (3,))
        u /= np.maximum(np.linalg.norm(u, axis=-1, keepdims=True), 1e-12)
        return rng.normal(0.0, sigma_mm, shape + (1,)) * u
    if model == "gaussian":
        return rng.normal(0.0, sigma_mm, shape + (3,))
    raise ValueError(f"unknown camera noise model {model!r}; use 'paper' or 'gaussian'")


def _default_geometry(config: SceneConfig):
    nx, ny = config.corners
    half = np.array([(nx - 1) * config.square_mm / 2, (ny - 1) * config.square_mm / 2, 0.0])
    if config.setup == EYE_IN_HAND:
        # A realistic XB3 mount: optical axis near tool0 z, offset by the camera body.
        x_true = _transform([2.5, -3.0, 88.0], [62.5, -118.3, 96.4])
        rot = Rotation.from_euler("xyz", [180.0, 0.0, 12.0], degrees=True).as_matrix()  # printed face up
        centre = np.array([900.0, 120.0, 80.0])
        target2fixed = transform_from_rotation_translation(rot, centre - rot @ half)
        return x_true, target2fixed, centre
    # Eye-to-hand: camera on a stand looking at the work zone; board 60 mm in front of the flange.
    camera_position = np.array([1750.0, -700.0, 1350.0])
    look = np.array([950.0, 0.0, 700.0])
    x_true = look_at(camera_position, look, np.radians(5.0))
    rot = Rotation.from_euler("x", 180.0, degrees=True).as_matrix()
    target2fixed = transform_from_rotation_translation(rot, np.array([0.0, 0.0, 60.0]) - rot @ half)
    return x_true, target2fixed, look


def _self_clear_veto(robot: RobotModel, margin_mm: float):
    """``veto(joints) -> bool`` of :attr:`SceneConfig.self_clear_mm`: True keeps the posture (and remembers it)."""
    from ..robot import DEFAULT_CARRIED
    from ..robot import CellGuard

    posture = CellGuard(robot, [], DEFAULT_CARRIED, margin_mm=margin_mm)
    moves = CellGuard(robot, [], DEFAULT_CARRIED, margin_mm=0.0, step_mm=5.0)  # as the mock supervises them
    kept = [np.zeros(robot.dof)]

    def veto(joints) -> bool:
        if posture.posture_violation(joints) is not None:
            return False
        if any(moves.path_violation(start, joints) is not None for start in kept):
            return False
        kept.append(np.asarray(joints, float))
        return True
    return veto


def make_scene(config: SceneConfig = SceneConfig()) -> Scene:
    """Sample a reachable posture set with the whole board in view (deterministic per seed).

    Raises
    ------
    RuntimeError
        If the geometry does not yield enough postures (should not happen with the defaults).
    """
    if config.setup not in SETUPS:
        raise ValueError(f"setup must be one of {', '.join(SETUPS)}")
    rng = np.random.default_rng(config.seed)
    robot = load_robot(config.robot)
    board = BoardGeometry(tuple(config.corners), config.square_mm)
    corners = board_corners(config.corners, config.square_mm)
    x_true, target2fixed, centre = _default_geometry(config)
    if config.setup == EYE_IN_HAND:
        sampling = ViewSampling(distance_mm=tuple(config.distance_mm), cone_deg=config.cone_deg,
                                roll_deg=config.roll_deg, aim_mm=config.aim_mm)
        veto = None if config.self_clear_mm is None else _self_clear_veto(robot, config.self_clear_mm)
        try:
            joints = sample_eye_in_hand_postures(robot, x_true, target2fixed, corners, config.postures, rng, sampling,
                                                 veto=veto)
        except RuntimeError as exc:
            raise RuntimeError(f"{exc} (synthetic scene)") from None
        return Scene(config, robot, x_true, target2fixed, joints, board)
    joints = []
    seed = None
    attempts = 0
    while len(joints) < config.postures:
        attempts += 1
        if attempts > 200 * config.postures:
            raise RuntimeError(f"only {len(joints)} of {config.postures} postures found; widen the geometry")
        distance = rng.uniform(*config.distance_mm)
        tilt = np.radians(config.cone_deg) * np.sqrt(rng.uniform())
        azimuth = rng.uniform(0, 2 * np.pi)
        roll = np.radians(rng.uniform(-config.roll_deg, config.roll_deg))
        aim = rng.normal(0.0, config.aim_mm, 3)
        # Eye-to-hand: the board in front of the fixed camera, facing it, tilted and turned.
        optical = x_true[:3, 2]
        board_centre = x_true[:3, 3] + distance * optical + aim * 4.0
        facing = look_at(board_centre, x_true[:3, 3], 0.0)  # z from the board towards the camera
        tilt_rot = Rotation.from_rotvec(tilt * np.array([np.cos(azimuth), np.sin(azimuth), 0.0])).as_matrix()
        spin = Rotation.from_rotvec([0.0, 0.0, roll]).as_matrix()
        # target z points away from the camera
        rot = facing[:3, :3] @ tilt_rot @ Rotation.from_euler("x", 180.0, degrees=True).as_matrix() @ spin
        half = target2fixed[:3, :3].T @ (np.array([0.0, 0.0, 60.0]) - target2fixed[:3, 3])
        target2base = transform_from_rotation_translation(rot, board_centre - rot @ half)
        tool02base = target2base @ invert_transforms(target2fixed)
        target2cam = invert_transforms(x_true) @ target2base
        if not board_visible(target2cam, corners, (NOMINAL_XB3_LEFT,)):
            continue
        if seed is None:
            found = ik_from_standard_seeds(robot, tool02base, 5.0)
        else:
            ik = inverse_kinematics(robot, tool02base, seed, margin_deg=5.0)
            found = ik.joints_deg if ik.success else ik_from_standard_seeds(robot, tool02base, 5.0)
        if found is None or np.any(np.abs(found - (seed if seed is not None else found)) > 150.0):
            continue
        seed = found if seed is None else seed
        joints.append(found)
    return Scene(config, robot, x_true, target2fixed, np.array(joints), board)


def truth_dict(scene: Scene, noise: NoiseConfig) -> dict:
    """The ``truth.yaml`` mapping of a synthetic session."""
    parent = "tool0" if scene.config.setup == EYE_IN_HAND else "base"
    fixed = "base" if scene.config.setup == EYE_IN_HAND else "tool0"
    return {
        "camera_pose": {"parent": parent, **pose_from_transform(scene.x_true)},
        "target_pose": {"parent": fixed, **pose_from_transform(scene.target2fixed)},
        "joints_true_deg": [[round(float(v), 9) for v in row] for row in scene.joints_deg],
        "scene": {"postures": scene.config.postures, "corners": list(scene.config.corners),
                  "square_mm": scene.config.square_mm, "seed": scene.config.seed, "robot": scene.robot.name},
        "noise": {"sigma_rob_deg": noise.sigma_rob_deg, "sigma_cam_mm": noise.sigma_cam_mm,
                  "camera_model": noise.camera_model, "joint_offset_deg": list(noise.joint_offset_deg),
                  "seed": noise.seed},
    }


def sample_session(scene: Scene, noise: NoiseConfig = NoiseConfig()) -> Session:
    """A session drawn from ``scene`` with ``noise`` (the scene itself is not changed)."""
    rng = np.random.default_rng(noise.seed)
    true_joints = scene.joints_deg
    target2cam = scene.target2cam()
    square_mm = scene.board.square_mm
    if square_mm is None:  # make_scene always sets it
        raise ValueError("the scene's board has no square_mm")
    corners = board_corners(scene.board.corners, square_mm)
    points = np.einsum("nij,mj->nmi", target2cam[:, :3, :3], corners) + target2cam[:, None, :3, 3]
    points = points + camera_noise(rng, points.shape[:2], noise.sigma_cam_mm, noise.camera_model)
    reported = true_joints + np.asarray(noise.joint_offset_deg, float)
    if noise.sigma_rob_deg > 0:
        reported = reported + rng.normal(0.0, noise.sigma_rob_deg, true_joints.shape)
    tool02base = scene.robot.forward_transform(reported)
    postures = [
        Posture(index=i, tool0_in_base=tool02base[i], joints_deg=reported[i], points_mm=points[i])
        for i in range(len(true_joints))
    ]
    return Session(setup=scene.config.setup, robot=scene.robot.name, target=scene.board, postures=postures)


def with_postures(config: SceneConfig, postures: int) -> SceneConfig:
    """A copy of ``config`` with another posture count."""
    return replace(config, postures=postures)
