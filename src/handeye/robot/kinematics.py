"""Forward kinematics in quaternions (paper eq. 9-12) for serial robots described by data files.

A robot is a YAML file in ``robots/`` (or anywhere, given by path) holding its standard
Denavit-Hartenberg table, the controller's joint coupling, joint limits and axis speeds. At load the
table is turned into the paper's chain: for each axis a rotation axis ``N_i`` and a displacement
``D_i`` to the next axis, both in the home (all-zero) configuration, so that (eq. 11-12)

    Q(i) = Q(i-1) * RtoQ(N_i, θ_i),     P(i) = P(i-1) + rot(Q(i), D_i),

with ``Q(0) = 1`` and ``P(0) = D_0``. The flange (tool0) orientation is ``Q(6) * Q_tool0,home``.
Controller angles (ABB convention, degrees) become serial angles through the coupling matrix: on the
IRB 1400 the serial angle of axis 3 is controller axis 3 minus controller axis 2 (parallel arm).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from ..base import parse_yaml, read_text_file
from ..geometry import canonical_quaternions, matrix_from_quaternion, quaternion_from_axis_angle, quaternion_from_matrix, quaternion_multiply, rotate_vectors
from ..geometry import transform_from_rotation_translation

__all__ = [
    "FrameBody",
    "LinkBody",
    "RobotModel",
    "load_robot",
    "robot_file",
    "known_robots",
    "dh_transforms",
    "InverseKinematicsResult",
    "inverse_kinematics",
]

ROBOTS_DIR = Path(__file__).with_name("robots")


def dh_transforms(dh_table: ArrayLike, theta_rad: ArrayLike) -> np.ndarray:
    """Standard DH link transforms ``Rz(θ) Tz(d) Tx(a) Rx(α)``.

    Parameters
    ----------
    dh_table : array-like, shape (k, 4)
        Rows ``(d_mm, a_mm, alpha_deg, theta_offset_deg)``.
    theta_rad : array-like, shape (..., k)
        Full DH angles (offset included), radians.

    Returns
    -------
    ndarray, shape (..., k, 4, 4)
    """
    dh = np.asarray(dh_table, dtype=float)
    theta = np.asarray(theta_rad, dtype=float)
    d, a, alpha = dh[:, 0], dh[:, 1], np.radians(dh[:, 2])
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out = np.zeros(theta.shape + (4, 4))
    out[..., 0, 0] = ct
    out[..., 0, 1] = -st * ca
    out[..., 0, 2] = st * sa
    out[..., 0, 3] = a * ct
    out[..., 1, 0] = st
    out[..., 1, 1] = ct * ca
    out[..., 1, 2] = -ct * sa
    out[..., 1, 3] = a * st
    out[..., 2, 1] = sa
    out[..., 2, 2] = ca
    out[..., 2, 3] = d
    out[..., 3, 3] = 1.0
    return out


@dataclass(frozen=True)
class LinkBody:
    """A capsule around part of the arm, for the cell checks (``robot.clearance``).

    Attributes
    ----------
    name : str
        How the operator reads it (``link 5``).
    start, end : int
        Points of the chain (:meth:`RobotModel.chain_points`) the capsule's axis joins: 0 on axis 1,
        ``i`` on axis ``i + 1``, ``k`` (the axis count) the tool0 origin. Both on one rigid link.
    radius_mm : float
    """

    name: str
    start: int
    end: int
    radius_mm: float


@dataclass(frozen=True)
class FrameBody:
    """A capsule fixed to one link of the arm (the base, links 1-3), for the cell and self-collision checks.

    Attributes
    ----------
    name : str
        How the operator reads it (``link 3``); several capsules may share a name (one part).
    link : int
        The part it rides on: 0 the base (never moves), ``i`` the link turned by axis ``i`` (1-based).
    start_mm, end_mm : tuple of float, shape (3,)
        The ends of its axis in base with every axis at 0 (the home posture of the dimension drawing).
    radius_mm : float
    """

    name: str
    link: int
    start_mm: tuple
    end_mm: tuple
    radius_mm: float


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A serial robot in the paper's quaternion chain form.

    Attributes
    ----------
    name : str
    base_offset : ndarray, shape (3,)
        ``D_0``: the first axis' reference point in the base frame, mm.
    axes : ndarray, shape (k, 3)
        ``N_i``: unit rotation axes in the home configuration.
    links : ndarray, shape (k, 3)
        ``D_i``: from axis i to axis i+1 (the last: to the tool0 origin), mm, home configuration.
    tool0_home : ndarray, shape (4,)
        Orientation of tool0 at home, (w, x, y, z).
    coupling : ndarray, shape (k, k)
        ``serial_angles = coupling @ controller_angles``.
    joint_limits_deg : ndarray, shape (k, 2)
    max_speed_deg_s : ndarray, shape (k,)
    dh : ndarray, shape (k, 4)
        The source table, kept for checks.
    bodies : tuple of LinkBody
        Capsules around the links the cell checks watch (the wrist end); empty when the robot file
        names none.
    link_bodies : tuple of FrameBody
        Capsules of the rest of the arm (the base, links 1-3), each fixed to one link.
    self_pairs : tuple of (str, str)
        Which bodies must keep clear of each other (``self_collision.pairs`` of the robot file): names of
        bodies, or ``carried`` for everything the flange carries. Adjacent links are left out by the file.
    """

    name: str
    base_offset: np.ndarray
    axes: np.ndarray
    links: np.ndarray
    tool0_home: np.ndarray
    coupling: np.ndarray
    joint_limits_deg: np.ndarray
    max_speed_deg_s: np.ndarray
    dh: np.ndarray
    bodies: tuple = ()
    link_bodies: tuple = ()
    self_pairs: tuple = ()

    @property
    def dof(self) -> int:
        return int(self.axes.shape[0])

    @classmethod
    def from_dh(cls, name: str, dh: ArrayLike, coupling_rows: Sequence[Sequence[float]] = (),
                joint_limits_deg: ArrayLike | None = None, max_speed_deg_s: ArrayLike | None = None,
                bodies: Sequence[LinkBody | Mapping] = (), link_bodies: Sequence[FrameBody | Mapping] = (),
                self_pairs: Sequence[Sequence[str]] = ()) -> "RobotModel":
        """Build the chain from a standard DH table (rows ``d, a, alpha_deg, theta_offset_deg``);
        ``bodies``: :class:`LinkBody` capsules, or mappings ``{name, from, to, radius_mm}``;
        ``link_bodies``: :class:`FrameBody` capsules, or mappings ``{name, link, from_mm, to_mm, radius_mm}``;
        ``self_pairs``: pairs of body names (or ``carried``), each name checked (ValueError)."""
        dh = np.asarray(dh, dtype=float)
        k = dh.shape[0]
        frames = np.eye(4)[None].repeat(k + 1, axis=0)
        links = dh_transforms(dh, np.radians(dh[:, 3]))
        for i in range(k):
            frames[i + 1] = frames[i] @ links[i]
        centres = frames[:k, :3, 3]  # axis i passes through the origin of frame i-1
        axes = frames[:k, :3, 2]
        displacements = np.diff(np.vstack([centres, frames[k, :3, 3]]), axis=0)
        coupling = np.eye(k)
        for i, j, c in coupling_rows:
            coupling[int(i) - 1, int(j) - 1] += float(c)
        limits = np.asarray(joint_limits_deg if joint_limits_deg is not None else [[-180, 180]] * k, dtype=float)
        speeds = np.asarray(max_speed_deg_s if max_speed_deg_s is not None else [100.0] * k, dtype=float)
        return cls(
            name=name,
            base_offset=centres[0].copy(),
            axes=axes / np.linalg.norm(axes, axis=1, keepdims=True),
            links=displacements,
            tool0_home=quaternion_from_matrix(frames[k, :3, :3]),
            coupling=coupling,
            joint_limits_deg=limits,
            max_speed_deg_s=speeds,
            dh=dh,
            bodies=tuple(_link_body(b, k) for b in bodies),
            link_bodies=tuple(_frame_body(b, k) for b in link_bodies),
            self_pairs=_self_pairs(self_pairs, bodies, link_bodies),
        )

    def serial_angles_rad(self, joints_deg: ArrayLike) -> np.ndarray:
        """Serial chain angles (radians) of controller angles ``(..., k)`` in degrees."""
        joints = np.asarray(joints_deg, dtype=float)
        return np.radians(np.einsum("ij,...j->...i", self.coupling, joints))

    def forward(self, joints_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """tool0 in base for controller angles, by eq. 11-12.

        Parameters
        ----------
        joints_deg : array-like, shape (..., k)
            Controller axis angles in degrees (ABB convention).

        Returns
        -------
        position_mm : ndarray, shape (..., 3)
        quaternion_wxyz : ndarray, shape (..., 4)
            ``w >= 0``.
        """
        rotations, points = self._chain(joints_deg)
        return points[..., -1, :], canonical_quaternions(quaternion_multiply(rotations[-1], self.tool0_home))

    def _chain(self, joints_deg) -> tuple[list, np.ndarray]:
        """``Q(0..k)`` (eq. 11) and ``P(0..k)`` (eq. 12) of controller angles ``(..., k)``: a list of
        ``(..., 4)`` quaternions and points ``(..., k + 1, 3)`` (mm), ``Q(0) = 1``, ``P(0) = D_0``."""
        theta = self.serial_angles_rad(joints_deg)
        lead = theta.shape[:-1]
        turns = quaternion_from_axis_angle(self.axes, theta)  # (..., k, 4): every axis at once
        rotations = [np.broadcast_to(np.array([1.0, 0.0, 0.0, 0.0]), lead + (4,))]  # Q(0), θ_0 = 0
        for i in range(self.dof):
            rotations.append(quaternion_multiply(rotations[-1], turns[..., i, :]))  # eq. 11
        # eq. 12 for every link in one rotation; the running sum adds them in the chain's order
        steps = rotate_vectors(np.stack(rotations[1:], axis=-2), self.links)
        starts = np.broadcast_to(self.base_offset, lead + (1, 3))  # P(0) = D_0
        return rotations, np.cumsum(np.concatenate([starts, steps], axis=-2), axis=-2)

    def chain_points(self, joints_deg: ArrayLike) -> np.ndarray:
        """Points of the chain in base: ``P(0)`` on axis 1 (``D_0``), ``P(i)`` on axis ``i + 1``
        (eq. 12), ``P(k)`` the tool0 origin.

        Parameters
        ----------
        joints_deg : array-like, shape (..., k)
            Controller axis angles in degrees.

        Returns
        -------
        ndarray, shape (..., k + 1, 3)
            mm.
        """
        return self._chain(joints_deg)[1]

    def link_frames(self, joints_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Where each part of the arm is: rotations ``(..., k + 1, 3, 3)`` and pivots ``(..., k + 1, 3)``.

        Part 0 is the base (identity, pivot ``P(0)``); part ``i`` the link turned by axis ``i``:
        rotation ``Q(i)`` (eq. 11) and pivot ``P(i - 1)`` on axis ``i`` (eq. 12). A point ``x`` of part
        ``i`` (given in base with every axis at 0) is at ``pivot_i + R_i (x - pivot_i,home)``.
        """
        rotations, points = self._chain(joints_deg)
        lead = points.shape[:-2]
        base = np.broadcast_to(np.eye(3), lead + (1, 3, 3))
        matrices = np.concatenate([base, matrix_from_quaternion(np.stack(rotations[1:], axis=-2))], axis=-3)
        # part 0 pivots at P(0), part i at P(i - 1) (on axis i)
        return matrices, np.concatenate([points[..., :1, :], points[..., :-1, :]], axis=-2)

    def home_pivots(self) -> np.ndarray:
        """The pivots of :meth:`link_frames` with every axis at 0: ``(k + 1, 3)``."""
        points = self.chain_points(np.zeros(self.dof))
        return np.vstack([points[:1], points[:-1]])

    def forward_transform(self, joints_deg: ArrayLike) -> np.ndarray:
        """tool02base ``(..., 4, 4)`` for controller angles ``(..., k)`` in degrees."""
        p, q = self.forward(joints_deg)
        return transform_from_rotation_translation(matrix_from_quaternion(q), p)

    def may_reach(self, position_mm: ArrayLike) -> bool:
        """False when tool0 certainly cannot be at ``position_mm``: farther from the circle the second
        axis sweeps about a vertical first axis than the rest of the arm is long. A quick test to
        skip hopeless inverse kinematics; True when it cannot tell (first axis not vertical)."""
        if not np.allclose(np.abs(self.axes[0]), [0.0, 0.0, 1.0]) or np.linalg.norm(self.base_offset[:2]) > 1e-9:
            return True
        shoulder = self.base_offset + self.links[0]
        radius = np.linalg.norm(shoulder[:2])
        reach = float(np.sum(np.linalg.norm(self.links[1:], axis=1)))
        p = np.asarray(position_mm, float)
        gap = np.hypot(np.linalg.norm(p[:2]) - radius, p[2] - shoulder[2])
        return bool(gap <= reach)

    def within_limits(self, joints_deg: ArrayLike, margin_deg: float = 0.0) -> np.ndarray:
        """True where every axis is inside its limits shrunk by ``margin_deg``; shape ``(...)``."""
        joints = np.asarray(joints_deg, dtype=float)
        low = self.joint_limits_deg[:, 0] + margin_deg
        high = self.joint_limits_deg[:, 1] - margin_deg
        return np.all((joints >= low) & (joints <= high), axis=-1)

    def limit_violations(self, joints_deg: ArrayLike, margin_deg: float = 0.0) -> list[str]:
        """Readable list of the axes of one posture outside their limits (empty when inside)."""
        joints = np.asarray(joints_deg, dtype=float)
        out = []
        for axis, (value, (low, high)) in enumerate(zip(joints, self.joint_limits_deg), start=1):
            if not np.isfinite(value):
                out.append(f"axis {axis} is {value}")
            elif value < low + margin_deg or value > high - margin_deg:
                out.append(f"axis {axis} = {value:.4f} deg outside [{low + margin_deg:g}, {high - margin_deg:g}]")
        return out


def _link_body(body, dof: int) -> LinkBody:
    """A :class:`LinkBody` from itself or a robot file's mapping ``{name, from, to, radius_mm}``."""
    if not isinstance(body, LinkBody):
        body = LinkBody(str(body["name"]), int(body["from"]), int(body["to"]), float(body["radius_mm"]))
    if not (0 <= body.start <= dof and 0 <= body.end <= dof and body.radius_mm > 0):
        raise ValueError(f"body {body.name!r}: chain points must be 0..{dof} and the radius > 0")
    return body


def _frame_body(body, dof: int) -> FrameBody:
    """A :class:`FrameBody` from itself or a mapping ``{name, link, from_mm, to_mm, radius_mm}``."""
    if not isinstance(body, FrameBody):
        body = FrameBody(str(body["name"]), int(body["link"]), tuple(float(v) for v in body["from_mm"]),
                         tuple(float(v) for v in body["to_mm"]), float(body["radius_mm"]))
    if not (0 <= body.link <= dof and len(body.start_mm) == 3 and len(body.end_mm) == 3 and body.radius_mm > 0):
        raise ValueError(f"link body {body.name!r}: link must be 0..{dof}, from_mm and to_mm 3 numbers, radius > 0")
    return body


#: The word of ``self_collision.pairs`` for everything the flange carries (the camera, its bracket, a cable).
CARRIED = "carried"


def _self_pairs(pairs, bodies, link_bodies) -> tuple:
    """``self_collision.pairs`` as ``((a, b), ...)``; a name that is no body of the file (nor ``carried``)
    or a body paired with itself is refused (ValueError), never dropped."""
    names = {str(b.name if hasattr(b, "name") else b["name"]) for b in (*bodies, *link_bodies)}
    out = []
    for pair in pairs:
        if isinstance(pair, str) or len(pair) != 2:
            raise ValueError(f"self_collision.pairs: each entry is [body, body]; got {pair!r}")
        a, b = (str(n) for n in pair)
        for name in (a, b):
            if name not in names and name != CARRIED:
                raise ValueError(f"self_collision.pairs names {name!r}, which is no body of the robot file "
                                 f"(bodies: {', '.join(sorted(names))}, or {CARRIED!r})")
        if a == b:
            raise ValueError(f"self_collision.pairs pairs {a!r} with itself")
        out.append((a, b))
    return tuple(out)


def _normalise_name(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch.isalnum())


@lru_cache(maxsize=None)
def _robot_files() -> dict:
    table = {}
    for path in sorted(ROBOTS_DIR.glob("*.yaml")):
        data = parse_yaml(read_text_file(path, "robot file", ValueError), path, ValueError)
        for name in [data["name"], *data.get("aliases", [])]:
            table[_normalise_name(name)] = path
    return table


def known_robots() -> list[str]:
    """Names of the robot models shipped with the package."""
    return sorted({_load_path(p).name for p in set(_robot_files().values())})


@lru_cache(maxsize=None)
def _load_path(path: Path) -> RobotModel:
    data = parse_yaml(read_text_file(path, "robot file", ValueError), path, ValueError)
    try:
        return RobotModel.from_dh(
            data["name"],
            data["dh"],
            data.get("coupling", ()),
            data.get("joint_limits_deg"),
            data.get("max_speed_deg_s"),
            data.get("bodies", ()),
            data.get("link_bodies", ()),
            (data.get("self_collision") or {}).get("pairs", ()),
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ValueError(f"robot file {path} is not a valid robot model: {exc}") from None


def robot_file(name_or_path: str) -> Path | None:
    """The YAML file of a robot named (``IRB1400``, a shipped file's name or alias) or given by its path
    (``.yaml``/``.yml``), or None when there is none."""
    key = _normalise_name(str(name_or_path))
    files = _robot_files()
    if key in files:
        return files[key]
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") and path.is_file():
        return path.resolve()
    return None


def load_robot(name_or_path: str) -> RobotModel:
    """A robot model by name (``IRB1400``) or by the path of a YAML file of the same layout.

    Raises
    ------
    ValueError
        If the name is unknown and no such file exists.
    """
    path = robot_file(name_or_path)
    if path is not None:
        return _load_path(path)
    raise ValueError(f"unknown robot model {name_or_path!r}; known: {', '.join(known_robots())} (or a path to a robot YAML file)")


@dataclass(frozen=True)
class InverseKinematicsResult:
    """Numerical inverse kinematics for one pose.

    Attributes
    ----------
    joints_deg : ndarray, shape (k,)
    success : bool
        Position within ``tolerance_mm`` and orientation within ``tolerance_deg``, limits respected.
    position_error_mm, rotation_error_deg : float
    """

    joints_deg: np.ndarray
    success: bool
    position_error_mm: float
    rotation_error_deg: float


#: Relative forward-difference step of the inverse kinematics' Jacobian (scipy's default for '2-point').
_FD_STEP = float(np.finfo(float).eps ** 0.5)


def inverse_kinematics(
    robot: RobotModel,
    tool02base: ArrayLike,
    seed_deg: ArrayLike,
    margin_deg: float = 0.0,
    tolerance_mm: float = 1e-3,
    tolerance_deg: float = 1e-4,
) -> InverseKinematicsResult:
    """Controller angles that put tool0 at ``tool02base``, found from ``seed_deg`` by least squares.

    The configuration found is the one nearest the seed (the solver does not switch arm, elbow or
    wrist configuration by itself). Angles stay inside the joint limits shrunk by ``margin_deg``.

    Parameters
    ----------
    robot : RobotModel
    tool02base : array-like, shape (4, 4)
    seed_deg : array-like, shape (k,)
    """
    target = np.asarray(tool02base, dtype=float)
    target_inverse = Rotation.from_matrix(target[:3, :3]).inv()
    lever_mm = 500.0  # weights orientation like a position error at half a metre

    def residuals(joints):
        """Pose error ``(..., 6)`` of controller angles ``(..., k)``: mm, and lever x rotation vector."""
        p, q = robot.forward(joints)
        rot_err = (target_inverse * Rotation.from_quat(np.reshape(q, (-1, 4)), scalar_first=True)).as_rotvec()
        return np.concatenate([p - target[:3, 3], lever_mm * rot_err.reshape(p.shape)], axis=-1)

    low = robot.joint_limits_deg[:, 0] + margin_deg
    high = robot.joint_limits_deg[:, 1] - margin_deg

    def jacobian(joints):
        # scipy's forward differences ('2-point': step sqrt(eps) * max(1, |x|), turned back at a
        # bound), all k steps through one batched forward kinematics instead of k calls
        step = _FD_STEP * np.maximum(1.0, np.abs(joints)) * np.where(joints >= 0, 1.0, -1.0)
        step = np.where((joints + step > high) | (joints + step < low), -step, step)
        moved = residuals(np.vstack([joints, joints + np.diag(step)]))
        return ((moved[1:] - moved[0]) / step[:, None]).T

    seed = np.clip(np.asarray(seed_deg, dtype=float), low + 1e-9, high - 1e-9)
    fit = least_squares(residuals, seed, jac=jacobian, bounds=(low, high), x_scale=1.0, xtol=1e-12, ftol=1e-12,  # pyright: ignore[reportArgumentType]
                        gtol=1e-12, max_nfev=100)
    r = residuals(fit.x)
    pos_err = float(np.linalg.norm(r[:3]))
    rot_err = float(np.degrees(np.linalg.norm(r[3:]) / lever_mm))
    ok = pos_err <= tolerance_mm and rot_err <= tolerance_deg
    return InverseKinematicsResult(fit.x, ok, pos_err, rot_err)
