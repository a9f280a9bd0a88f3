"""k-fold posture cross-validation of the maximum-likelihood fit, with the error its noise model
predicts (the definitions of ``src/handeye/calibration/crossval.py``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..metrics import fixed_points
from ..noise import skew
from .fit import MLFit, _jacobians, fit_ml
from .model import Observations

if TYPE_CHECKING:
    from ..crossval import CrossValidation


def ml_cross_validation(obs: Observations, fit: MLFit, keep: np.ndarray, folds: int,
                        kinematic: bool = False) -> CrossValidation:
    """k-fold cross-validation of the ML fit (``crossval.py`` definition) with its predicted error.

    Each fold refits ``X, T`` (and the DH deviations when modelled) from the full solution with the
    variance components held at their full-data values; the held-out postures' fitted board points
    are carried by their flange poses as measured (the nominal kinematics, as the controller uses
    them). The predicted mean-square error of a held-out point ``p`` of posture ``i`` is
    ``tr(L_p (S_i + J_i C J_i^T) L_p^T)``: its posture's random noise (camera, joints) and the
    training fit's uncertainty ``C``, ``L_p = [I, -[g_p]x]`` carrying a board twist to the point,
    plus the same for the training mean point divided by the number of training postures. Errors
    the random model does not hold (the arm's kinematic deviations, a moving bracket) make the
    observed error larger.
    """
    from ..crossval import CrossValidation, fold_assignment, held_out_errors  # noqa: PLC0415

    n = obs.n
    index = np.flatnonzero(keep)
    fold = np.full(n, -1)
    fold[index] = fold_assignment(len(index), folds)
    k = int(fold.max()) + 1
    model = obs.model_points
    points = np.einsum("nij,mj->nmi", obs.board[:, :3, :3], model) + obs.board[:, None, :3, 3]
    lever = np.zeros((len(model), 3, 6))
    lever[:, :, :3] = np.eye(3)
    lever[:, :, 3:] = -skew(model)
    jac = _jacobians(obs)
    mean = np.full(n, np.nan)
    mean_sq = np.full(n, np.nan)
    predicted = np.full(n, np.nan)
    for f in range(k):
        train = keep & (fold != f)
        test = fold == f
        ff = fit_ml(obs, fit.x, fit.target, fit.theta, estimate_theta=False, keep=train, kinematic0=fit.kinematic,
                    kinematic_var0=fit.kinematic_var, kinematic=kinematic)
        reference = fixed_points(obs.hand[train], ff.x, points[train]).mean(axis=0)
        mean[test], mean_sq[test] = held_out_errors(obs.hand[test], ff.x, points[test], reference)
        s_cv = ff.posture_cov + jac @ ff.covariance @ np.swapaxes(jac, 1, 2)
        per_point = np.trace(np.mean(lever[None] @ s_cv[:, None] @ np.swapaxes(lever, 1, 2)[None], axis=1),
                             axis1=1, axis2=2)  # (n,)
        predicted[test] = per_point[test] + per_point[train].mean() / train.sum()
    rms_pred = float(np.sqrt(np.nanmean(predicted)))
    return CrossValidation(k, mean, "corners" if len(model) > 3 else "compact", mean_sq, rms_pred)
