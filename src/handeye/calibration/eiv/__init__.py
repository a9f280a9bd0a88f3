"""Maximum-likelihood (errors-in-variables) hand-eye calibration: the package's default estimator.

Model. With hand poses ``A_i`` (``tool02base`` eye-in-hand, ``base2tool0`` eye-to-hand), board
poses ``B_i`` (``target2cam``), the unknown ``X`` and the unknown board pose ``T`` in the frame it
is fixed in (eq. 13 for all board points at once),

    A_i^true X B_i^true = T                                  for every posture i,

where both measured sides are noisy: ``A_i = A_i^true ⊕ ξ_i`` (robot) and ``B_i = B_i^true ⊕ η_i``
(camera; ``⊕`` and twists as in ``noise.py``). The unknowns are ``X``, ``T`` and per posture the
robot correction ``ξ_i`` (and the board correction ``η_i``), with Gaussian priors
``ξ_i ~ N(0, C_A,i)``, ``η_i ~ N(0, C_B,i)``. To first order the pose residual of posture i

    r_i = twist(T^-1 A_i X B_i) = Ad_{(X B_i)^-1} ξ_i + η_i

so the corrections are eliminated in closed form (the Schur complement of their normal equations;
the best corrections given ``X, T`` are ``ξ̂_i = C_A Ad^T S_i^-1 r_i``), leaving 12 unknowns and

    minimise  sum_i r_i^T S_i^-1 r_i,      S_i = Ad_i C_A,i Ad_i^T + C_B,i,

solved by Gauss-Newton on ``X ⊕ δx``, ``T ⊕ δt`` (``dr/dδx = Ad_{B_i^-1}``, ``dr/dδt = -I``).

Weights. ``C_B,i`` comes from the weighted rigid fit of the board to its corners, each corner
weighted by its stereo covariance (``noise.py``: far noisier in depth than sideways), with the
corner-noise variance components estimated from the fit residuals. Sessions of board poses only
get ``C_B,i`` from components in the board frame: tilt (rotation about the board's in-plane axes,
poorly seen by one camera), spin (about its normal), depth (along the camera's optical axis) and an
isotropic position noise (which an isotropic flange position noise could not be told from). A
board pose measured by one camera is best determined at the middle of what the camera sees, so its
tilt turns the board about that point and moves a corner origin with it (``ρ = ρ_c + c x φ``): the
point ``c`` (board frame, unknown in a session of poses) is found by restricted maximum likelihood
and kept when the likelihood ratio exceeds :data:`CENTRE_LR` (chi-square, 3 degrees of freedom,
p = 0.001), so poses whose rotation and position errors are independent keep the origin model.
``C_A,i = σ_q² J_i J_i^T + σ_p² I_pos`` with the flange Jacobian ``J_i`` of the robot model when the
session holds joint angles (joint noise, and position noise for what joints cannot shape); else
flange rotation and translation noise in the flange frame.

Kinematic deviations. A real arm differs from its DH table by deviations ``u`` that are the same
at every posture (``noise.kinematic_jacobian``: the flange moves by ``K_i u``). With joints, the
fit is repeated with ``u ~ N(0, diag(σ_len², σ_ang²))`` as random effects (Henderson's mixed-model
equations: the unknowns become ``X, T, u``); the model is kept when the likelihood ratio of the two
restricted likelihoods exceeds :data:`KINEMATIC_LR` (chi-square, 2 degrees of freedom,
p = 0.001). The deviations that ``X`` absorbs exactly (the flange's own offset) then enter the
covariance of ``X`` through their prior, with variances estimated from the deviations the data
do show: the one-sigma values cover the arm's errors, not only the noise.

Variance components. Every ``σ²`` not fixed by the board fits is estimated by restricted maximum
likelihood (Fisher scoring, scale-free, on ``S_i = F_i + sum_k θ_k G_ik``; the kinematic variances
through the mixed-model identity ``Z^T P Z = Λ^-1 - Λ^-1 M_uu Λ^-1``), alternated with the
Gauss-Newton fit, so no noise level is typed in. The covariance of ``X`` is the inverse of the
mixed-model normal matrix at the optimum with those components.

Start and outliers. The paper's mcb (Algorithm 1, selection by d_back, eq. 23) on the postures
that keep the X-free angle invariant (eq. 30: ``S_A = S_B``); with many postures, on a subset of
:data:`START_POSTURES` spread over the hand rotations, so the default never needs the exhaustive
triplet search. Then alternately the ML fit over the inliers and outlier detection on the
postures' Mahalanobis distances ``d_i = sqrt(r_i^T S_i^-1 r_i)``: a posture with a high robust
z-score is tested by its deleted distance (:func:`deleted_mahalanobis`: the fit of the other
postures predicts it; an F test with a Bonferroni bound, so clean sets, small ones too, keep every
posture); a posture that breaks the angle invariant stays out when its deleted distance is also
beyond the 5 % level shared among such postures and its angle gap three times what the fitted
rotation noise explains. Until the inlier set is stable, never dropping more than half. Finally a 5-fold posture cross-validation (``crossval.py``) with
the error the noise model predicts for it.

Modules: ``model`` (observations and variance components), ``fit`` (the ML fit), ``centre`` (the
board's rotation centre), ``start`` (mcb on the invariant-consistent postures), ``outliers``,
``cross_validation`` and ``pipeline`` (:func:`solve_eiv`). The public names are importable from here.
"""

from .centre import CENTRE_LR, board_centre, centred
from .cross_validation import ml_cross_validation
from .fit import MLFit, fit_ml, initial_board_pose
from .model import Component, Observations, observations
from .outliers import deleted_mahalanobis
from .pipeline import KINEMATIC_LR, EivSolution, solve_eiv
from .start import START_POSTURES, board_pose_angle_gaps_deg, varied_rotation_subset

__all__ = [
    "START_POSTURES",
    "KINEMATIC_LR",
    "Component",
    "Observations",
    "observations",
    "MLFit",
    "fit_ml",
    "EivSolution",
    "solve_eiv",
    "ml_cross_validation",
    "deleted_mahalanobis",
    "board_pose_angle_gaps_deg",
    "varied_rotation_subset",
    "initial_board_pose",
    "CENTRE_LR",
    "centred",
    "board_centre",
]
