"""Unit quaternions, scalar first ``(w, x, y, z)`` = ABB ``q1..q4``.

Every function accepts batches: leading dimensions ``...`` broadcast as in numpy.
Conversions to and from rotation matrices go through scipy's ``Rotation`` where a
batch is flat; the products used in hot loops are written out with numpy.
The paper's notation: ``Q * P`` is the quaternion product, ``Q̄`` the conjugate,
``rot(Q, P) = Q * P * Q̄`` (eq. 10) and ``RtoQ(N, θ)`` the axis-angle quaternion (eq. 9).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

__all__ = [
    "cross3",
    "skew",
    "UNIT_TOLERANCE",
    "check_quaternions",
    "canonical_quaternions",
    "quaternion_multiply",
    "quaternion_conjugate",
    "rotate_vectors",
    "quaternion_from_axis_angle",
    "axis_angle_from_quaternion",
    "matrix_from_quaternion",
    "quaternion_from_matrix",
    "rotation_angle",
]

#: Largest accepted deviation of a quaternion's norm from 1 before it is called "not unit".
UNIT_TOLERANCE = 1e-3


def check_quaternions(q: npt.ArrayLike, tolerance: float = UNIT_TOLERANCE) -> np.ndarray:
    """Return ``q`` as float64 unit quaternions, normalised.

    Parameters
    ----------
    q : array-like, shape (..., 4)
        Quaternions (w, x, y, z).
    tolerance : float
        Largest accepted ``| |q| - 1 |``; within it the quaternion is renormalised.

    Raises
    ------
    ValueError
        If the last axis is not 4, a value is not finite, or a norm is off by more than ``tolerance``.
    """
    q = np.asarray(q, dtype=float)
    if q.shape[-1:] != (4,):
        raise ValueError(f"a quaternion needs 4 values (w, x, y, z); got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise ValueError("quaternion holds NaN or inf")
    with np.errstate(over="ignore"):  # a huge component: the norm is inf, refused below without a warning
        norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(np.abs(norm - 1.0) > tolerance):
        worst = float(norm.ravel()[np.argmax(np.abs(norm - 1.0))])
        raise ValueError(f"quaternion is not unit (norm {worst:.6g}); write it as (w, x, y, z) with norm 1")
    return q / norm


def canonical_quaternions(q: npt.ArrayLike) -> np.ndarray:
    """Flip the sign of ``q`` so that ``w >= 0`` (the written-out convention).

    Parameters
    ----------
    q : array-like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)
    """
    q = np.asarray(q, dtype=float)
    return np.where(q[..., :1] < 0.0, -q, q)


def quaternion_multiply(p: npt.ArrayLike, q: npt.ArrayLike) -> np.ndarray:
    """Hamilton product ``p * q``.

    Parameters
    ----------
    p, q : array-like, shape (..., 4)
        Quaternions (w, x, y, z); the leading shapes broadcast.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def quaternion_conjugate(q: npt.ArrayLike) -> np.ndarray:
    """Conjugate ``Q̄`` (the inverse of a unit quaternion).

    Parameters
    ----------
    q : array-like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)
    """
    q = np.asarray(q, dtype=float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def rotate_vectors(q: npt.ArrayLike, v: npt.ArrayLike) -> np.ndarray:
    """``rot(Q, P) = Q * P * Q̄`` for unit quaternions (eq. 10), without building the product.

    Parameters
    ----------
    q : array-like, shape (..., 4)
        Unit quaternions (w, x, y, z).
    v : array-like, shape (..., 3)
        Vectors; the leading shapes broadcast with ``q``.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * cross3(u, v)
    return v + w * t + cross3(u, t)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` of 3-vectors along the last axis, shapes broadcast: the same numbers as ``np.cross``
    (the same products and differences), at a third of its cost on the small arrays of the kinematics
    and the rotations (``np.cross`` moves axes for every call).

    Parameters
    ----------
    a, b : ndarray, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3)
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def quaternion_from_axis_angle(axis: npt.ArrayLike, angle: npt.ArrayLike) -> np.ndarray:
    """``RtoQ(N, θ) = cos(θ/2) + sin(θ/2) N/|N|`` (eq. 9).

    Parameters
    ----------
    axis : array-like, shape (..., 3)
        Rotation axes, any non-zero length.
    angle : array-like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    axis = np.asarray(axis, dtype=float)
    half = 0.5 * np.asarray(angle, dtype=float)
    n = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    return np.concatenate([np.cos(half)[..., None], np.sin(half)[..., None] * n], axis=-1)


def axis_angle_from_quaternion(q: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Unit axis and angle in [0, pi] of unit quaternions.

    Parameters
    ----------
    q : array-like, shape (..., 4)

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axes; (1, 0, 0) for the identity.
    angle : ndarray, shape (...)
        Angles in radians, in [0, pi].
    """
    q = canonical_quaternions(q)
    s = np.linalg.norm(q[..., 1:], axis=-1)
    angle = 2.0 * np.arctan2(s, q[..., 0])
    safe = np.where(s[..., None] > 1e-15, q[..., 1:] / np.maximum(s, 1e-300)[..., None], [1.0, 0.0, 0.0])
    return safe, angle


def rotation_angle(q: npt.ArrayLike) -> np.ndarray:
    """Rotation angle in radians, in [0, pi], of unit quaternions ``(..., 4)``."""
    q = np.asarray(q, dtype=float)
    return 2.0 * np.arctan2(np.linalg.norm(q[..., 1:], axis=-1), np.abs(q[..., 0]))


def matrix_from_quaternion(q: npt.ArrayLike) -> np.ndarray:
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    q : array-like, shape (..., 4)
        Unit quaternions (w, x, y, z).

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    q = np.asarray(q, dtype=float)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def quaternion_from_matrix(matrix: npt.ArrayLike) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)`` with ``w >= 0`` of rotation matrices (via scipy).

    Parameters
    ----------
    matrix : array-like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 4)
    """
    matrix = np.asarray(matrix, dtype=float)
    lead = matrix.shape[:-2]
    flat = Rotation.from_matrix(matrix.reshape(-1, 3, 3)).as_quat(scalar_first=True)
    return canonical_quaternions(flat.reshape(lead + (4,)))


def skew(v: npt.ArrayLike) -> np.ndarray:
    """Cross-product matrices ``[v]_x`` of vectors ``(..., 3)``, shape ``(..., 3, 3)``: ``[v]_x w = v x w``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out
