"""Which of a session's postures to revisit for a check: the ones that tell the explanations apart.

Each revisited posture ``j`` adds ``J_j^T S_j^-1 J_j`` to the information about the stacked
parameters of every explanation (``verification.hypothesis_jacobians``: camera 6, board 6, one zero
per joint); :func:`informative_postures` picks, greedily, the posture that raises the log-determinant
of that information most (a D-optimal design), so the chosen ones spread their rotation axes and
distances where the explanations differ.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
import numpy as np

from .verification import Baseline, discrepancy, hypothesis_jacobians

if TYPE_CHECKING:
    from ..robot import RobotModel
    from collections.abc import Callable
    from .eiv.model import Observations
    from numpy.typing import ArrayLike

__all__ = ["informative_postures"]


def informative_postures(baseline: Baseline, obs: Observations, joints_deg: np.ndarray, robot: RobotModel, count: int, allowed: ArrayLike | None = None, path_time: Callable[[list[int]], float] | None = None,
                         budget: float = np.inf) -> np.ndarray:
    """Indices (into ``obs``) of ``count`` postures chosen for diagnostic power, in the order chosen.

    With ``path_time(indices) -> seconds`` only postures that keep the path within ``budget`` seconds
    are taken at each step (the one adding least time when none does): a short check.

    Parameters
    ----------
    baseline : Baseline
    obs : eiv.Observations
        The session's postures.
    joints_deg : ndarray, shape (n, dof) or None
    robot : RobotModel or None
    count : int
    allowed : array-like of bool, shape (n,), optional
        Postures that may be chosen (default all).
    """
    disc = discrepancy(baseline, obs, joints_deg)
    jac = np.concatenate(list(hypothesis_jacobians(disc, baseline.x, robot).values()), axis=1)
    n, p = obs.n, jac.shape[1]
    blocks = jac.reshape(n, 6, p)
    weights = np.linalg.inv(disc.noise.reshape(n, 6, n, 6)[np.arange(n), :, np.arange(n), :])
    info = np.swapaxes(blocks, 1, 2) @ weights @ blocks  # (n, p, p)
    scale = np.sqrt(np.maximum(np.einsum("npp->p", info), 1e-30))
    info = info / np.outer(scale, scale)  # parameters of different units on one footing
    free = np.ones(n, bool) if allowed is None else np.asarray(allowed, bool).copy()
    total = 1e-6 * np.eye(p)
    chosen = []
    for _ in range(min(count, int(free.sum()))):
        candidates = np.flatnonzero(free)
        if path_time is not None:
            times = np.array([path_time(chosen + [int(j)]) for j in candidates])
            candidates = candidates[times <= budget] if np.any(times <= budget) else candidates[[int(np.argmin(times))]]
        gains = np.full(n, -np.inf)
        for j in candidates:
            gains[j] = np.linalg.slogdet(total + info[j])[1]
        best = int(np.argmax(gains))
        chosen.append(best)
        free[best] = False
        total = total + info[best]
    return np.array(chosen, int)
