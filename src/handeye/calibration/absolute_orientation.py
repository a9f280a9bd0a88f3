"""Absolute orientation (``absROT`` of the paper), Horn 1987 closed form in quaternions, batched.

Horn, B. K. P. (1987). Closed-form solution of absolute orientation using unit quaternions.
J. Opt. Soc. Am. A 4(4), 629-642.

The rotation that best carries a set of source vectors onto target vectors (least squares) is the
eigenvector of the largest eigenvalue of Horn's symmetric 4x4 matrix ``N`` built from the
correlation ``S = sum_i source_i target_i^T``. The paper (section 3.2, eq. 24-29) uses the same
closed form for three points: eq. 24 centres the points, eq. 28 composes the rotation and eq. 29
gives the translation. The eigenvector form used here is exact for any number of points and
handles batches of problems in one ``numpy.linalg.eigh`` call.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..base import WORKERS, map_chunks
from ..geometry import canonical_quaternions, rotate_vectors

__all__ = ["AbsoluteOrientation", "rotation_between_vectors", "absolute_orientation", "horn_matrix"]


@dataclass(frozen=True)
class AbsoluteOrientation:
    """Result of a (batched) absolute-orientation problem.

    Attributes
    ----------
    quaternion : ndarray, shape (..., 4)
        Rotation (w, x, y, z), ``w >= 0``, carrying source onto target.
    translation : ndarray, shape (..., 3)
        Translation (zero for the vector-only problem): ``target ≈ rot(q, source) + t`` (eq. 29).
    rms_residual : ndarray, shape (...)
        Root mean square of ``|target - (rot(q, source) + t)|`` over the points.
    eigen_gap : ndarray, shape (...)
        ``(λ1 - λ2) / max(|λ1|, tiny)`` of Horn's matrix: near 0 means the rotation is not
        determined (e.g. all vectors parallel).
    """

    quaternion: np.ndarray
    translation: np.ndarray
    rms_residual: np.ndarray
    eigen_gap: np.ndarray


def horn_matrix(source: ArrayLike, target: ArrayLike, weights: ArrayLike | None = None) -> np.ndarray:
    """Horn's symmetric 4x4 matrix ``N`` for the correlation of source and target vectors.

    Parameters
    ----------
    source, target : array-like, shape (..., m, 3)
    weights : array-like, shape (..., m), optional

    Returns
    -------
    ndarray, shape (..., 4, 4)
    """
    source = np.asarray(source, dtype=float)
    target = np.asarray(target, dtype=float)
    if weights is not None:
        source = source * np.asarray(weights, dtype=float)[..., None]
    s = np.einsum("...mi,...mj->...ij", source, target)  # S_ab = sum source_a target_b
    sxx, sxy, sxz = s[..., 0, 0], s[..., 0, 1], s[..., 0, 2]
    syx, syy, syz = s[..., 1, 0], s[..., 1, 1], s[..., 1, 2]
    szx, szy, szz = s[..., 2, 0], s[..., 2, 1], s[..., 2, 2]
    n = np.empty(s.shape[:-2] + (4, 4))
    n[..., 0, 0] = sxx + syy + szz
    n[..., 0, 1] = n[..., 1, 0] = syz - szy
    n[..., 0, 2] = n[..., 2, 0] = szx - sxz
    n[..., 0, 3] = n[..., 3, 0] = sxy - syx
    n[..., 1, 1] = sxx - syy - szz
    n[..., 1, 2] = n[..., 2, 1] = sxy + syx
    n[..., 1, 3] = n[..., 3, 1] = szx + sxz
    n[..., 2, 2] = -sxx + syy - szz
    n[..., 2, 3] = n[..., 3, 2] = syz + szy
    n[..., 3, 3] = -sxx - syy + szz
    return n


#: Batches larger than this are split over threads (numpy's LAPACK loop releases the GIL).
_THREAD_BATCH = 20000


def _top_eigenvector(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if n.ndim == 3 and len(n) > _THREAD_BATCH:
        parts = map_chunks(np.linalg.eigh, np.array_split(n, WORKERS))
        values = np.concatenate([p[0] for p in parts])
        vectors = np.concatenate([p[1] for p in parts])
    else:
        values, vectors = np.linalg.eigh(n)
    top = vectors[..., :, -1]
    scale = np.maximum(np.abs(values[..., -1]), np.finfo(float).tiny)
    gap = (values[..., -1] - values[..., -2]) / scale
    return canonical_quaternions(top), gap


def rotation_between_vectors(source: ArrayLike, target: ArrayLike, weights: np.ndarray | None = None) -> AbsoluteOrientation:
    """Rotation ``q`` minimising ``sum_i w_i |target_i - rot(q, source_i)|^2`` (no translation).

    This is ``absROT(V_B, V_A)`` of eq. 30 when the vectors are the vector parts of relative
    motions.

    Parameters
    ----------
    source, target : array-like, shape (..., m, 3)
        Corresponding vectors, ``m >= 2`` and not all parallel for a unique answer.
    weights : array-like, shape (..., m), optional
        Non-negative weights.

    Returns
    -------
    AbsoluteOrientation
        ``translation`` is zero.
    """
    source = np.asarray(source, dtype=float)
    target = np.asarray(target, dtype=float)
    q, gap = _top_eigenvector(horn_matrix(source, target, weights))
    residual = target - rotate_vectors(q[..., None, :], source)
    rms = np.sqrt(np.mean(np.sum(residual**2, axis=-1), axis=-1))
    return AbsoluteOrientation(q, np.zeros(q.shape[:-1] + (3,)), rms, gap)


def absolute_orientation(source: ArrayLike, target: ArrayLike) -> AbsoluteOrientation:
    """Rigid motion carrying source points onto target points (Horn 1987; eq. 24-29).

    Parameters
    ----------
    source, target : array-like, shape (..., m, 3)
        Corresponding points, ``m >= 3`` and not collinear for a unique answer.

    Returns
    -------
    AbsoluteOrientation
        ``target ≈ rot(quaternion, source) + translation``.
    """
    source = np.asarray(source, dtype=float)
    target = np.asarray(target, dtype=float)
    source_centre = source.mean(axis=-2)
    target_centre = target.mean(axis=-2)
    q, gap = _top_eigenvector(horn_matrix(source - source_centre[..., None, :], target - target_centre[..., None, :]))
    translation = target_centre - rotate_vectors(q, source_centre)  # eq. 29
    residual = target - (rotate_vectors(q[..., None, :], source) + translation[..., None, :])
    rms = np.sqrt(np.mean(np.sum(residual**2, axis=-1), axis=-1))
    return AbsoluteOrientation(q, translation, rms, gap)
