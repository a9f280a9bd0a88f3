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
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.stats import f as f_dist

from .noise import (
    VARIANCE_FLOOR,
    CornerNoise,
    adjoint,
    corner_noise,
    fit_board_poses,
    flange_jacobian,
    inverse_covariances,
    kinematic_jacobian,
    retract,
    shape_eigen,
    skew,
    stereo_point_shape,
    twist_between,
)
from .invariants import bounded_pairs, posture_medians
from .metrics import fixed_points
from .problem import EYE_IN_HAND, MIN_POSTURES, HandEyeProblem
from .rotations import quaternion_from_matrix
from .transforms import invert_transforms

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
    "angle_gaps_deg",
    "varied_rotation_subset",
    "initial_board_pose",
    "CENTRE_LR",
    "centred",
    "board_centre",
]

#: Above this many (invariant-consistent) postures, mcb starts from a subset of this size.
START_POSTURES = 20
#: Gauss-Newton stops when the step is below these (mm, rad).
STEP_TOL_MM = 1e-7
STEP_TOL_RAD = 1e-10
MAX_OUTER = 40
#: Largest relative change of the variance components counted as converged.
THETA_TOL = 1e-3
#: FK(joints) must match the session's flange pose this well for the joint Jacobian to be used.
JOINT_MATCH_MM = 5.0
JOINT_MATCH_DEG = 0.5


@dataclass(frozen=True)
class Component:
    """One variance component ``θ G_i`` of the posture covariance.

    Attributes
    ----------
    name : str
        ``joint`` (deg²), ``flange_rotation`` (rad²), ``flange_translation`` (mm²),
        ``camera_rotation`` (rad²), ``camera_translation`` (mm²).
    side : str
        ``hand``: ``structure`` is a local covariance of the hand pose, carried to the residual
        frame by ``Ad_{(X B_i)^-1}``; ``board``: already in the residual (board) frame.
    structure : ndarray, shape (n, 6, 6)
        ``G`` per unit variance.
    """

    name: str
    side: str
    structure: np.ndarray


@dataclass(frozen=True)
class Observations:
    """A problem prepared for the ML fit.

    Attributes
    ----------
    hand : ndarray, shape (n, 4, 4)
    board : ndarray, shape (n, 4, 4)
        Fitted board poses ``B_i`` (``target2cam``).
    board_cov : ndarray, shape (n, 6, 6)
        Fixed camera covariance of ``B_i`` (board frame twist); zeros for sessions of board poses.
    components : tuple of Component
        The variance components to estimate.
    mode : str
        ``corners`` (points fitted, camera noise from the fits) or ``poses``.
    corner : CornerNoise or None
    points : ndarray, shape (n, m, 3)
        Measured points (camera frame) used by the point measures.
    model_points : ndarray, shape (m, 3)
        The same points in the target frame.
    point_cov : ndarray, shape (n, m, 3, 3) or None
        Corner covariances (corner sessions).
    kinematic : ndarray, shape (n, 6, q) or None
        Hand-local twist per unit deviation of each DH entry of the robot model (sessions with
        joints): the arm's kinematic errors, the same at every posture (``noise.kinematic_jacobian``).
    kinematic_kinds : ndarray of int, shape (q,) or None
        0 for a length (mm), 1 for an angle (deg).
    """

    hand: np.ndarray
    board: np.ndarray
    board_cov: np.ndarray
    components: tuple
    mode: str
    corner: CornerNoise | None
    points: np.ndarray
    model_points: np.ndarray
    point_cov: np.ndarray | None = None
    kinematic: np.ndarray | None = None
    kinematic_kinds: np.ndarray | None = None
    notes: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.hand.shape[0])

    def subset(self, keep) -> "Observations":
        keep = np.asarray(keep)
        comps = tuple(replace(c, structure=c.structure[keep]) for c in self.components)
        return replace(self, hand=self.hand[keep], board=self.board[keep], board_cov=self.board_cov[keep],
                       components=comps, points=self.points[keep],
                       point_cov=None if self.point_cov is None else self.point_cov[keep],
                       kinematic=None if self.kinematic is None else self.kinematic[keep])


def _board_data(problem: HandEyeProblem) -> tuple[np.ndarray, np.ndarray, bool]:
    """Measured points, their target-frame model and whether they are corners (more than 3)."""
    model = problem.target_points
    pts = problem.points_cam
    if model is not None and pts.shape[1] == len(model) and pts.shape[1] > 3:
        return pts, np.asarray(model, float), True
    return problem.compact.points, np.asarray(problem.compact.target_points, float), False


def _hand_components(problem: HandEyeProblem) -> tuple:
    """Robot-side components in the hand's local frame, and the kinematic-deviation Jacobian.

    With joint angles and a robot model: joint noise through the flange Jacobian, and the DH
    deviations (``noise.kinematic_jacobian``); otherwise flange rotation and translation noise.
    """
    n = problem.n
    tool02base = problem.hand if problem.setup == EYE_IN_HAND else invert_transforms(problem.hand)
    to_hand = np.broadcast_to(np.eye(6), (n, 6, 6)) if problem.setup == EYE_IN_HAND else -adjoint(tool02base)
    # eye-to-hand: hand = tool02base^-1, so (T ⊕ ξ)^-1 = T^-1 ⊕ (-Ad_T ξ)
    robot = _robot_for(problem, tool02base)
    if robot is not None:
        jac = flange_jacobian(robot, problem.joints_deg)
        g = to_hand @ (jac @ np.swapaxes(jac, 1, 2)) @ np.swapaxes(to_hand, 1, 2)
        kin, kinds = kinematic_jacobian(robot, problem.joints_deg)
        # joint noise, and a position noise of the flange for what joint noise cannot shape
        # (a jittering bracket, elastic deflection)
        trans = np.zeros((6, 6))
        trans[:3, :3] = np.eye(3)
        comps = (Component("joint", "hand", g),
                 Component("flange_translation", "hand", to_hand @ trans @ np.swapaxes(to_hand, 1, 2)))
        return comps, (to_hand @ kin, kinds)
    rot = np.zeros((6, 6))
    rot[3:, 3:] = np.eye(3)
    trans = np.zeros((6, 6))
    trans[:3, :3] = np.eye(3)
    g_rot = to_hand @ rot @ np.swapaxes(to_hand, 1, 2)
    g_trans = to_hand @ trans @ np.swapaxes(to_hand, 1, 2)
    return (Component("flange_rotation", "hand", g_rot), Component("flange_translation", "hand", g_trans)), None


def _robot_for(problem: HandEyeProblem, tool02base: np.ndarray):
    """The robot model of the problem's joints when its kinematics reproduce the flange poses."""
    joints = getattr(problem, "joints_deg", None)
    robot_name = getattr(problem, "robot", None)
    if joints is None or robot_name is None:
        return None
    from .kinematics import load_robot  # noqa: PLC0415 (only sessions with joints need it)

    try:
        robot = load_robot(robot_name)
    except ValueError:
        return None
    joints = np.asarray(joints, float)
    if joints.shape != (problem.n, robot.dof):
        return None
    fk = robot.forward_transform(joints)
    gap = twist_between(fk, tool02base)
    if np.max(np.linalg.norm(gap[:, :3], axis=1)) > JOINT_MATCH_MM or \
            np.degrees(np.max(np.linalg.norm(gap[:, 3:], axis=1))) > JOINT_MATCH_DEG:
        return None
    return robot


