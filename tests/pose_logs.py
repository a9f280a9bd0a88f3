"""Writers of hand-eye logs in other tools' conventions, for the import tests.

Each writer takes poses in the project's own form (mm, ``tool0_in_base`` and ``target_in_camera``)
and writes them the way another tool would: inverted if asked, in metres if asked, as Euler angles
in any of the 24 conventions, quaternions in either order, rotation vectors, matrices row- or
column-major. The import must read them back unchanged.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from handeye.calibration.compact_points import compact_points_from_corners
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.geometry.transforms import invert_transforms
from helpers import scene

#: The 24 Euler conventions as scipy names them: uppercase = rotating (intrinsic) axes, lowercase =
#: static (extrinsic) axes; 6 Tait-Bryan and 6 proper-Euler axis orders each.
_ORDERS = ["".join(p) for p in itertools.permutations("xyz")] + [a + b + a for a in "xyz" for b in "xyz" if b != a]
EULER_SEQUENCES = tuple(o.upper() for o in _ORDERS) + tuple(_ORDERS)


@dataclass(frozen=True)
class PoseConvention:
    """How a log writes a pose (the test's own description, independent of the package's readers).

    ``kind``: matrix, quaternion, rotvec or euler; ``layout``: row/column (matrix) or wxyz/xyzw
    (quaternion); ``sequence`` and ``degrees`` (euler); ``rotation_first``; ``width`` numbers.
    """

    kind: str
    layout: str = ""
    sequence: str = ""
    degrees: bool = False
    rotation_first: bool = False
    width: int = 6

    @property
    def key(self) -> str:
        """The name the package's reader gives this convention (``conventions.PoseConvention.key``)."""
        if self.kind == "euler":
            return f"euler:{self.sequence}:{'deg' if self.degrees else 'rad'}"
        if self.kind == "quaternion":
            return f"quaternion:{self.layout}" + (":first" if self.rotation_first else "")
        if self.kind == "matrix":
            return f"matrix{self.width}:{self.layout}"
        return "rotvec" + (":first" if self.rotation_first else "")


KUKA = PoseConvention("euler", sequence="ZYX", degrees=True)
FANUC = PoseConvention("euler", sequence="xyz", degrees=True)
ROS_RPY = PoseConvention("euler", sequence="xyz", degrees=False)
ROTVEC = PoseConvention("rotvec")
RVEC_TVEC = PoseConvention("rotvec", rotation_first=True)
WXYZ = PoseConvention("quaternion", "wxyz", width=7)
XYZW = PoseConvention("quaternion", "xyzw", width=7)
MATRIX16 = PoseConvention("matrix", "row", width=16)


class Truth:
    """A noisy synthetic station: the flange and board poses a real log would hold (mm) and the mount."""

    def __init__(self, setup: str, postures: int = 12, seed: int = 0, sigma_cam: float = 0.5, sigma_rob: float = 0.01):
        sc = scene(postures, setup, seed)
        session = sample_session(sc, NoiseConfig(sigma_rob_deg=sigma_rob, sigma_cam_mm=sigma_cam, seed=seed + 1))
        self.setup = setup
        self.x = sc.x_true
        self.tool0 = np.array([p.tool0_in_base for p in session.postures])
        points = np.array([p.points_mm for p in session.postures])
        self.target = compact_points_from_corners(points, sc.board).target2cam

    @property
    def n(self) -> int:
        return len(self.tool0)


def encode(poses_mm, convention: PoseConvention, unit: str = "mm", invert: bool = False) -> np.ndarray:
    """Rows of numbers ``(n, width)``: ``poses_mm`` (inverted first if asked) in ``convention`` and ``unit``."""
    poses = invert_transforms(poses_mm) if invert else np.array(poses_mm, dtype=float)
    t = poses[:, :3, 3] / (1000.0 if unit == "m" else 1.0)
    rotation = Rotation.from_matrix(poses[:, :3, :3])
    if convention.kind == "euler":
        return np.hstack([t, rotation.as_euler(convention.sequence, degrees=convention.degrees)])
    if convention.kind == "rotvec":
        r = rotation.as_rotvec()
        return np.hstack([r, t]) if convention.rotation_first else np.hstack([t, r])
    if convention.kind == "quaternion":
        q = rotation.as_quat(scalar_first=convention.layout == "wxyz")
        return np.hstack([q, t]) if convention.rotation_first else np.hstack([t, q])
    m = poses.copy()
    m[:, :3, 3] = t
    if convention.width == 16:
        return (m if convention.layout == "row" else np.transpose(m, (0, 2, 1))).reshape(len(m), 16)
    if convention.layout == "row":
        return m[:, :3, :].reshape(len(m), 12)
    return np.transpose(m[:, :3, :], (0, 2, 1)).reshape(len(m), 12)


def table_text(*columns, header=None, sep: str = ",", index: bool = False, comment: str | None = None) -> str:
    """A text table: the given blocks of columns side by side, one row per posture."""
    values = np.hstack(columns)
    lines = [f"# {comment}"] if comment else []
    if header:
        lines.append(sep.join(header))
    for k, row in enumerate(values):
        cells = [f"{v:.15g}" for v in row]
        lines.append(sep.join(([str(k)] if index else []) + cells))
    return "\n".join(lines) + "\n"


def write_json(path, robot_values, camera_values, robot_key="robot", camera_key="camera", wrap=None):
    """JSON: a list of ``{robot_key: [...], camera_key: [...]}`` (or ``wrap(robot, camera)`` items)."""
    items = [wrap(a, b) if wrap else {robot_key: a.tolist(), camera_key: b.tolist()}
             for a, b in zip(robot_values, camera_values)]
    path.write_text(json.dumps(items))
    return path


def write_yaml(path, data):
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def poses_of(session) -> tuple:
    return (np.array([p.tool0_in_base for p in session.postures]),
            np.array([p.target_in_camera for p in session.postures]))


def same_poses(session, tool0, target, tol_mm: float = 1e-6) -> bool:
    """The session holds exactly these poses (rotation matrices within 1e-9, positions within ``tol_mm``)."""
    a, b = poses_of(session)
    if a.shape != np.shape(tool0):
        return False
    return all(np.max(np.abs(p[:, :3, :3] - q[:, :3, :3])) < 1e-9 and np.max(np.abs(p[:, :3, 3] - q[:, :3, 3])) < tol_mm
               for p, q in ((a, tool0), (b, target)))
