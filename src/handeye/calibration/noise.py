"""Measurement noise of a hand-eye session: what the maximum-likelihood estimator (``eiv/``) weighs by.

Rigid-motion perturbations. A pose ``P = (R, t)`` perturbed by a twist ``ξ = (ρ, φ)`` (mm, rad)
expressed in its own (local) frame is

    P ⊕ ξ = (R exp([φ]x), t + R ρ),

and ``Ad_P = [[R, [t]x R], [0, R]]`` carries a local twist into the parent frame to first order
(``(P ⊕ ξ) P^-1 ≈ I ⊕ Ad_P ξ``).

Camera. Board corners triangulated by a rectified stereo pair (focal length ``f`` px, baseline
``B`` mm, the right camera at ``+x``) carry pixel noise into 3D very unevenly: with
``X = B (u_l - c_x) / d``, ``Y = B (v - c_y) / d``, ``Z = f B / d`` and ``d = u_l - u_r``, a point at
depth ``Z`` moves ``Z / f`` mm per pixel sideways but ``Z^2 / (f B)`` mm per pixel of disparity
along its ray, four times more at 1 m for the XB3 wide pair (``f`` = 983 px, ``B`` = 239.98 mm).
A corner's covariance is modelled as two variance components,

    Σ_p = a I + b S_p,      S_p = J_p diag(1, 1, 1/2) J_p^T        (pixel noise b in px²)

(``J_p`` the Jacobian of the triangulation in ``(u_l, u_r, v)``, ``v`` the mean of both rows), the
isotropic part ``a`` (mm²) covering everything that is not stereo geometry (e.g. the paper's noise
model, section 4). Both are estimated from the residuals of each posture's rigid board fit, which
the robot cannot influence: ``n (3m - 6)`` degrees of freedom for ``n`` postures of ``m`` corners.

The board pose of each posture is fitted to its corners by weighted least squares; the inverse of
its normal matrix is the covariance of the pose (a local twist of ``target2cam``). When a session
holds board poses only, their covariance is estimated with the robot's (``eiv/``).

Robot. A joint-angle error ``δq`` (controller angles, degrees) moves the flange by the local twist
``J_q δq`` (the flange Jacobian below, from the kinematics of eq. 11-12), so joint noise of
variance ``σ_q²`` gives the flange pose the covariance ``σ_q² J_q J_q^T``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..robot import RobotModel
from ..geometry import quaternion_from_axis_angle, quaternion_multiply, rotate_vectors, skew

__all__ = [
    "XB3_FOCAL_PX",
    "XB3_BASELINE_MM",
    "skew",
    "adjoint",
    "retract",
    "twist_between",
    "matrix_from_rotvec",
    "rotvec_from_matrix",
    "stereo_point_shape",
    "BoardFit",
    "fit_board_poses",
    "CornerNoise",
    "shape_eigen",
    "corner_noise",
    "inverse_covariances",
    "flange_jacobian",
    "kinematic_jacobian",
]

#: The nominal rectified XB3 wide pair (shared/reference/bumblebee-xb3.md).
XB3_FOCAL_PX = 983.0
XB3_BASELINE_MM = 239.98
#: Floor of every variance (mm², px²): noise-free data stay finite.
VARIANCE_FLOOR = 1e-18


def adjoint(transform: ArrayLike) -> np.ndarray:
    """``Ad_P = [[R, [t]x R], [0, R]]`` of poses ``(..., 4, 4)``: shape ``(..., 6, 6)``, twists ``(ρ, φ)``."""
    p = np.asarray(transform, dtype=float)
    r, t = p[..., :3, :3], p[..., :3, 3]
    out = np.zeros(p.shape[:-2] + (6, 6))
    out[..., :3, :3] = r
    out[..., :3, 3:] = skew(t) @ r
    out[..., 3:, 3:] = r
    return out


def retract(transform: ArrayLike, twist: ArrayLike) -> np.ndarray:
    """``P ⊕ ξ = (R exp([φ]x), t + R ρ)`` for poses ``(..., 4, 4)`` and local twists ``(..., 6)``."""
    p = np.asarray(transform, dtype=float)
    xi = np.asarray(twist, dtype=float)
    lead = np.broadcast_shapes(p.shape[:-2], xi.shape[:-1])
    p = np.broadcast_to(p, lead + (4, 4))
    xi = np.broadcast_to(xi, lead + (6,))
    out = np.zeros(lead + (4, 4))
    out[..., :3, :3] = p[..., :3, :3] @ matrix_from_rotvec(xi[..., 3:])
    out[..., :3, 3] = p[..., :3, 3] + (p[..., :3, :3] @ xi[..., :3, None])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def twist_between(reference: ArrayLike, transform: ArrayLike) -> np.ndarray:
    """The local twist ``ξ`` with ``transform = reference ⊕ ξ`` (exact inverse of :func:`retract`).

    Parameters
    ----------
    reference, transform : array-like, shape (..., 4, 4)

    Returns
    -------
    ndarray, shape (..., 6)
        ``(R_ref^T (t - t_ref), rotvec(R_ref^T R))``.
    """
    a = np.asarray(reference, dtype=float)
    b = np.asarray(transform, dtype=float)
    lead = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    a = np.broadcast_to(a, lead + (4, 4))
    b = np.broadcast_to(b, lead + (4, 4))
    rt = np.swapaxes(a[..., :3, :3], -1, -2)
    out = np.empty(lead + (6,))
    out[..., :3] = (rt @ (b[..., :3, 3] - a[..., :3, 3])[..., None])[..., 0]
    out[..., 3:] = rotvec_from_matrix(rt @ b[..., :3, :3])
    return out


def matrix_from_rotvec(rotvec: ArrayLike) -> np.ndarray:
    """Rodrigues' formula for rotation vectors ``(..., 3)`` (radians): matrices ``(..., 3, 3)``."""
    v = np.asarray(rotvec, dtype=float)
    angle = np.linalg.norm(v, axis=-1)[..., None, None]
    small = angle < 1e-4
    a2 = angle * angle
    safe = np.where(small, 1.0, angle)
    sin_term = np.where(small, 1.0 - a2 / 6.0, np.sin(safe) / safe)
    cos_term = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(safe)) / np.where(small, 1.0, a2))
    k = skew(v)
    return np.eye(3) + sin_term * k + cos_term * (k @ k)