def observations(problem: HandEyeProblem, stereo: tuple | None = None) -> Observations:
    """Board poses, their covariance and the variance components of a problem.

    Parameters
    ----------
    problem : HandEyeProblem
    stereo : (f_px, baseline_mm), optional
        Rectified stereo geometry behind triangulated corners (default: the nominal XB3 wide pair).
    """
    pts, model, corners = _board_data(problem)
    n = problem.n
    start = problem.target2cam if corners else None
    if not corners:  # board poses from the three compact points (Horn, eq. 24-29)
        from .absolute_orientation import absolute_orientation  # noqa: PLC0415
        from .rotations import matrix_from_quaternion  # noqa: PLC0415

        fit = absolute_orientation(np.broadcast_to(model, pts.shape), pts)
        start = np.tile(np.eye(4), (n, 1, 1))
        start[:, :3, :3] = matrix_from_quaternion(fit.quaternion)
        start[:, :3, 3] = fit.translation
    hand_comps, kin = _hand_components(problem)
    kin_fields = {} if kin is None else {"kinematic": kin[0], "kinematic_kinds": kin[1]}
    if corners:
        f_px, baseline = stereo if stereo is not None else (None, None)
        kwargs = {} if f_px is None else {"f_px": f_px, "baseline_mm": baseline}
        shapes = stereo_point_shape(pts, **kwargs)
        eigen = shape_eigen(shapes)
        fit = fit_board_poses(pts, model, start, iterations=2)  # unweighted first: residuals for the components
        noise = corner_noise(fit.residuals, eigen)
        fit = fit_board_poses(pts, model, fit.target2cam, inverse_covariances(noise, eigen), iterations=1)
        noise = corner_noise(fit.residuals, eigen)
        fit = fit_board_poses(pts, model, fit.target2cam, inverse_covariances(noise, eigen), iterations=1)
        cov = noise.covariances(shapes)
        board_cov = np.linalg.inv(fit.information)
        return Observations(problem.hand, fit.target2cam, board_cov, hand_comps, "corners", noise, pts, model, cov,
                            **kin_fields)
    return Observations(problem.hand, start, np.zeros((n, 6, 6)), _pose_components(hand_comps, start, model), "poses",
                        None, pts, model, **kin_fields)


def _pose_components(hand_comps: tuple, target2cam: np.ndarray, model: np.ndarray) -> tuple:
    """Components of sessions of board poses: the robot's, the board's rotation, a position noise
    and the board's extra depth noise (along the camera's optical axis, as from a monocular pose).

    An isotropic position noise of the flange and one of the board give the residual the same
    covariance (``Ad`` only rotates it): one component ``position`` stands for both.
    """
    n = len(target2cam)
    tilt = np.zeros((n, 6, 6))
    tilt[:, 3, 3] = tilt[:, 4, 4] = 1.0  # about the board's in-plane axes: poorly seen by one camera
    spin = np.zeros((n, 6, 6))
    spin[:, 5, 5] = 1.0                  # about the board normal: well seen
    pos = np.zeros((n, 6, 6))
    pos[:, :3, :3] = np.eye(3)
    axis = target2cam[:, 2, :3]  # the camera z axis in the board frame: row 2 of R_B
    depth = np.zeros((n, 6, 6))
    depth[:, :3, :3] = axis[:, :, None] * axis[:, None, :]
    hand_comps = tuple(c for c in hand_comps if c.name != "flange_translation")
    return hand_comps + (Component("camera_tilt", "board", tilt), Component("camera_spin", "board", spin),
                         Component("position", "board", pos), Component("camera_depth", "board", depth))


#: Board-frame rotation components of sessions of board poses, per unit variance about the board origin.
_ROTATION_BASES = {"camera_tilt": np.diag([0.0, 0.0, 0.0, 1.0, 1.0, 0.0]), "camera_spin": np.diag([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])}
#: Likelihood ratio above which the board's rotation noise is modelled about a fitted centre (chi-square,
#: 3 degrees of freedom, p = 0.001).
CENTRE_LR = 16.27
#: Lower bound of the variances while the centre is searched (mm², rad²): keeps every ``S_i`` invertible.
CENTRE_THETA_FLOOR = 1e-12
#: The centre search of a larger session runs on this many of its postures, evenly spread in capture
#: order (the fits that follow use them all): its cost no longer grows with a stream's length.
CENTRE_POSTURES = 2000


def _lever(centre) -> np.ndarray:
    """``[[I, [c]x], [0, I]]``: a twist about the board point ``c`` as a twist about the board origin."""
    out = np.eye(6)
    out[:3, 3:] = skew(np.asarray(centre, float))
    return out


def centred(obs: "Observations", centre) -> "Observations":
    """Observations whose board rotation noise (tilt, spin) turns the board about the board point ``centre``.

    A board pose measured by one camera is best determined at the middle of what the camera sees:
    its tilt error turns the board about that point, so the board origin (a corner) moves with the
    tilt, ``ρ = ρ_c + c x φ``. ``centre`` is that point in the board frame (mm).
    """
    lever = _lever(centre)
    comps = tuple(replace(c, structure=np.broadcast_to(lever @ _ROTATION_BASES[c.name] @ lever.T, (obs.n, 6, 6)).copy())
                  if c.side == "board" and c.name in _ROTATION_BASES else c for c in obs.components)
    return replace(obs, components=comps, notes={**obs.notes, "camera_centre_mm": np.asarray(centre, float)})


def _centre_nll(params, r, jac, g, rotation) -> tuple[float, np.ndarray]:
    """Minus the restricted log-likelihood at fixed ``X, T`` (constants dropped) of the variance
    components ``θ = CENTRE_THETA_FLOOR + exp(params[3:])`` (never below the floor, so every ``S_i``
    stays invertible), the board rotation components about the centre ``params[:3]``, and its
    gradient: ``½ (tr(W D) - tr(M C^T W D W C) - r^T W D W r)`` for ``D = dS/dp``."""
    lever = _lever(params[:3])
    with np.errstate(over="ignore"):  # a trial step of the optimiser far out: an infinite cost
        scale = np.exp(params[3:])
    if not np.all(np.isfinite(scale)):
        return float("inf"), np.zeros(len(params))
    theta = CENTRE_THETA_FLOOR + scale
    moved = np.array([lever @ gk @ lever.T if about else gk for gk, about in zip(g, rotation)])
    s = np.tensordot(theta, moved, axes=1)
    sign, logdet = np.linalg.slogdet(s)
    if np.any(sign <= 0):
        return float("inf"), np.zeros(len(params))
    w = np.linalg.inv(s)
    wj = w @ jac
    normal = _sum_t(jac, wj)
    sign_m, logdet_m = np.linalg.slogdet(normal)
    if sign_m <= 0:
        return float("inf"), np.zeros(len(params))
    wr = (w @ r[..., None])[..., 0]
    # every derivative D of S enters as sum_i <P_i, D_i>, P_i = W_i - (W C M C^T W)_i - W_i r_i r_i^T W_i
    p = w - wj @ np.linalg.inv(normal) @ np.swapaxes(wj, 1, 2) - wr[:, :, None] * wr[:, None, :]
    grad = np.empty(len(params))
    grad[3:] = (moved.reshape(len(moved), -1) @ p.reshape(-1)) * scale  # d / d params[3 + k]
    # d / dc_a: dS = sum_k θ_k (E_a G_k L^T + L G_k E_a^T), E_a = dL/dc_a, so <P, dS> = 2 <E_a, sum θ_k P L G_k>
    plg = np.sum(p @ lever @ np.tensordot(theta[rotation], g[rotation], axes=1), axis=0)
    grad[:3] = 2.0 * np.array([np.sum(skew(np.eye(3)[a]) * plg[:3, 3:]) for a in range(3)])
    value = 0.5 * float(np.sum(logdet) + logdet_m + np.einsum("ni,ni->", r, wr))
    return value, 0.5 * grad


