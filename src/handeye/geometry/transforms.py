"""Rigid transforms as 4x4 homogeneous matrices, named ``a2b`` (maps frame a to frame b).

Lengths are millimetres throughout the package; a pose written to disk is
``{"position_mm": [x, y, z], "quaternion_wxyz": [w, x, y, z]}`` with ``w >= 0``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .rotations import canonical_quaternions, check_quaternions, matrix_from_quaternion, quaternion_from_matrix

__all__ = [
    "transform_from_rotation_translation",
    "transform_from_pose",
    "pose_from_transform",
    "invert_transforms",
    "transform_points",
    "rotation_error_deg",
    "translation_error_mm",
    "rigid_defect",
]


def transform_from_rotation_translation(rotation: npt.ArrayLike, translation: npt.ArrayLike) -> np.ndarray:
    """Stack rotation matrices and translations into 4x4 transforms.

    Parameters
    ----------
    rotation : array-like, shape (..., 3, 3)
    translation : array-like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 4, 4)
    """
    rotation = np.asarray(rotation, dtype=float)
    translation = np.asarray(translation, dtype=float)
    lead = np.broadcast_shapes(rotation.shape[:-2], translation.shape[:-1])
    out = np.zeros(lead + (4, 4))
    out[..., :3, :3] = rotation
    out[..., :3, 3] = translation
    out[..., 3, 3] = 1.0
    return out


def transform_from_pose(position_mm: npt.ArrayLike, quaternion_wxyz: npt.ArrayLike) -> np.ndarray:
    """4x4 transform from a position (mm) and a unit quaternion (w, x, y, z).

    Parameters
    ----------
    position_mm : array-like, shape (..., 3)
    quaternion_wxyz : array-like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Raises
    ------
    ValueError
        If the quaternion is not unit or a value is not finite.
    """
    position = np.asarray(position_mm, dtype=float)
    if position.shape[-1:] != (3,):
        raise ValueError(f"a position needs 3 values (x, y, z); got shape {position.shape}")
    if not np.all(np.isfinite(position)):
        raise ValueError("position holds NaN or inf")
    q = check_quaternions(quaternion_wxyz)
    return transform_from_rotation_translation(matrix_from_quaternion(q), position)


def pose_from_transform(transform: npt.ArrayLike) -> dict:
    """The on-disk pose dictionary of one 4x4 transform (``w >= 0``)."""
    transform = np.asarray(transform, dtype=float)
    q = canonical_quaternions(quaternion_from_matrix(transform[:3, :3]))
    return {
        "position_mm": [float(v) for v in transform[:3, 3]],
        "quaternion_wxyz": [float(v) for v in q],
    }


def invert_transforms(transform: npt.ArrayLike) -> np.ndarray:
    """Inverse of rigid transforms, ``(..., 4, 4)``, using ``R^T`` (no general inverse)."""
    transform = np.asarray(transform, dtype=float)
    rotation_t = np.swapaxes(transform[..., :3, :3], -1, -2)
    translation = -np.einsum("...ij,...j->...i", rotation_t, transform[..., :3, 3])
    return transform_from_rotation_translation(rotation_t, translation)


def transform_points(transform: npt.ArrayLike, points: npt.ArrayLike) -> np.ndarray:
    """Apply transforms ``(..., 4, 4)`` to points ``(..., m, 3)``; returns ``(..., m, 3)``."""
    transform = np.asarray(transform, dtype=float)
    points = np.asarray(points, dtype=float)
    return np.einsum("...ij,...mj->...mi", transform[..., :3, :3], points) + transform[..., None, :3, 3]


def rotation_error_deg(transform_a: npt.ArrayLike, transform_b: npt.ArrayLike) -> np.ndarray:
    """Geodesic angle in degrees between the rotations of two transforms (or 3x3 rotations)."""
    ra = np.asarray(transform_a, dtype=float)[..., :3, :3]
    rb = np.asarray(transform_b, dtype=float)[..., :3, :3]
    cos = (np.einsum("...ij,...ij->...", ra, rb) - 1.0) / 2.0
    # arccos loses precision near 0; use the sine from the skew part as well.
    relative = np.einsum("...ji,...jk->...ik", ra, rb)
    skew = np.stack(
        [relative[..., 2, 1] - relative[..., 1, 2], relative[..., 0, 2] - relative[..., 2, 0],
         relative[..., 1, 0] - relative[..., 0, 1]], axis=-1
    )
    sin = 0.5 * np.linalg.norm(skew, axis=-1)
    return np.degrees(np.arctan2(sin, cos))


def translation_error_mm(transform_a: npt.ArrayLike, transform_b: npt.ArrayLike) -> np.ndarray:
    """Euclidean distance in mm between the translations of two transforms."""
    ta = np.asarray(transform_a, dtype=float)[..., :3, 3]
    tb = np.asarray(transform_b, dtype=float)[..., :3, 3]
    return np.linalg.norm(ta - tb, axis=-1)


def rigid_defect(matrix: npt.ArrayLike, tolerance: float = 1e-3) -> str | None:
    """Why ``matrix`` is not a 4x4 rigid transform, in a few words; None when it is one.

    Parameters
    ----------
    matrix : ndarray
        The candidate (any shape: a wrong one is the reason).
    tolerance : float
        Largest accepted ``max |R^T R - I|`` of the rotation part; the bottom row may differ from
        ``0 0 0 1`` by 1e-6 at most.

    Returns
    -------
    str or None
        ``must be a 4x4 matrix; got shape 3x3``, ``holds NaN or inf``, ``bottom row must be 0 0 0 1; got
        ...``, ``rotation part is not orthonormal (|R^T R - I| = 3)``, ``rotation part is a reflection
        (determinant -1)``; None for a rigid transform.
    """
    m = np.asarray(matrix, dtype=float)
    if m.shape != (4, 4):
        return f"must be a 4x4 matrix; got shape {'x'.join(map(str, m.shape)) or 'scalar'}"
    if not np.all(np.isfinite(m)):
        return "holds NaN or inf"
    if np.max(np.abs(m[3] - [0.0, 0.0, 0.0, 1.0])) > 1e-6:
        return f"bottom row must be 0 0 0 1; got {' '.join(f'{v:g}' for v in m[3])}"
    r = m[:3, :3]
    error = float(np.max(np.abs(r.T @ r - np.eye(3))))
    if error > tolerance:
        return f"rotation part is not orthonormal (|R^T R - I| = {error:.3g})"
    if np.linalg.det(r) < 0:
        return "rotation part is a reflection (determinant -1)"
    return None