def rotvec_from_matrix(matrix: ArrayLike) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` of rotation matrices ``(..., 3, 3)`` (scipy near a half turn)."""
    r = np.asarray(matrix, dtype=float)
    cos = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1.0) * 0.5, -1.0, 1.0)
    angle = np.arccos(cos)
    v = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], axis=-1)
    small = angle < 1e-4
    factor = np.where(small, 0.5 + angle * angle / 12.0, angle / (2.0 * np.sin(np.where(small, 1.0, angle))))
    out = v * factor[..., None]
    near_pi = angle > 3.0
    if np.any(near_pi):
        out[near_pi] = Rotation.from_matrix(np.array(r[near_pi])).as_rotvec()
    return out


def stereo_point_shape(points_cam: ArrayLike, f_px: float = XB3_FOCAL_PX, baseline_mm: float = XB3_BASELINE_MM) -> np.ndarray:
    """Covariance ``S_p`` (mm² per px² of pixel noise) of points triangulated by a rectified pair.

    Parameters
    ----------
    points_cam : array-like, shape (..., 3)
        Points in the left (reference) camera frame, mm, ``Z > 0``.
    f_px, baseline_mm : float
        Rectified focal length and baseline (right camera at ``+x``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``J diag(1, 1, 1/2) J^T`` with ``J = (Z/f) [[1 - X/B, X/B, 0], [-Y/B, Y/B, 1], [-Z/B, Z/B, 0]]``
        the Jacobian of ``(X, Y, Z)`` in ``(u_l, u_r, v)``; ``v``, the mean of the two rows, has half
        the variance of one row.
    """
    p = np.asarray(points_cam, dtype=float)
    z = np.maximum(p[..., 2], 1e-6)
    jac = np.zeros(p.shape[:-1] + (3, 3))
    ratio = p / baseline_mm
    jac[..., 0, 0], jac[..., 0, 1] = 1.0 - ratio[..., 0], ratio[..., 0]
    jac[..., 1, 0], jac[..., 1, 1], jac[..., 1, 2] = -ratio[..., 1], ratio[..., 1], 1.0
    jac[..., 2, 0], jac[..., 2, 1] = -ratio[..., 2], ratio[..., 2]
    jac *= (z / f_px)[..., None, None]
    scaled = jac * np.array([1.0, 1.0, np.sqrt(0.5)])
    return scaled @ np.swapaxes(scaled, -1, -2)


@dataclass(frozen=True)
class BoardFit:
    """Board poses fitted to measured points, with their covariance.

    Attributes
    ----------
    target2cam : ndarray, shape (n, 4, 4)
    residuals : ndarray, shape (n, m, 3)
        Measured minus fitted points, mm.
    information : ndarray, shape (n, 6, 6)
        ``sum_p J_p^T Σ_p^-1 J_p`` of the local twist of ``target2cam``; its inverse is the pose covariance.
    """

    target2cam: np.ndarray
    residuals: np.ndarray
    information: np.ndarray


def fit_board_poses(points_cam: ArrayLike, model_points: ArrayLike, start: ArrayLike, weights: ArrayLike | None = None, iterations: int = 3) -> BoardFit:
    """Weighted least-squares rigid fit of a known board to measured points, every posture at once.

    Parameters
    ----------
    points_cam : array-like, shape (n, m, 3)
        Measured points in the camera frame, mm.
    model_points : array-like, shape (m, 3)
        The same points in the target frame.
    start : array-like, shape (n, 4, 4)
        Start poses ``target2cam`` (e.g. the plane fit of ``compact_points``).
    weights : array-like, shape (n, m, 3, 3), optional
        Inverse covariance of each point (``None``: identity).
    iterations : int
        Gauss-Newton steps (the start is within noise of the answer: 2-3 are plenty).
    """
    y = np.asarray(points_cam, dtype=float)
    g = np.asarray(model_points, dtype=float)
    pose = np.array(start, dtype=float)
    n, m, _ = y.shape
    w = np.broadcast_to(np.eye(3), (n, m, 3, 3)) if weights is None else np.asarray(weights, dtype=float)
    local = np.zeros((m, 3, 6))  # d(R (g + ρ + φ x g)) / dξ = R [I, -[g]x]
    local[:, :, :3] = np.eye(3)
    local[:, :, 3:] = -skew(g)
    info = np.zeros((n, 6, 6))
    for _ in range(max(iterations, 1)):
        rot = pose[:, :3, :3]
        residual = y - (g @ np.swapaxes(rot, 1, 2) + pose[:, None, :3, 3])
        jac = (rot[:, None] @ local).reshape(n, 3 * m, 6)  # (n, 3m, 6)
        wj = (w @ jac.reshape(n, m, 3, 6)).reshape(n, 3 * m, 6)
        info = np.swapaxes(jac, 1, 2) @ wj
        grad = (np.swapaxes(wj, 1, 2) @ residual.reshape(n, 3 * m, 1))[..., 0]
        step = np.linalg.solve(info + 1e-12 * np.eye(6), grad[..., None])[..., 0]
        pose = retract(pose, step)
    predicted = g @ np.swapaxes(pose[:, :3, :3], 1, 2) + pose[:, None, :3, 3]
    return BoardFit(pose, y - predicted, info)


@dataclass(frozen=True)
class CornerNoise:
    """Variance components of the corner noise, estimated from board-fit residuals.

    Attributes
    ----------
    isotropic_mm2 : float
        ``a``: variance per coordinate of the isotropic part, mm².
    pixel_px2 : float
        ``b``: pixel variance of the stereo part, px².
    dof : int
        Degrees of freedom behind the estimate, ``n (3m - 6)``.
    """

    isotropic_mm2: float
    pixel_px2: float
    dof: int

    def covariances(self, shapes: np.ndarray) -> np.ndarray:
        """``a I + b S_p`` for stereo shapes ``(..., 3, 3)``."""
        return self.isotropic_mm2 * np.eye(3) + self.pixel_px2 * shapes

    def rms_mm(self, shapes: np.ndarray) -> float:
        """RMS length of a corner's error vector, mm (over the given points)."""
        return float(np.sqrt(np.mean(np.trace(self.covariances(shapes), axis1=-2, axis2=-1))))


def shape_eigen(shapes: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition ``S_p = U diag(λ) U^T`` of stereo shapes ``(..., 3, 3)``: ``λ (..., 3)``, ``U (..., 3, 3)``."""
    lam, vec = np.linalg.eigh(np.asarray(shapes, dtype=float))
    return np.maximum(lam, 0.0), vec


def corner_noise(residuals: ArrayLike, eigen: tuple[np.ndarray, np.ndarray], iterations: int = 30, seen: ArrayLike | None = None) -> CornerNoise:
    """REML-type estimate of ``(a, b)`` in ``Σ_p = a I + b S_p`` from board-fit residuals (Fisher scoring).

    Parameters
    ----------
    residuals : array-like, shape (n, m, 3)
        Residuals of the rigid board fit (6 parameters per posture absorbed).
    eigen : tuple of ndarray
        :func:`shape_eigen` of the stereo shapes ``S_p`` (:func:`stereo_point_shape`), ``(n, m, 3)``
        and ``(n, m, 3, 3)``.

    Notes
    -----
    In the eigenbasis of ``S_p = U diag(λ) U^T`` every ``Σ_p`` is diagonal, ``v_j = a + b λ_j``. For
    Gaussian residuals the score of component ``k`` is ``½ sum (e_j^2 / v_j^2 - c / v_j) g_kj`` and the
    Fisher information ``½ c sum g_kj g_lj / v_j^2`` with ``g_0 = 1``, ``g_1 = λ``; ``c = (3m - 6) / 3m``
    accounts for the six pose parameters each posture's fit absorbed (REML-like), so the estimate is
    not biased low. ``seen`` (bool ``(n, m)``, partial views of a ChArUco board) leaves the corners a
    view did not see out of every sum; ``c`` then counts the seen corners.
    """
    e = np.asarray(residuals, dtype=float)
    lam, vec = eigen
    n, m, _ = e.shape
    if seen is not None:
        return _masked_corner_noise(e, lam, vec, np.asarray(seen, bool), iterations)
    dof = max(n * (3 * m - 6), 1)
    c = dof / float(n * 3 * m)
    e2 = np.einsum("nmij,nmi->nmj", vec, e) ** 2  # squared residuals in the eigenbasis
    mean_sq = float(np.mean(e2)) / c
    scale_s = float(np.mean(lam))
    if mean_sq <= VARIANCE_FLOOR or scale_s <= 0:
        return CornerNoise(max(mean_sq, VARIANCE_FLOOR), VARIANCE_FLOOR, int(dof))
    theta = np.array([0.5 * mean_sq, 0.5 * mean_sq / scale_s])
    g = np.stack([np.ones_like(lam), lam])  # (2, n, m, 3)
    for _ in range(iterations):
        v = theta[0] + theta[1] * lam
        score = 0.5 * np.einsum("knmj,nmj->k", g, e2 / v**2 - c / v)
        fisher = 0.5 * c * np.einsum("knmj,lnmj,nmj->kl", g, g, 1.0 / v**2)
        new = np.maximum(theta + np.linalg.solve(fisher, score), VARIANCE_FLOOR)
        done = np.all(np.abs(new - theta) <= 1e-6 * np.maximum(theta, VARIANCE_FLOOR))
        theta = new
        if done:
            break
    return CornerNoise(float(theta[0]), float(theta[1]), int(dof))


def _masked_corner_noise(e, lam, vec, seen, iterations: int) -> CornerNoise:
    """:func:`corner_noise` over the seen corners only (``seen`` ``(n, m)``)."""
    count = seen.sum(axis=1)
    dof = max(int(np.sum(np.maximum(3 * count - 6, 0))), 1)
    total = max(3 * int(count.sum()), 1)
    c = dof / float(total)
    w = np.broadcast_to(seen[..., None], lam.shape).astype(float)
    e2 = np.einsum("nmij,nmi->nmj", vec, e) ** 2 * w
    mean_sq = float(e2.sum() / total) / c
    scale_s = float((lam * w).sum() / total)
    if mean_sq <= VARIANCE_FLOOR or scale_s <= 0:
        return CornerNoise(max(mean_sq, VARIANCE_FLOOR), VARIANCE_FLOOR, int(dof))
    theta = np.array([0.5 * mean_sq, 0.5 * mean_sq / scale_s])
    g = np.stack([np.ones_like(lam), lam])
    for _ in range(iterations):
        v = theta[0] + theta[1] * lam
        score = 0.5 * np.einsum("knmj,nmj->k", g, w * (e2 / v**2 - c / v))
        fisher = 0.5 * c * np.einsum("knmj,lnmj,nmj->kl", g, g, w / v**2)
        new = np.maximum(theta + np.linalg.solve(fisher, score), VARIANCE_FLOOR)
        done = np.all(np.abs(new - theta) <= 1e-6 * np.maximum(theta, VARIANCE_FLOOR))
        theta = new
        if done:
            break
    return CornerNoise(float(theta[0]), float(theta[1]), int(dof))


def inverse_covariances(noise: CornerNoise, eigen: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """``(a I + b S_p)^-1`` from :func:`shape_eigen` of the shapes; shape ``(..., 3, 3)``."""
    lam, vec = eigen
    inv = 1.0 / (noise.isotropic_mm2 + noise.pixel_px2 * lam)
    return np.einsum("...ik,...k,...jk->...ij", vec, inv, vec)


def flange_jacobian(robot: RobotModel, joints_deg: np.ndarray) -> np.ndarray:
    """Local twist of tool0 per degree of each controller angle, from the chain of eq. 11-12.

    Parameters
    ----------
    robot : RobotModel
    joints_deg : array-like, shape (n, k)
        Controller angles (degrees).

    Returns
    -------
    ndarray, shape (n, 6, k)
        Column ``j``: ``(ρ, φ)`` in the flange frame when controller angle ``j`` grows by one degree.
        Axis ``i`` of the chain passes through ``P(i-1)`` along ``rot(Q(i-1), N_i)`` (eq. 11-12);
        turning it by ``δθ`` turns the flange by ``w δθ`` and moves its origin by ``w x (p_flange - P(i-1)) δθ``.
    """
    theta = robot.serial_angles_rad(joints_deg)  # coupling applied
    lead = theta.shape[:-1]
    q = np.broadcast_to(np.array([1.0, 0.0, 0.0, 0.0]), lead + (4,))
    p = np.broadcast_to(robot.base_offset, lead + (3,))
    axes_world, points = [], []
    for i in range(robot.dof):
        axes_world.append(rotate_vectors(q, robot.axes[i]))  # rot(Q(i-1), N_i)
        points.append(p)
        q = quaternion_multiply(q, quaternion_from_axis_angle(robot.axes[i], theta[..., i]))  # eq. 11
        p = p + rotate_vectors(q, robot.links[i])  # eq. 12
    flange_rot = Rotation.from_quat(quaternion_multiply(q, robot.tool0_home).reshape(-1, 4),
                                    scalar_first=True).as_matrix().reshape(lead + (3, 3))
    w = np.stack(axes_world, axis=-1)  # (..., 3, k) serial axes in base
    lever = p[..., :, None] - np.stack(points, axis=-1)
    spatial_v = np.cross(w, lever, axis=-2)
    rt = np.swapaxes(flange_rot, -1, -2)
    serial = np.concatenate([rt @ spatial_v, rt @ w], axis=-2)  # (..., 6, k) per radian of serial angle
    return serial @ robot.coupling * (np.pi / 180.0)


def kinematic_jacobian(robot: RobotModel, joints_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local twist of tool0 per unit deviation of every entry of the robot's DH table.

    A real arm is never exactly its table: its ``d, a`` (mm), ``alpha`` and ``theta`` offsets
    (degrees) differ by small amounts that are the same at every posture. With the standard DH
    link ``L_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)`` and frames ``F_i = L_1 ... L_i`` (``F_0`` the base),
    a deviation of ``θ_i`` or ``d_i`` is a twist about or along ``z`` of frame ``F_(i-1)`` (``Rz`` and
    ``Tz`` commute), of ``a_i`` or ``α_i`` along or about ``x`` of ``F_i`` (``Tx`` and ``Rx`` commute);
    a twist ``ξ`` in frame ``F`` moves the flange ``F_n`` by the local twist ``Ad_{F_n^-1 F} ξ``.

    Parameters
    ----------
    robot : RobotModel
    joints_deg : array-like, shape (n, k)

    Returns
    -------
    jacobian : ndarray, shape (n, 6, 4k)
        Column ``4 i + c`` for DH entry ``c`` (``d, a, alpha, theta``) of axis ``i``.
    kinds : ndarray of int, shape (4k,)
        0 for lengths (mm), 1 for angles (degrees).
    """
    from ..robot import dh_transforms  # noqa: PLC0415

    theta = robot.serial_angles_rad(joints_deg) + np.radians(robot.dh[:, 3])
    links = dh_transforms(robot.dh, theta)  # (n, k, 4, 4)
    n, k = theta.shape
    frames = np.empty((n, k + 1, 4, 4))
    frames[:, 0] = np.eye(4)
    for i in range(k):
        frames[:, i + 1] = frames[:, i] @ links[:, i]
    flange_inv = np.linalg.inv(frames[:, k])
    to_flange = adjoint(flange_inv[:, None] @ frames)  # (n, k + 1, 6, 6): Ad_{F_n^-1 F_j}
    deg = np.pi / 180.0
    jac = np.empty((n, 6, 4 * k))
    for i in range(k):
        before, after = to_flange[:, i], to_flange[:, i + 1]
        jac[:, :, 4 * i + 0] = before[:, :, 2]          # d: along z of F_(i-1)
        jac[:, :, 4 * i + 1] = after[:, :, 0]           # a: along x of F_i
        jac[:, :, 4 * i + 2] = after[:, :, 3] * deg     # alpha: about x of F_i
        jac[:, :, 4 * i + 3] = before[:, :, 5] * deg    # theta: about z of F_(i-1)
    return jac, np.tile([0, 0, 1, 1], k)