def board_centre(obs: "Observations", fit: "MLFit", keep, start) -> tuple[np.ndarray, np.ndarray] | None:
    """The board point about which the board's rotation noise acts, by restricted maximum likelihood.

    ``obs`` holds the rotation components about the board origin; the residuals of ``fit`` (its
    ``X, T``) are held, the centre and the variance components (bounded below by
    :data:`CENTRE_THETA_FLOOR`) searched together (BFGS), over at most :data:`CENTRE_POSTURES` of
    the postures ``keep``. Returns the centre (mm) and the variance components, ``None`` when the
    search fails.
    """
    from scipy.optimize import minimize  # noqa: PLC0415

    keep = np.asarray(keep, bool)
    if keep.sum() > CENTRE_POSTURES:
        kept = np.flatnonzero(keep)
        keep = np.zeros_like(keep)
        keep[kept[np.linspace(0, len(kept) - 1, CENTRE_POSTURES).round().astype(int)]] = True
    sub = obs.subset(keep)
    rotation = np.array([c.side == "board" and c.name in _ROTATION_BASES for c in sub.components])
    start_theta = np.log(np.maximum(fit.theta - CENTRE_THETA_FLOOR, CENTRE_THETA_FLOOR))
    try:
        found = minimize(_centre_nll, np.concatenate([start, start_theta]), method="BFGS", jac=True,
                         args=(fit.residuals[keep], _jacobians(sub), _structures(sub, fit.x), rotation))
    except (np.linalg.LinAlgError, ValueError):
        return None
    if not (np.all(np.isfinite(found.x)) and np.isfinite(found.fun)):
        return None
    return found.x[:3], CENTRE_THETA_FLOOR + np.exp(found.x[3:])


def _centre_test(obs: "Observations", fit: "MLFit", keep, kinematic: bool):
    """Board rotation noise about a fitted centre (sessions of board poses), kept when the likelihood
    ratio of the restricted likelihoods exceeds :data:`CENTRE_LR`; the centre and the fit are found
    alternately (twice). Returns the observations and the fit to go on with, and the report."""
    rotation = [c.name for c in obs.components if c.side == "board" and c.name in _ROTATION_BASES]
    if obs.mode != "poses" or not rotation or 6 * int(np.sum(keep)) - 12 <= len(obs.components) + 3:
        return obs, fit, {"modelled": False, "reason": "board poses fitted to corners, or too few postures"}
    centre, current = np.zeros(3), fit
    for _ in range(2):
        found = board_centre(obs, current, keep, centre)
        if found is None:
            break
        centre = found[0]
        # the restricted likelihood can have more than one maximum (a component pinned at its floor):
        # from the search's components and from the usual start of every fit, the higher one
        fits = [fit_ml(centred(obs, centre), current.x, current.target, theta0, keep=keep, kinematic=kinematic,
                       kinematic0=fit.kinematic, kinematic_var0=fit.kinematic_var) for theta0 in (found[1], None)]
        current = max(fits, key=lambda f: f.loglik)
    lr = 2.0 * (current.loglik - fit.loglik)
    report = {"modelled": bool(lr > CENTRE_LR), "likelihood_ratio": float(lr), "threshold": CENTRE_LR}
    if not report["modelled"]:
        return obs, fit, report
    report["centre_mm"] = [float(v) for v in centre]
    return centred(obs, centre), current, report


# --------------------------------------------------------------------------------------- the fit
@dataclass(frozen=True)
class MLFit:
    """The ML solution over a set of postures.

    Attributes
    ----------
    x, target : ndarray, shape (4, 4)
        ``X`` and ``T`` (the board in the fixed frame).
    theta : ndarray, shape (k,)
        Variance components, in the order of ``Observations.components``.
    kinematic : ndarray, shape (q,)
        Estimated deviations of the robot's DH table (empty without a robot model).
    kinematic_var : ndarray, shape (2,)
        Their variance components: lengths (mm²) and angles (deg²).
    covariance : ndarray, shape (12, 12)
        Of the local twists ``(δx, δt)`` of ``X ⊕ δx``, ``T ⊕ δt`` (mm, rad), the kinematic
        deviations marginalised.
    residuals : ndarray, shape (n, 6)
        ``r_i`` of every posture of the observations (also those left out of the fit), kinematic
        deviations applied.
    mahalanobis : ndarray, shape (n,)
        ``d_i``.
    posture_cov : ndarray, shape (n, 6, 6)
        ``S_i``.
    iterations : int
    converged : bool
    loglik : float
        Restricted (REML) log-likelihood at the solution, for comparing noise models with the same
        fixed parameters ``X, T``.
    """

    x: np.ndarray
    target: np.ndarray
    theta: np.ndarray
    kinematic: np.ndarray
    kinematic_var: np.ndarray
    covariance: np.ndarray
    residuals: np.ndarray
    mahalanobis: np.ndarray
    posture_cov: np.ndarray
    iterations: int
    converged: bool
    loglik: float = float("nan")


def _residuals(obs: Observations, x, t, u=None, ju=None) -> np.ndarray:
    """``r_i = twist(T^-1 (A_i ⊕ K_i u) X B_i)`` to first order in ``u``; ``(n, 6)``."""
    r = twist_between(t, obs.hand @ x @ obs.board)
    if u is not None and len(u):
        r = r + ju @ u
    return r


def _jacobians(obs: Observations, ju=None) -> np.ndarray:
    """``d r / d(δx, δt, u)``: ``Ad_{B^-1}``, ``-I`` and ``Ad_{(X B)^-1} K_i``; ``(n, 6, 12 + q)``."""
    q = 0 if ju is None else ju.shape[2]
    jac = np.zeros((obs.n, 6, 12 + q))
    jac[:, :, :6] = adjoint(invert_transforms(obs.board))
    jac[:, :, 6:12] = -np.eye(6)
    if q:
        jac[:, :, 12:] = ju
    return jac


def _to_residual_frame(obs: Observations, x) -> np.ndarray:
    return adjoint(invert_transforms(x[None] @ obs.board))  # Ad_{(X B_i)^-1}


def _structures(obs: Observations, x) -> np.ndarray:
    """``G_ik`` in the residual frame, shape ``(k, n, 6, 6)``."""
    if not obs.components:
        return np.zeros((0, obs.n, 6, 6))
    ad = _to_residual_frame(obs, x)
    out = []
    for comp in obs.components:
        g = comp.structure
        out.append(ad @ g @ np.swapaxes(ad, 1, 2) if comp.side == "hand" else g)
    return np.array(out)


def _kinematic_jac(obs: Observations, x) -> np.ndarray | None:
    if obs.kinematic is None:
        return None
    return _to_residual_frame(obs, x) @ obs.kinematic


def _posture_cov(obs: Observations, g: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``S_i = F_i + sum_k θ_k G_ik``; ``(n, 6, 6)``."""
    s = obs.board_cov.copy()
    for value, structure in zip(theta, g):
        s += value * structure
    return 0.5 * (s + np.swapaxes(s, 1, 2))


def _prior(obs: Observations, lam: np.ndarray) -> np.ndarray:
    """Prior precision of ``(δx, δt, u)``: none on ``X, T``; ``Λ^-1`` on the DH deviations."""
    q = 0 if obs.kinematic is None else obs.kinematic.shape[2]
    prior = np.zeros((12 + q, 12 + q))
    if q:
        prior[12:, 12:] = np.diag(1.0 / lam[obs.kinematic_kinds])
    return prior


def _initial_theta(obs: Observations, g: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Each component alone explaining its share of the residual, block by block (rotation, translation)."""
    k = len(g)
    if k == 0:
        return np.zeros(0)
    excess = np.maximum(np.einsum("ni,nj->nij", r, r) - obs.board_cov, 0.0)
    theta = np.empty(k)
    for c in range(k):
        ratios = []
        for block in (slice(0, 3), slice(3, 6)):
            trace_g = np.trace(g[c][:, block, block], axis1=1, axis2=2).sum()
            if trace_g > 0:
                ratios.append(np.trace(excess[:, block, block], axis1=1, axis2=2).sum() / trace_g)
        theta[c] = max(min(ratios) / k, VARIANCE_FLOOR) if ratios else VARIANCE_FLOOR
    return theta


def _sum_t(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``sum_n a_n^T b_n`` for stacks ``(..., n, r, p)`` and ``(..., n, r, s)``: ``(..., p, s)``.

    Small per-posture products summed, rather than one tall matrix product: a tall product goes
    to a multi-threaded BLAS, which stalls when the machine's cores are busy.
    """
    return (np.swapaxes(a, -1, -2) @ b).sum(axis=-3)


def _normal(jac: np.ndarray, w: np.ndarray, prior: np.ndarray) -> np.ndarray:
    return _sum_t(jac, w @ jac) + prior


def _gauss_newton(obs: Observations, x, t, u, w: np.ndarray, prior: np.ndarray, steps: int):
    """Gauss-Newton on ``sum_i ρ_i^T W_i ρ_i + u^T Λ^-1 u``, ``ρ_i = r_i + J_u,i u`` (mixed-model equations)."""
    step = np.zeros(12)
    for _ in range(steps):
        ju = _kinematic_jac(obs, x)
        jac = _jacobians(obs, ju)
        rho = _residuals(obs, x, t, u, ju)
        p = jac.shape[2]
        wj = w @ jac
        normal = _sum_t(jac, wj) + prior
        grad = _sum_t(wj, rho[..., None])[:, 0]
        if p > 12:
            grad = grad + prior[:, 12:] @ u
        step = -np.linalg.solve(normal, grad)
        x = retract(x, step[:6])
        t = retract(t, step[6:12])
        u = u + step[12:]
        if _small(step):
            break
    return x, t, u, step


def _small(step) -> bool:
    return bool(np.all(np.abs(step[[0, 1, 2, 6, 7, 8]]) < STEP_TOL_MM) and np.all(np.abs(step[[3, 4, 5, 9, 10, 11]]) < STEP_TOL_RAD)
                and np.all(np.abs(step[12:]) < STEP_TOL_MM))


def _reml_score_information(g, wg, wj, a, m, quad, tr_pg, weight, theta, lam, u, kinds, kinds_present, pz, ztpz):
    """Score and Fisher information of the restricted likelihood in ``(θ, λ[kinds_present])``.

    The terms of :func:`_variance_step` (Henderson's form): ``½ (ρ^T S^-1 G_k S^-1 ρ - tr(P G_k))`` and
    ``½ (û_c^T û_c / λ_c² - tr(Z_c^T P Z_c))`` for the scores, ``½ tr(P V_a P V_b)`` for the information,
    with the boundary-avoiding prior's terms on the block components (``weight``).

    Returns
    -------
    score : ndarray, shape (k + c,)
    info : ndarray, shape (k + c, k + c)
    """
    k = len(theta)
    size = k + len(kinds_present)
    score = np.empty(size)
    info = np.empty((size, size))
    score[:k] = 0.5 * (quad - tr_pg) + 0.5 * weight / theta  # with the boundary-avoiding prior's score
    for i in range(k):
        for j in range(i, k):
            term1 = np.sum(wg[i] * np.swapaxes(wg[j], 1, 2))
            b = _sum_t(wj, g[i] @ (wg[j] @ wj))  # C^T S^-1 G_i S^-1 G_j S^-1 C
            term2 = np.trace(m @ b)
            term3 = np.trace(m @ a[i] @ m @ a[j])
            info[i, j] = info[j, i] = 0.5 * (term1 - 2.0 * term2 + term3)
        info[i, i] += 0.5 * weight[i] / theta[i] ** 2
    for ci, c in enumerate(kinds_present):
        sel = kinds == c
        score[k + ci] = 0.5 * (np.sum(u[sel] ** 2) / lam[c] ** 2 - np.trace(ztpz[np.ix_(sel, sel)]))
        for i in range(k):  # ½ tr(Z_c^T P G_i P Z_c)
            info[i, k + ci] = info[k + ci, i] = 0.5 * np.sum(pz[:, :, sel] * (g[i] @ pz[:, :, sel]))
        for di, d in enumerate(kinds_present):
            info[k + ci, k + di] = 0.5 * np.sum(ztpz[np.ix_(sel, kinds == d)] ** 2)
    return score, info


def _variance_step(g: np.ndarray, w: np.ndarray, theta: np.ndarray, rho: np.ndarray, jac: np.ndarray,
                   prior: np.ndarray, u: np.ndarray, lam: np.ndarray, kinds, fisher_scoring: bool,
                   boundary_prior: float = 0.0):
    """One REML update of the block components ``θ`` and the DH-deviation variances ``λ``, jointly.

    Henderson's mixed-model form: with ``C = [J_X, J_T, Z]`` (``Z = J_u``), ``M = (C^T S^-1 C + Π)^-1``
    (``Π`` the prior precision ``Λ^-1`` of the DH deviations), ``P = S^-1 - S^-1 C M C^T S^-1`` and
    ``P y = S^-1 ρ``, ``Z^T P y = Λ^-1 û``. Scores: ``½ (ρ^T S^-1 G_k S^-1 ρ - tr(P G_k))`` for a block
    component, ``½ (û_c^T û_c / λ_c² - tr(Z_c^T P Z_c))`` for a kind of DH entry; the information is
    ``½ tr(P V_a P V_b)`` for every pair (``V = G_k`` or ``Z_c Z_c^T``), all reduced to per-posture
    6x6 products and ``(12 + q)``-square sums. The first iterations take the positive fixed point
    (EM), then scale-free Fisher scoring with an active set at zero.

    Returns
    -------
    theta, lam : ndarray
    m : ndarray, shape (12 + q, 12 + q)
        ``M`` at the current values.
    """
    k = len(theta)
    p = jac.shape[2]
    q = p - 12
    wj = w @ jac                                      # (n, 6, p)
    m = np.linalg.inv(_sum_t(jac, wj) + prior)
    kinds_present = [c for c in range(len(lam)) if q and np.any(kinds == c)]
    if k == 0 and not kinds_present:
        return theta, lam, m
    wg = w[None] @ g                                  # S^-1 G_k, (k, n, 6, 6)
    wr = w @ rho[..., None]                           # (n, 6, 1)
    quad = np.sum((g @ wr[None]) * wr[None], axis=(1, 2, 3))
    gwj = g @ wj[None]                                # G_k S^-1 C, (k, n, 6, p)
    a = _sum_t(wj[None], gwj)                         # C^T S^-1 G_k S^-1 C, (k, p, p)
    tr_wg = np.trace(wg, axis1=2, axis2=3).sum(axis=1)  # tr(S^-1 G_k)
    tr_pg = tr_wg - np.sum(m[None] * np.swapaxes(a, 1, 2), axis=(1, 2))
    # A component whose effect the fixed parameters absorb (tr(P G) ~ 0 against tr(S^-1 G)) gets no
    # information from the restricted likelihood: it keeps its value, and the prior (improper,
    # rate -> 0) is not applied to it, as it would push it up without bound.
    informed = tr_pg > 1e-9 * tr_wg
    weight = np.where(informed, boundary_prior, 0.0)
    if q:
        z = jac[:, :, 12:]
        pz = w @ z - wj @ (m @ _sum_t(jac, w @ z))   # P Z, per posture (n, 6, q)
        ztpz = _sum_t(z, pz)                          # Z^T P Z, (q, q)
    if not fisher_scoring:
        return (*_em_update(theta, quad, tr_pg, weight, informed, lam, u, m, kinds, kinds_present), m)
    score, info = _reml_score_information(g, wg, wj, a, m, quad, tr_pg, weight, theta, lam, u, kinds, kinds_present,
                                          pz if q else None, ztpz if q else None)
    size = len(score)
    values = np.concatenate([theta, lam[kinds_present]])
    if not (np.all(np.isfinite(score)) and np.all(np.isfinite(info))):  # noise-free data: nothing to learn
        return theta, lam, m
    # scale-free step: in relative units δv / v; components pinned at the floor with a negative score
    # left out (active set); a component driven below zero stops at a hundredth of its value
    active = ~((values <= 10.0 * VARIANCE_FLOOR) & (score <= 0.0))
    rel = np.zeros(size)
    if active.any():
        scaled = info[np.ix_(active, active)] * np.outer(values[active], values[active])
        rhs = values[active] * score[active]
        if not (np.all(np.isfinite(scaled)) and np.all(np.isfinite(rhs))):
            return theta, lam, m
        rel[active] = np.linalg.lstsq(scaled, rhs, rcond=1e-12)[0]
    values = np.maximum(values * (1.0 + np.maximum(rel, -0.99)), VARIANCE_FLOOR)
    new_lam = lam.copy()
    new_lam[kinds_present] = values[k:]
    return values[:k], new_lam, m


#: Weight of the boundary-avoiding prior on the variance components in the outlier test's fits:
#: ``log p(σ_k) = BOUNDARY_PRIOR log σ_k``, a gamma(2, rate -> 0) prior on each standard deviation
#: (Chung, Rabe-Hesketh, Dorie, Gelman and Liu, Psychometrika 78, 2013), i.e. the restricted likelihood
#: plus ``½ BOUNDARY_PRIOR log θ_k``. With few postures a component the data hardly determine is
#: otherwise estimated at exactly zero (18 of 60 clean six-pose sets of OpenCV's model), and a
#: posture is then tested against a covariance that calls its ordinary error in that direction
#: impossible. The estimate of ``X`` keeps the plain restricted likelihood: where a noise source is
#: truly absent (a simulated robot without noise) the prior's pull off zero costs accuracy.
BOUNDARY_PRIOR = 1.0


def _em_update(theta, quad, tr_pg, weight, informed, lam, u, m, kinds, kinds_present) -> tuple[np.ndarray, np.ndarray]:
    """The EM (positive fixed point) update of the block components and the DH-deviation variances.

    Block components: the fixed point of the score ``½ (quad - tr(P G)) + weight / (2 θ)``; the
    components the restricted likelihood does not inform keep their values.
    """
    new_theta = np.where(informed, (theta * quad + weight) / np.where(informed, tr_pg, 1.0), theta)
    new_lam = lam.copy()
    for c in kinds_present:
        sel = kinds == c
        m_uu = m[12:, 12:][np.ix_(sel, sel)]
        new_lam[c] = max((np.sum(u[sel] ** 2) + np.trace(m_uu)) / sel.sum(), VARIANCE_FLOOR)
    return np.maximum(new_theta, VARIANCE_FLOOR), new_lam


#: Start of the DH-deviation variances (mm², deg²): a start for EM, which takes it from here.
KINEMATIC_START = np.array([0.1**2, 0.01**2])


def _damped(theta, lam, new, new_lam, last_delta):
    """The variance step, damped: alternating with the fit, confounded components can overshoot back
    and forth, so a component's step is halved when it turns against the previous one. Returns the
    new ``theta``, the new kinematic variances and the step taken."""
    delta = np.concatenate([new - theta, new_lam - lam])
    flip = delta * last_delta < 0
    if flip.any():
        delta = np.where(flip, 0.5 * delta, delta)
        new, new_lam = theta + delta[:len(theta)], lam + delta[len(theta):]
    return new, new_lam, delta


def fit_ml(obs: Observations, x0: np.ndarray, t0: np.ndarray | None = None, theta0: np.ndarray | None = None,
           estimate_theta: bool = True, keep=None, kinematic0=None, kinematic_var0=None,
           kinematic: bool = True, boundary_prior: float = 0.0) -> MLFit:
    """The ML solution over the postures ``keep`` (default all), from a start ``x0``.

    Parameters
    ----------
    obs : Observations
    x0 : ndarray, shape (4, 4)
    t0 : ndarray, shape (4, 4), optional
        Start for ``T``; default :func:`initial_board_pose`.
    theta0 : ndarray, shape (k,), optional
        Start (or, with ``estimate_theta=False``, fixed values) of the variance components.
    keep : array-like of bool, shape (n,), optional
        Postures taking part; residuals and ``d_i`` are returned for all.
    kinematic0, kinematic_var0 : ndarray, optional
        Start of the DH deviations and (fixed with ``estimate_theta=False``) of their variances.
    kinematic : bool
        Model the arm's DH deviations (when the observations have them); ``False``: the robot's
        errors are independent from posture to posture.
    boundary_prior : float
        Weight of the boundary-avoiding prior on the variance components (:data:`BOUNDARY_PRIOR`);
        0, the default, is the plain restricted likelihood.
    """
    keep = np.ones(obs.n, bool) if keep is None else np.asarray(keep, bool)
    if not kinematic and obs.kinematic is not None:
        obs = replace(obs, kinematic=None, kinematic_kinds=None)
    sub = obs.subset(keep)
    q = 0 if sub.kinematic is None else sub.kinematic.shape[2]
    x = np.array(x0, float)
    t = initial_board_pose(sub, x) if t0 is None else np.array(t0, float)
    u = np.zeros(q) if kinematic0 is None or q == 0 else np.array(kinematic0, float)
    lam = KINEMATIC_START.copy() if kinematic_var0 is None else np.array(kinematic_var0, float)
    prior = _prior(sub, lam)
    g = _structures(sub, x)
    if theta0 is None:  # rough weights (1 mm, 1 mrad) for a first fit, then a start per component
        w0 = np.linalg.inv(_posture_cov(sub, g, np.zeros(len(g))) + _unit_floor())
        x, t, u, _ = _gauss_newton(sub, x, t, u, w0, prior, 3)
        theta = _initial_theta(sub, g, _residuals(sub, x, t, u, _kinematic_jac(sub, x)))
    else:
        theta = np.array(theta0, float)
    converged = False
    outer = 0
    last_delta = np.zeros(len(theta) + len(lam))
    for outer in range(1, MAX_OUTER + 1):
        g = _structures(sub, x)
        w = np.linalg.inv(_posture_cov(sub, g, theta))
        x, t, u, step = _gauss_newton(sub, x, t, u, w, prior, 2)
        if not estimate_theta or (len(theta) == 0 and q == 0):
            if _small(step):
                converged = True
                break
            continue
        ju = _kinematic_jac(sub, x)
        jac = _jacobians(sub, ju)
        rho = _residuals(sub, x, t, u, ju)
        new, new_lam, _ = _variance_step(g, w, theta, rho, jac, prior, u, lam, sub.kinematic_kinds,
                                         fisher_scoring=outer > 3, boundary_prior=boundary_prior)
        new, new_lam, last_delta = _damped(theta, lam, new, new_lam, last_delta)
        change = np.max(np.abs(new - theta) / np.maximum(theta, VARIANCE_FLOOR)) if len(theta) else 0.0
        if q:
            change = max(change, np.max(np.abs(new_lam - lam) / lam))
            lam = new_lam
            prior = _prior(sub, lam)
        theta = new
        if change < THETA_TOL and _small(step):
            converged = True
            break
    return _finished_fit(obs, sub, x, t, u, theta, lam, prior, outer, converged)


def _finished_fit(obs: Observations, sub: Observations, x, t, u, theta, lam, prior, outer: int,
                  converged: bool) -> MLFit:
    """The :class:`MLFit` of a converged fit over ``sub``: the covariance of X, the REML
    log-likelihood, and residuals with Mahalanobis distances for every posture of ``obs``."""
    g = _structures(sub, x)
    s = _posture_cov(sub, g, theta)
    ju = _kinematic_jac(sub, x)
    jac = _jacobians(sub, ju)
    w = np.linalg.inv(s)
    mme = _normal(jac, w, prior)
    cov = np.linalg.inv(mme)[:12, :12]
    loglik = _reml_loglik(sub, s, w, mme, _residuals(sub, x, t, u, ju), u, lam)
    g_all = _structures(obs, x)
    s_all = _posture_cov(obs, g_all, theta)
    r_all = _residuals(obs, x, t, u, _kinematic_jac(obs, x))
    d = np.sqrt(np.maximum(np.einsum("ni,ni->n", r_all, np.linalg.solve(s_all, r_all[..., None])[..., 0]), 0.0))
    return MLFit(x, t, theta, u, lam, 0.5 * (cov + cov.T), r_all, d, s_all, outer, converged, loglik)


def _reml_loglik(obs: Observations, s, w, mme, rho, u, lam) -> float:
    """``-½ (log det R + log det Λ + log det MME + ρ^T R^-1 ρ + u^T Λ^-1 u)``, constants dropped.

    The restricted likelihood of the mixed model in Henderson's form: ``R`` the block-diagonal
    posture covariances, ``Λ`` the DH-deviation variances, ``MME = C^T R^-1 C + Π``.
    """
    logdet_r = float(np.sum(np.linalg.slogdet(s)[1]))
    logdet_m = float(np.linalg.slogdet(mme)[1])
    quad = float(np.einsum("ni,nij,nj->", rho, w, rho))
    logdet_l = 0.0
    if obs.kinematic is not None and len(u):
        var = lam[obs.kinematic_kinds]
        logdet_l = float(np.sum(np.log(var)))
        quad += float(np.sum(u * u / var))
    return -0.5 * (logdet_r + logdet_l + logdet_m + quad)


def _unit_floor() -> np.ndarray:
    return np.diag([1.0, 1.0, 1.0, 1e-6, 1e-6, 1e-6])  # 1 mm and 1 mrad: the start's weights only


def initial_board_pose(obs: Observations, x: np.ndarray) -> np.ndarray:
    """``T`` from ``X``: the chordal mean of ``A_i X B_i`` (rotation by SVD, translation by the mean)."""
    chain = obs.hand @ x @ obs.board
    u, _, vt = np.linalg.svd(chain[:, :3, :3].mean(axis=0))
    rot = u @ vt
    if np.linalg.det(rot) < 0:
        rot = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = chain[:, :3, 3].mean(axis=0)
    return out


# ------------------------------------------------------------------------------ start helpers
def angle_gaps_deg(hand: np.ndarray, board: np.ndarray) -> np.ndarray:
    """Per posture: median over the others of ``|angle(A_ij) - angle(B_ij)|`` (eq. 30, X-free), degrees.

    ``A_ij = A_i^-1 A_j`` and ``B_ij = B_i B_j^-1`` rotate by the same angle for the true motion
    whatever ``X`` is; the angles come from quaternion dot products. Over every pair of a small set,
    over ``invariants.bounded_pairs`` (neighbours in time and random partners) of a large one.
    """
    qa = quaternion_from_matrix(hand[:, :3, :3])
    qb = quaternion_from_matrix(board[:, :3, :3])
    pairs = bounded_pairs(len(qa))
    i, j = pairs[:, 0], pairs[:, 1]
    angle_a = 2.0 * np.arccos(np.clip(np.abs(np.einsum("pi,pi->p", qa[i], qa[j])), 0.0, 1.0))
    # the angle of B_i B_j^-1 is the angle between R_Bi and R_Bj, as for A_i^-1 A_j
    angle_b = 2.0 * np.arccos(np.clip(np.abs(np.einsum("pi,pi->p", qb[i], qb[j])), 0.0, 1.0))
    return np.degrees(posture_medians(np.abs(angle_a - angle_b), pairs, len(qa)))


def varied_rotation_subset(hand: np.ndarray, candidates: np.ndarray, size: int) -> np.ndarray:
    """Indices (sorted) of ``size`` postures among ``candidates`` spread over the hand rotations.

    Farthest-point sampling on the rotation angle between hand orientations, from the posture
    nearest the mean orientation: relative motions between the chosen postures are then large and
    about varied axes, as mcb needs.
    """
    candidates = np.asarray(candidates)
    if len(candidates) <= size:
        return np.sort(candidates)
    q = quaternion_from_matrix(hand[candidates, :3, :3])
    mean = np.linalg.eigh(q.T @ q)[1][:, -1]
    chosen = [int(np.argmax(np.abs(q @ mean)))]
    dist = 2.0 * np.arccos(np.clip(np.abs(q @ q[chosen[0]]), 0.0, 1.0))
    while len(chosen) < size:
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, 2.0 * np.arccos(np.clip(np.abs(q @ q[nxt]), 0.0, 1.0)))
    return np.sort(candidates[chosen])


# ---------------------------------------------------------------------------------- the pipeline
@dataclass(frozen=True)
class EivSolution:
    """What :func:`solve_eiv` returns: the answer and everything the result reports.

    Attributes
    ----------
    x : ndarray, shape (4, 4)
    outliers : ndarray of bool, shape (n,)
    residuals_mm : ndarray, shape (n,)
        The fit residual the outliers are judged on, per posture: mean distance of its three compact
        board points, carried into the fixed frame, from the fitted board ``T`` (all postures, outliers
        too). Not reported as the posture residual (``quality_words.posture_residuals``).
    fit : MLFit
        Over the inliers.
    observations : Observations
    uncertainty : dict
    details : dict
    cross_validation : dict or None
        ``CrossValidation.to_dict`` with the systematic-error verdict: the ratio test, or the
        arm's kinematic deviations found by the likelihood-ratio test.
    cv : CrossValidation or None
    """

    x: np.ndarray
    outliers: np.ndarray
    residuals_mm: np.ndarray
    fit: MLFit
    observations: Observations
    uncertainty: dict
    details: dict
    cross_validation: dict | None
    cv: object | None = None


def _mcb_start(problem: HandEyeProblem, subset: np.ndarray) -> tuple[np.ndarray, dict]:
    """Algorithm 1 with selection by d_back (eq. 23), the paper's mcb, on the postures ``subset``."""
    from .paper import solve_paper  # noqa: PLC0415
    from .selection import least_d_back  # noqa: PLC0415

    x, details = solve_paper(problem.subset(subset), least_d_back)
    return x, {"method": "mcb", "postures": int(len(subset)), "candidates": details["candidates"],
               "selected_triplet": details["selected_triplet"], "criterion_value": float(details["criterion_value"])}


def _compact_residuals(problem: HandEyeProblem, x: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Mean distance per posture of ``A_i X c_ik`` from ``T c_k`` over the three compact points, mm."""
    c = problem.compact
    model = c.target_points @ target[:3, :3].T + target[:3, 3]
    return np.linalg.norm(fixed_points(problem.hand, x, c.points) - model[None], axis=-1).mean(axis=1)


def _start(problem: HandEyeProblem, obs: Observations, gap_flags: np.ndarray) -> tuple[np.ndarray, dict]:
    """mcb on (a spread subset of) the invariant-consistent postures; mcb on all of them, then the
    paper's MC, when that subset is degenerate."""
    from .errors import CalibrationError  # noqa: PLC0415
    from .triplets import all_postures_solution  # noqa: PLC0415

    candidates = np.flatnonzero(~gap_flags)
    attempts = [varied_rotation_subset(obs.hand, candidates, START_POSTURES)]
    if len(candidates) > START_POSTURES:
        attempts.append(varied_rotation_subset(obs.hand, np.arange(problem.n), START_POSTURES))
    for subset in attempts:
        try:
            return _mcb_start(problem, subset)
        except (ValueError, CalibrationError, np.linalg.LinAlgError):
            continue
    return all_postures_solution(problem), {"method": "mc", "postures": problem.n}


def _parent_covariance(fit: MLFit) -> np.ndarray:
    """Covariance of (δt mm, δθ deg) of ``X`` in its parent frame (``t + R ρ``, ``exp(Rφ) R``)."""
    rot = fit.x[:3, :3]
    block = np.zeros((6, 6))
    block[:3, :3] = rot
    block[3:, 3:] = rot
    cov = block @ fit.covariance[:6, :6] @ block.T
    scale = np.array([1.0, 1.0, 1.0, 180.0 / np.pi, 180.0 / np.pi, 180.0 / np.pi])
    return cov * np.outer(scale, scale)


def _noise_report(obs: Observations, fit: MLFit) -> dict:
    """The estimated noise levels, in the units an operator reads."""
    out: dict = {"camera": {}, "robot": {}}
    if obs.corner is not None:
        out["camera"]["corner_isotropic_mm"] = float(np.sqrt(obs.corner.isotropic_mm2))
        out["camera"]["stereo_pixel_px"] = float(np.sqrt(obs.corner.pixel_px2))
        out["camera"]["corner_rms_mm"] = float(np.sqrt(np.mean(np.trace(obs.point_cov, axis1=-2, axis2=-1))))
        out["camera"]["degrees_of_freedom"] = int(obs.corner.dof)
    board_cov = obs.board_cov.copy()
    if "camera_centre_mm" in obs.notes:  # tilt and spin turn the board about this board point
        out["camera"]["rotation_centre_mm"] = [float(v) for v in obs.notes["camera_centre_mm"]]
    for comp, theta in zip(obs.components, fit.theta):
        if comp.name == "joint":
            out["robot"]["joint_deg"] = float(np.sqrt(theta))
        elif comp.name == "flange_rotation":
            out["robot"]["flange_rotation_deg"] = float(np.degrees(np.sqrt(theta)))
        elif comp.name == "flange_translation":
            out["robot"]["flange_translation_mm"] = float(np.sqrt(theta))
        elif comp.name == "camera_tilt":
            out["camera"]["board_tilt_deg"] = float(np.degrees(np.sqrt(theta)))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "camera_spin":
            out["camera"]["board_spin_deg"] = float(np.degrees(np.sqrt(theta)))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "camera_depth":
            out["camera"]["board_depth_mm"] = float(np.sqrt(theta))
            board_cov = board_cov + theta * comp.structure
        elif comp.name == "position":
            out["position_mm"] = float(np.sqrt(theta))
            out["position_note"] = "isotropic position noise of the flange or of the board: the data cannot tell which"
            board_cov = board_cov + theta * comp.structure
    hand = sum((theta * comp.structure for comp, theta in zip(obs.components, fit.theta) if comp.side == "hand"),
               np.zeros((obs.n, 6, 6)))
    out["robot"]["flange_position_rms_mm"] = float(np.sqrt(np.mean(np.trace(hand[:, :3, :3], axis1=1, axis2=2))))
    out["robot"]["flange_rotation_rms_deg"] = float(np.degrees(np.sqrt(np.mean(np.trace(hand[:, 3:, 3:], axis1=1, axis2=2)))))
    out["camera"]["board_position_rms_mm"] = float(np.sqrt(np.mean(np.trace(board_cov[:, :3, :3], axis1=1, axis2=2))))
    out["camera"]["board_rotation_rms_deg"] = float(np.degrees(np.sqrt(np.mean(np.trace(board_cov[:, 3:, 3:], axis1=1, axis2=2)))))
    return out


def ml_cross_validation(obs: Observations, fit: MLFit, keep: np.ndarray, folds: int, kinematic: bool = False):
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
    from .crossval import CrossValidation, fold_assignment, held_out_errors  # noqa: PLC0415

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


def _outlier_flags(problem: HandEyeProblem, obs: Observations, fit: MLFit, keep: np.ndarray, kinematic: bool,
                   gaps: np.ndarray, gap_flags: np.ndarray) -> np.ndarray:
    """The outlier postures after a fit, shape (n,) of bool.

    The ML's own test decides: the angle-gap and start flags only kept postures out of the start, and
    a posture must also be unlikely under the noise model fitted WITHOUT it (:func:`deleted_mahalanobis`,
    F distribution, Bonferroni over the postures), so small clean sets keep every posture. A posture
    that breaks the X-free angle invariant stays out when the fit confirms it (5 % shared among the
    flagged postures) and its angle gap is also three times what the fitted rotation noise explains:
    the median of |N(0, v_i + v_j)| is 0.674 sqrt(v_i + v_j).
    """
    from .refine import RESIDUAL_FLOOR_MM, at_most_half, robust_outliers  # noqa: PLC0415

    n = problem.n
    residual_mm = _compact_residuals(problem, fit.x, fit.target)
    level = GAP_CONFIRM_P / max(int(gap_flags.sum()), 1)
    v = np.trace(fit.posture_cov[:, 3:, 3:], axis1=1, axis2=2) / 3.0  # rad² per axis
    expected = np.degrees(0.674 * np.sqrt(v + np.median(v)))
    suspects = robust_outliers(fit.mahalanobis) & (residual_mm > RESIDUAL_FLOOR_MM)
    breaking = gap_flags & (gaps > GAP_CONFIRM_Z * expected) & (residual_mm > RESIDUAL_FLOOR_MM)
    flags = np.zeros(n, bool)
    for i in np.flatnonzero(suspects | breaking):
        d2, nu = deleted_mahalanobis(obs, fit, keep, i, kinematic)
        if nu > 0:
            flags[i] = (suspects[i] and d2 > 6.0 * f_dist.ppf(1.0 - OUTLIER_P / n, 6, nu)) or \
                       (breaking[i] and d2 > 6.0 * f_dist.ppf(1.0 - level, 6, nu))
    return at_most_half(flags, fit.mahalanobis)


def deleted_mahalanobis(obs: Observations, fit: MLFit, keep: np.ndarray, i: int, kinematic: bool) -> tuple[float, int]:
    """Posture ``i`` against the fit of the other postures: ``d²_(i)`` and its residual degrees of freedom.

    ``d²_(i) = r_i^T (S_i + J_i C J_i^T)^-1 r_i`` with ``X, T``, the noise levels ``θ`` and ``C`` (the
    covariance of ``X, T``) all from the postures ``keep`` without ``i``: the externally studentised
    distance of regression diagnostics, which an outlier cannot hide by inflating the noise it is
    measured against. The noise levels of this fit carry the boundary-avoiding prior
    (:data:`BOUNDARY_PRIOR`), so that no component the other postures hardly determine is zero.

    With the noise levels estimated from ``ν = 6 n' - 12 - k`` residual degrees of freedom (``n'``
    postures, ``k`` components), ``d²_(i) / 6`` follows an ``F(6, ν)`` distribution (exact for one
    component, Hotelling), not a chi-square: with few postures the estimated noise levels are
    themselves uncertain, and a chi-square test flags clean postures far more often than its level.
    """
    others = np.asarray(keep, bool).copy()
    others[i] = False
    fit = fit_ml(obs, fit.x, fit.target, fit.theta, keep=others, kinematic0=fit.kinematic,
                 kinematic_var0=fit.kinematic_var, kinematic=kinematic, boundary_prior=BOUNDARY_PRIOR)
    jac = _jacobians(obs.subset(np.array([i])))[0, :, :12]
    cov = fit.posture_cov[i] + jac @ fit.covariance @ jac.T
    r = fit.residuals[i]
    return float(r @ np.linalg.solve(cov, r)), int(6 * others.sum() - 12 - len(fit.theta))


def _uncertainty(fit: MLFit, kinematic: bool) -> dict:
    """The result's ``uncertainty`` entry: one-sigma values and the covariance of X in its parent frame."""
    cov = _parent_covariance(fit)
    return {
        "translation_mm": [float(v) for v in np.sqrt(np.maximum(np.diag(cov)[:3], 0.0))],
        "rotation_deg": [float(v) for v in np.sqrt(np.maximum(np.diag(cov)[3:], 0.0))],
        "covariance": [[float(v) for v in row] for row in cov],
        "covariance_units": "x, y, z (mm) and rotations about x, y, z (deg) of the camera pose in its parent frame",
        "level": "one sigma from the maximum-likelihood covariance with noise levels estimated from the data"
                 + ("; includes the uncertainty of the arm's kinematic deviations (details.kinematics)" if kinematic
                    else "; the robot's errors modelled as independent from posture to posture")
                 + "; cross_validation checks it on held-out postures",
    }


def solve_eiv(problem: HandEyeProblem, progress=None, folds: int | None = None) -> EivSolution:
    """The default estimator: robust start, ML fit with outlier loop, covariance and cross-validation.

    Parameters
    ----------
    problem : HandEyeProblem
    progress : callable, optional
        ``progress(done, total, label)`` after each stage (start, each fit round, each fold).
    folds : int, optional
        Cross-validation folds (default ``crossval.DEFAULT_FOLDS``; 0 skips the cross-validation).
    """
    from .crossval import DEFAULT_FOLDS  # noqa: PLC0415
    from .refine import ANGLE_GAP_FLOOR_DEG, RESIDUAL_FLOOR_MM, at_most_half, keep_majority, robust_outliers  # noqa: PLC0415

    folds = DEFAULT_FOLDS if folds is None else folds
    n = problem.n
    report = progress or (lambda done, total, label: None)
    total = 3 + folds
    obs = observations(problem)
    gaps = angle_gaps_deg(obs.hand, obs.board)
    gap_flags = keep_majority(robust_outliers(gaps, ANGLE_GAP_FLOOR_DEG), MIN_POSTURES)
    x, start = _start(problem, obs, gap_flags)
    report(1, total, f"start: {start['method']} on {start['postures']} postures")
    # gross outliers of the start: point residuals far out of the others' spread
    start_target = initial_board_pose(obs.subset(~gap_flags), x)
    start_res = _compact_residuals(problem, x, start_target)
    flags = at_most_half(gap_flags | robust_outliers(start_res, RESIDUAL_FLOOR_MM), start_res)
    fit = None
    rounds = 0
    kinematic = False  # posture-independent robot errors until the test below says otherwise
    tested = obs.kinematic is None
    lr = centre = None
    for rounds in range(1, MAX_ROUNDS + 2):
        keep = ~flags
        warm = {} if fit is None else {"t0": fit.target, "theta0": fit.theta, "kinematic0": fit.kinematic,
                                       "kinematic_var0": fit.kinematic_var}
        fit = fit_ml(obs, x, keep=keep, kinematic=kinematic, **warm)
        if not tested:
            # Kinematic deviations of the arm (the same at every posture): kept only when they raise
            # the restricted likelihood significantly (likelihood ratio above KINEMATIC_LR).
            tested = True
            kin_fit = fit_ml(obs, fit.x, fit.target, fit.theta, keep=keep, kinematic=True)
            lr = 2.0 * (kin_fit.loglik - fit.loglik)
            if lr > KINEMATIC_LR:
                fit, kinematic = kin_fit, True
        if centre is None:  # board poses only: the board's rotation noise about a fitted centre (CENTRE_LR)
            obs, fit, centre = _centre_test(obs, fit, keep, kinematic)
        x = fit.x
        new_flags = _outlier_flags(problem, obs, fit, keep, kinematic, gaps, gap_flags)
        report(1 + rounds, total + rounds, f"ML fit, round {rounds}: {int(new_flags.sum())} outlier postures")
        if n - new_flags.sum() < MIN_POSTURES or np.array_equal(new_flags, flags) or rounds > MAX_ROUNDS:
            break
        flags = new_flags
    keep = ~flags
    residual_mm = _compact_residuals(problem, fit.x, fit.target)
    uncertainty = _uncertainty(fit, kinematic)
    cv = cv_dict = None
    if folds and keep.sum() >= max(2 * MIN_POSTURES, folds):
        cv = ml_cross_validation(obs, fit, keep, folds, kinematic)
        cv_dict = cv.to_dict(problem.posture_ids)
        if kinematic:
            cv_dict["systematic"] = True
            cv_dict["advice"] = KINEMATIC_ADVICE + ("; " + cv_dict["advice"] if "advice" in cv_dict else "")
        report(total + rounds, total + rounds, "cross-validation done")
    details = _details(problem, obs, fit, start, rounds, _kinematic_report(obs, fit, kinematic, lr), centre, gaps)
    return EivSolution(fit.x, flags, residual_mm, fit, obs, uncertainty, details, cv_dict, cv)


def _details(problem: HandEyeProblem, obs: Observations, fit: MLFit, start: dict, rounds: int, kinematics: dict,
             centre: dict, gaps: np.ndarray) -> dict:
    """The result's ``details`` entry of the default estimator."""
    return {
        "estimator": "maximum likelihood, errors in variables (calibration/eiv.py)",
        "start": start,
        "outlier_rounds": rounds,
        "fit": {"iterations": int(fit.iterations), "converged": bool(fit.converged), "mode": obs.mode,
                "components": {c.name: float(t) for c, t in zip(obs.components, fit.theta)}},
        "kinematics": kinematics,
        "camera_centre": centre,
        "noise": _noise_report(obs, fit),
        "mahalanobis": {str(int(i)): float(d) for i, d in zip(problem.posture_ids, fit.mahalanobis)},
        "angle_gap_deg": {str(int(i)): float(g) for i, g in zip(problem.posture_ids, gaps)},
        "target_pose": {"position_mm": [float(v) for v in fit.target[:3, 3]],
                        "rotation_matrix": [[float(v) for v in row] for row in fit.target[:3, :3]]},
    }


MAX_ROUNDS = 5
#: Probability that a clean posture set loses a posture to the outlier test (chi-square part).
OUTLIER_P = 1e-3
#: Level at which the fit confirms the postures that break the angle invariant (eq. 30), shared
#: among them (Bonferroni).
GAP_CONFIRM_P = 0.05
GAP_CONFIRM_Z = 3.0
KINEMATIC_ADVICE = (
    "the robot's errors are systematic: its kinematics differ from the nominal model (a likelihood-ratio test "
    "finds DH deviations, details.kinematics). They were estimated with the camera pose and their uncertainty is "
    "in the one-sigma values; positions the controller computes with its nominal model keep these errors: calibrate "
    "the robot, or measure in postures near the calibration postures")
#: Likelihood ratio above which the arm's kinematic deviations enter the model (chi-square with two
#: degrees of freedom: p = 0.001).
KINEMATIC_LR = 13.8


def _kinematic_report(obs: Observations, fit: MLFit, used: bool, lr) -> dict:
    if obs.kinematic is None:
        return {"modelled": False, "reason": "no joint angles with a known robot model in the session"}
    out = {"modelled": bool(used), "likelihood_ratio": None if lr is None else float(lr), "threshold": KINEMATIC_LR}
    if used:
        out["sigma_length_mm"] = float(np.sqrt(fit.kinematic_var[0]))
        out["sigma_angle_deg"] = float(np.sqrt(fit.kinematic_var[1]))
        names = [f"{p}{axis + 1}" for axis in range(len(fit.kinematic) // 4) for p in ("d", "a", "alpha", "theta")]
        out["dh_deviation"] = {name: float(v) for name, v in zip(names, fit.kinematic)}
        out["note"] = ("the arm differs from its nominal kinematics; deviations that are the same at every posture "
                       "are estimated with the camera pose and their uncertainty is in the one-sigma values")
    return out
