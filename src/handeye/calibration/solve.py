"""One entry point: a session (or problem) and a method name in, a :class:`CalibrationResult` out.

Input checks live here, with messages an operator can act on; the solvers behind assume clean data.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable, TypeVar, cast

import numpy as np

from .compact_points import compact_points_from_corners, compact_points_from_poses
from .consistency import consistent_majority
from ..base import CalibrationError, HandEyeError, brief, exception_line
from .invariants import bounded_pairs
from ..robot import load_robot
from .methods import DEFAULT_METHOD, METHODS, Method, get_method, method_names
from .metrics import axxb_residuals, d_back, d_org, errors_against_truth, fixed_points
from .paper import solve_paper, truth_board_points
from .plausibility import check_plausible
from .problem import EYE_IN_HAND, MIN_POSTURES, HandEyeProblem, hand_poses
from .quality_words import (
    MIN_AXIS_ANGLE_DEG,
    MIN_AXIS_DIVERGENCE_DEG,
    posture_residual_meaning,
    posture_residuals,
    relative_rotation_angles_deg,
    residual_points,
    rotation_axis_divergence_deg,
    usable_axes,
)
from .session import Session
from ..base import TIME_VARIABLE, OutOfTime, call_within
from ..geometry import pose_from_transform, rigid_defect, transform_from_pose
from .triplets import relative_motions

_T = TypeVar("_T")

__all__ = [
    "PAPER_METHODS",
    "ROBUST_METHOD",
    "ML_METHOD",
    "DEFAULT_METHOD",
    "ALL_METHODS",
    "CalibrationResult",
    "problem_from_session",
    "check_motion",
    "calibrate",
    "calibrate_within",
    "bounded_for",
    "calibrate_session",
    "method_row",
    "truth_from_dict",
]

#: The ``robust`` estimator's name (mcb, outlier postures out, robust refinement, uncertainty).
ROBUST_METHOD = "robust"
#: The recommended default's name (``methods.DEFAULT_METHOD``): maximum likelihood with errors in variables.
ML_METHOD = DEFAULT_METHOD


def __getattr__(name: str):
    """``ALL_METHODS`` (every name ``calibrate`` accepts) and ``PAPER_METHODS`` (the paper's variants),
    read from the methods table now, so they hold the methods of installed plug-ins too."""
    if name == "ALL_METHODS":
        return method_names()
    if name == "PAPER_METHODS":
        return method_names("paper")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


MIN_ROTATION_DEG = MIN_AXIS_ANGLE_DEG


@dataclass
class CalibrationResult:
    """The answer of one method on one data set.

    Attributes
    ----------
    method : str
    setup : str
    x : ndarray, shape (4, 4)
        ``cam2tool0`` (eye-in-hand) or ``cam2base`` (eye-to-hand), mm.
    metrics : dict
        ``d_org_mm``, ``d_back_mm`` (eq. 22-23, on the full point set), ``delta_r`` and
        ``delta_t_mm`` (eq. 16, RMS over all posture pairs), and which points were used.
    residuals_mm : dict
        Per posture index (outliers too): its posture residual, the same word for every method
        (``quality_words.posture_residuals``: its board points carried into the fixed frame through X,
        from their mean over the kept postures; eq. 21-22).
    outliers : list of int
        Posture indices judged inconsistent (empty for methods that do not judge).
    runtime_s : float
        The solve alone.
    details : dict
        Method-specific information (chosen triplet, candidate counts, ...).
    truth_errors : dict or None
        Errors against the known truth (synthetic sessions).
    uncertainty : dict or None
        One-sigma ``translation_mm`` (x, y, z) and ``rotation_deg`` (about x, y, z) of X.
    cross_validation : dict or None
        Posture-level cross-validation (``crossval.CrossValidation.to_dict``): held-out prediction
        error of the board points, what the noise model predicts, and whether the error is systematic.
    excluded : dict
        ``{posture index: reason}`` of gross postures left out before solving (``problem.excluded``);
        they are among ``outliers`` too.
    residuals_on : str
        The points ``residuals_mm`` (and d_org) are measured on, a key of
        ``quality_words.RESIDUAL_POINTS``: ``"corners"`` (the board corners) or ``"compact"`` (the three
        compact points of a session of board poses); the same for every method on one session.
    """

    method: str
    setup: str
    x: np.ndarray
    metrics: dict
    residuals_mm: dict
    outliers: list
    runtime_s: float
    details: dict = field(default_factory=dict)
    truth_errors: dict | None = None
    uncertainty: dict | None = None
    cross_validation: dict | None = None
    excluded: dict = field(default_factory=dict)
    residuals_on: str = "corners"

    @property
    def parent(self) -> str:
        return "tool0" if self.setup == EYE_IN_HAND else "base"

    @property
    def residuals_meaning(self) -> str:
        """The one text of what ``residuals_mm`` are (``quality_words.posture_residual_meaning``)."""
        return posture_residual_meaning(self.residuals_on)

    def to_json(self) -> dict:
        """The JSON of ``handeye calibrate --json`` (conventions.md)."""
        out = {
            "method": self.method,
            "setup": self.setup,
            "camera_pose": {"parent": self.parent, **pose_from_transform(self.x)},
            "metrics": self.metrics,
            "outliers": [int(i) for i in self.outliers],
            "runtime_s": self.runtime_s,
            "posture_residuals_mm": {str(k): v for k, v in self.residuals_mm.items()},
            "posture_residuals_meaning": self.residuals_meaning,
            "details": self.details,
        }
        if self.uncertainty is not None:
            out["uncertainty"] = self.uncertainty
        if self.cross_validation is not None:
            out["cross_validation"] = self.cross_validation
        if self.excluded:
            out["excluded_before_solve"] = [{"posture": int(i), "reason": r} for i, r in self.excluded.items()]
        if self.truth_errors is not None:
            out["truth_errors"] = self.truth_errors
        return out


def _posture_tool0(session: Session) -> np.ndarray:
    robot = None
    poses = []
    for p in session.postures:
        if p.tool0_in_base is not None:
            poses.append(p.tool0_in_base)
            continue
        if robot is None:
            if not session.robot:
                raise CalibrationError(
                    f"posture {p.index} holds joints_deg only; add 'robot: IRB1400' (or your model) to session.yaml"
                )
            try:
                robot = load_robot(session.robot)
            except ValueError as exc:
                raise CalibrationError(str(exc)) from None
        if p.joints_deg.shape != (robot.dof,):
            raise CalibrationError(
                f"posture {p.index}: joints_deg has {p.joints_deg.size} values; {robot.name} has {robot.dof} axes")
        poses.append(robot.forward_transform(p.joints_deg))
    return np.array(poses)


def problem_from_session(session: Session, check_units: bool = True,
                         check_consistency: bool | None = None) -> HandEyeProblem:
    """Turn a validated session into arrays, checking what the solver needs.

    Parameters
    ----------
    session : Session
        Lengths in mm (convert first with ``plausibility.session_in_mm`` when they are not).
    check_units : bool
        Refuse lengths that are not plausible millimetres (``plausibility.check_plausible``;
        default). Only tests of the solvers on deliberately odd data switch it off.
    check_consistency : bool, optional
        Refuse poses that no rigid camera mount fits (``consistency.check_consistent``), after leaving
        out a minority of gross postures when that makes the rest fit (``consistency.consistent_majority``:
        they are kept in the problem and named in ``problem.excluded``); default: as ``check_units``
        (both guard against data no real cell produces).

    Raises
    ------
    CalibrationError
        Too few postures, a posture with a different corner count, no usable board data.
    UnitsError
        Lengths that look like metres, a posture in another unit, a flange out of the robot's reach,
        corners whose spacing does not match ``target.square_mm``.
    InconsistentPosesError
        Robot and board poses that no rigid camera mount fits (a wrong set-up, pose direction or
        rotation convention), checked on the X-free invariants of AX = XB, and no consistent majority.
    """
    postures = session.postures
    if len(postures) < MIN_POSTURES:
        raise CalibrationError(f"at least {MIN_POSTURES} postures are needed; got {len(postures)}")
    ids = np.array([p.index for p in postures])
    check_consistency = check_units if check_consistency is None else check_consistency
    tool02base = _posture_tool0(session)
    if check_units:
        check_plausible(session, tool02base)
    hand = hand_poses(tool02base, session.setup)
    joints = _session_joints(session)
    with_points = [p for p in postures if p.points_mm is not None]
    if len(with_points) == len(postures):
        board = session.target
        if board is None:
            raise CalibrationError(
                "the postures hold points_mm but session.yaml has no target.corners; add the board's corner counts")
        if _partial(session):
            return _consistent(_partial_problem(session, hand, ids, joints), check_consistency)
        for p in postures:
            if len(p.points_mm) != board.count:
                raise CalibrationError(
                    f"posture {p.index} has {len(p.points_mm)} corners; the board has "
                    f"{board.corners[0]}x{board.corners[1]} = {board.count}"
                )
        points = np.array([p.points_mm for p in postures])
        compact = compact_points_from_corners(points, board)
        target_points = board.grid(compact.square_mm)
        return _consistent(HandEyeProblem(session.setup, hand, compact, points, ids, target_points, joints_deg=joints,
                                          robot=session.robot if joints is not None else None), check_consistency)
    missing = [p.index for p in postures if p.target_in_camera is None]
    if missing:
        raise CalibrationError(f"posture {missing[0]} holds neither points_mm nor target_in_camera like the others")
    length = 100.0
    if session.target is not None and session.target.square_mm:
        length = (max(session.target.corners) - 1) * session.target.square_mm
    compact = compact_points_from_poses(np.array([p.target_in_camera for p in postures]), length)
    return _consistent(HandEyeProblem(session.setup, hand, compact, compact.points, ids, compact.target_points,
                                      joints_deg=joints, robot=session.robot if joints is not None else None),
                       check_consistency)


def _partial(session: Session) -> bool:
    """True for a session of a board that may be seen in part (ChArUco), or one whose postures name corner ids."""
    from ..geometry import partial_ok  # noqa: PLC0415

    return partial_ok(session.target) or any(p.corner_ids is not None for p in session.postures)


def _partial_problem(session: Session, hand, ids, joints) -> HandEyeProblem:
    """The problem of a session with partial views: board points by id (``partial_views.board_arrays``)."""
    from .partial_views import board_arrays, compact_points_from_fit  # noqa: PLC0415

    board = session.target
    if board is None:  # calibrate's caller checks it; the partial-view path needs the board's geometry
        raise CalibrationError("the postures hold points_mm but session.yaml has no target; add the board")
    square = board.square_mm
    if square is None:
        raise CalibrationError("session.yaml: target.square_mm is needed for views of part of the board")
    try:
        points, seen, poses = board_arrays(session.postures, board, square)
    except ValueError as exc:
        raise CalibrationError(str(exc)) from None
    compact = compact_points_from_fit(points, seen, poses, board, square)
    return HandEyeProblem(session.setup, hand, compact, points, ids, board.grid(square), joints_deg=joints,
                          robot=session.robot if joints is not None else None, seen=None if seen.all() else seen)


def _session_joints(session: Session) -> np.ndarray | None:
    """Every posture's joint angles when all hold them (same count) and the session names its robot."""
    if not session.robot or any(p.joints_deg is None for p in session.postures):
        return None
    joints = [np.asarray(p.joints_deg, float) for p in session.postures]
    if len({j.shape for j in joints}) != 1 or joints[0].ndim != 1:
        return None
    return np.array(joints)


def _consistent(problem: HandEyeProblem, check: bool) -> HandEyeProblem:
    """The problem, after ``consistency.consistent_majority`` when ``check`` (the calibrate re-check),
    with the gross postures it names in ``excluded``."""
    if not check:
        return problem
    excluded = consistent_majority(problem.hand, problem.target2cam, problem.setup, problem.posture_ids)
    return replace(problem, excluded=excluded) if excluded else problem


def check_motion(problem: HandEyeProblem) -> None:
    """Refuse data whose robot motion cannot determine ``X``.

    Uses the quality words of ``calibration.quality_words``: the relative rotation angles and the
    rotation-axis divergence (how far the axes stray from one line).

    Raises
    ------
    CalibrationError
        When every relative rotation is below ~2 deg, or all rotation axes are (nearly) parallel.
    """
    # Q_A of every pair (Algorithm 1, step 2): quality_words.relative_rotation_quaternions of the hand. Built
    # with Q_B here, so a board whose points are not finite fails in this first step, as it always has.
    # Every pair of a small session, neighbours in time and random partners of a large one (bounded_pairs).
    q_rel = relative_motions(problem, bounded_pairs(problem.n)).q_a
    angles = relative_rotation_angles_deg(q_rel)
    if angles.max() < MIN_ROTATION_DEG:
        raise CalibrationError(
            f"the flange barely rotates between postures (largest relative rotation {angles.max():.2f} deg); "
            f"rotate it by 15-45 deg about different axes between postures"
        )
    divergence = rotation_axis_divergence_deg(usable_axes(q_rel))
    if divergence < MIN_AXIS_DIVERGENCE_DEG:
        raise CalibrationError(
            f"all relative rotations are about nearly parallel axes (rotation-axis divergence {divergence:.2f} deg); "
            f"rotate the flange about at least two different axes"
        )


def truth_from_dict(truth: dict | None) -> dict | None:
    """``{'x': 4x4, 'target2fixed': 4x4}`` from a ``truth.yaml`` mapping, or ``None``."""
    if not truth:
        return None
    try:
        camera, board = truth["camera_pose"], truth["target_pose"]
        x = transform_from_pose(camera["position_mm"], camera["quaternion_wxyz"])
        target = transform_from_pose(board["position_mm"], board["quaternion_wxyz"])
    except (KeyError, TypeError, ValueError, OverflowError):
        return None
    return {"x": x, "target2fixed": target}


def _summarise(problem: HandEyeProblem, x: np.ndarray) -> dict:
    """The metrics of ``x`` on (the kept postures of) a problem: eq. 22, 23 and 16."""
    fixed = fixed_points(problem.hand, x, problem.points_cam)
    motions_pairs = bounded_pairs(problem.n)  # every pair up to 200 postures, else a bounded sample
    delta_r, delta_t = axxb_residuals(problem.hand, problem.target2cam, x, motions_pairs)
    metrics = {
        "d_org_mm": d_org(fixed),
        "d_back_mm": d_back(fixed, motions_pairs),
        "delta_r": float(np.sqrt(np.mean(delta_r**2))),
        "delta_t_mm": float(np.sqrt(np.mean(delta_t**2))),
        "points": residual_points(problem),
        "postures": problem.n,
        "posture_pairs": int(len(motions_pairs)),
    }
    return metrics


_WARM = False


def _warm_up_numerics() -> None:
    """Start numpy's BLAS/LAPACK thread pools once, so ``runtime_s`` times the solve, not start-up."""
    global _WARM
    if not _WARM:
        a = np.eye(64)
        np.linalg.eigh(np.broadcast_to(np.eye(4), (8, 4, 4)))
        _ = a @ a
        _WARM = True


def calibrate(problem: HandEyeProblem, method: str | None = None, truth: dict | None = None,
              progress: Callable[[int, int, str], object] | None = None) -> CalibrationResult:
    """Solve ``AX = XB`` with one method.

    Parameters
    ----------
    problem : HandEyeProblem
    method : str, optional
        A paper variant (:data:`PAPER_METHODS`), ``robust`` or a classic solver: a name of the table
        :data:`~handeye.calibration.methods.METHODS`; ``None`` runs :data:`DEFAULT_METHOD`.
    truth : dict, optional
        ``{'x': 4x4, 'target2fixed': 4x4}`` of a synthetic data set: enables ``mcy`` and truth errors.
    progress : callable, optional
        ``progress(done, total, label)`` after each stage of the ``ml`` default (for a progress display).

    Raises
    ------
    CalibrationError
        Also when a solver fails inside numpy or scipy (``ValueError``, ``LinAlgError``) or returns a
        pose that is not finite: one line, never a traceback and never a NaN answer.
    """
    try:
        with np.errstate(all="ignore"):  # what goes wrong is reported below, not as warnings
            result = _calibrate(problem, method, truth, progress)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        reason = (str(exc).splitlines() or [type(exc).__name__])[0]
        raise CalibrationError(f"the {method or DEFAULT_METHOD} solver failed on these data ({reason}); check the "
                               f"session's values: lengths in mm, distinct finite poses, the whole board seen") from None
    return result


def bounded_for(method: str, function: Callable[[], _T], what: str = "solve") -> _T:
    """``function()``, under the time bound when ``method`` is another package's (an entry point's, or
    registered in code from outside handeye: :func:`~handeye.base.time_bound.call_within`); handeye's
    own methods run as they are.

    Raises
    ------
    OutOfTime
        Another package's method still ran after the bound (it is left running, in a daemon thread).
    """
    row = method_row(method)
    if _method_provider(row) is None:
        return function()
    return cast(_T, call_within(function, f"{what}-{row.name}"))  # what function() returned (call_within is untyped)


def calibrate_within(problem: HandEyeProblem, method: str | None, truth: dict | None = None,
                     progress: Callable[[int, int, str], object] | None = None) -> CalibrationResult:
    """:func:`calibrate`, another package's method under the time bound (:func:`bounded_for`): what the
    report's comparison and a user's own ``--method`` solve with, so a hanging plug-in is named in one line
    instead of hanging the command (``method`` None: :data:`DEFAULT_METHOD`, handeye's own).

    Raises
    ------
    CalibrationError
        What :func:`calibrate` raises, and a plug-in's method that took longer than the bound (one line
        naming the method, its package and the bound).
    """
    try:
        return bounded_for(method or DEFAULT_METHOD, lambda: calibrate(problem, method, truth, progress))
    except OutOfTime as exc:
        raise CalibrationError(_method_fault(method_row(method), f"took longer than {exc.seconds:g} s (the bound on "
                                             f"another package's method, {TIME_VARIABLE}; it is left running in the "
                                             "background)")) from None


def _calibrate(problem: HandEyeProblem, method: str | None = None, truth: dict | None = None,
               progress=None) -> CalibrationResult:
    """:func:`calibrate` without its guard against numerical failures."""
    if problem.excluded:  # gross postures named before solving: solve without them, report them as outliers
        return _with_excluded(problem, _calibrate(problem.subset(~problem.excluded_mask), method, truth, progress))
    row = method_row(method)
    if problem.n < MIN_POSTURES:
        raise CalibrationError(f"at least {MIN_POSTURES} postures are needed; got {problem.n}")
    check_motion(problem)
    if row.needs_truth and truth is None:
        raise CalibrationError(f"{row.name} needs the true board pose (truth.yaml of a synthetic session)")
    solver = _load_solver(row)
    _warm_up_numerics()
    start = time.perf_counter()
    solved = _solve(row, solver, problem, truth, progress)
    runtime = time.perf_counter() - start
    x = solved.x
    flags = np.zeros(problem.n, bool) if solved.outliers is None else np.asarray(solved.outliers, bool)
    metrics = _summarise(problem if solved.outliers is None else problem.subset(~flags), x)
    residuals = _residuals_by_posture(problem, x, ~flags)
    outliers = [int(i) for i in problem.posture_ids[flags]]
    result = CalibrationResult(row.name, problem.setup, x, metrics, residuals, outliers, runtime, solved.details,
                               uncertainty=solved.uncertainty, cross_validation=solved.cross_validation,
                               residuals_on=residual_points(problem))
    if truth is not None:
        result.truth_errors = errors_against_truth(x, truth["x"])
    return result


def method_row(method: str | None) -> Method:
    """The methods table's row of ``method`` (any case; None: :data:`DEFAULT_METHOD`).

    Raises
    ------
    CalibrationError
        A name that is not in the table (nor added by an installed plug-in), in one line.
    """
    row = get_method(method or DEFAULT_METHOD)
    if row is None:
        raise CalibrationError(METHODS.unknown(str(method).lower()))
    return row


def _load_solver(row: Method):
    """The row's solver, imported now (before the clock starts); a plug-in that cannot be imported is one line."""
    try:
        return row.load()
    except (ImportError, AttributeError) as exc:
        raise CalibrationError(f"the solver of method {row.name} ({row.solver}) cannot be loaded: {exc}; "
                               f"reinstall the package that provides it") from None


@dataclass(frozen=True)
class _Solved:
    """What a ``paper`` or ``classic`` method gives: ``X`` and its details, no judgement of postures
    (the attributes an ``estimator``'s solution has, its judgements None)."""

    x: np.ndarray
    details: dict
    outliers: np.ndarray | None = None
    uncertainty: dict | None = None
    cross_validation: dict | None = None


def _by_estimator(row: Method, solver, problem: HandEyeProblem, truth, progress):
    """``estimator``: the whole pipeline on the problem."""
    return solver(problem, progress)


def _by_selection(row: Method, solver, problem: HandEyeProblem, truth, progress) -> _Solved:
    """``paper``: Algorithm 1 with the row's selection criterion (none: all postures at once)."""
    return _Solved(*solve_paper(problem, solver, truth_board_points(problem, truth) if row.needs_truth else None))


def _by_axxb(row: Method, solver, problem: HandEyeProblem, truth, progress) -> _Solved:
    """``classic``: an AX = XB solver on the hand and board poses."""
    return _Solved(solver(problem.hand, problem.target2cam), {"reference": row.reference})


#: How each kind of method is called (``calibration.methods``, "Kinds").
_BY_KIND = {"estimator": _by_estimator, "paper": _by_selection, "classic": _by_axxb}

#: Largest ``max |R^T R - I|`` of the rotation a method returns: every method gives a rotation to
#: rounding, so beyond this the method is at fault, not the data, and its answer is refused.
SOLUTION_ORTHONORMAL_TOLERANCE = 1e-6


def _solve(row: Method, solver, problem: HandEyeProblem, truth, progress) -> _Solved:
    """The row's solver called as its kind says, and what it gives checked (:func:`_checked_solution`).

    Raises
    ------
    CalibrationError
        What the method's own code raises beyond handeye's errors, in one line naming the method and,
        for a plug-in, the package that provides it (handeye's own methods' numeric failures on
        degenerate data are left to :func:`calibrate`, which blames the data).
    """
    try:
        solved = _BY_KIND[row.kind](row, solver, problem, truth, progress)
    except HandEyeError:
        raise
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        if _method_provider(row) is None:
            raise
        raise CalibrationError(_method_fault(row, f"failed ({exception_line(exc)})")) from None
    except Exception as exc:  # noqa: BLE001 (a method's own fault: one line, never a traceback)
        raise CalibrationError(_method_fault(row, f"raised {exception_line(exc)}")) from None
    return _checked_solution(row, solved, problem.n)


def _checked_solution(row: Method, solved, n: int) -> _Solved:
    """``solved`` with ``x`` a rigid (4, 4) transform and ``outliers`` an (n,) bool array or None.

    Raises
    ------
    CalibrationError
        A solution without the attributes of its kind, an ``x`` that is not a rigid transform (a
        scaled or sheared rotation, a reflection, another shape) or outlier flags of another length:
        the method's fault, named. A non-finite ``x`` from handeye's own method is the data's fault,
        and said so.
    """
    try:
        x = np.asarray(solved.x, dtype=float)
        outliers = None if solved.outliers is None else np.asarray(solved.outliers, dtype=bool)
        checked = _Solved(x, dict(solved.details or {}), outliers, solved.uncertainty, solved.cross_validation)
    except (AttributeError, TypeError, ValueError) as exc:
        raise CalibrationError(_method_fault(row, f"returned a {type(solved).__name__}, not a solution with x, outliers, "
                                                  f"details, uncertainty and cross_validation ({exception_line(exc)})")) from None
    if x.shape == (4, 4) and not np.all(np.isfinite(x)):
        if _method_provider(row) is not None:
            raise CalibrationError(_method_fault(row, "found no finite camera pose"))
        raise CalibrationError(f"the {row.name} solver found no finite camera pose; check the session's values: "
                               f"lengths in mm, distinct finite poses, the whole board seen")
    defect = rigid_defect(x, SOLUTION_ORTHONORMAL_TOLERANCE)
    if defect:
        raise CalibrationError(_method_fault(row, f"returned a camera pose that is not a rigid transform: {defect}"))
    if outliers is not None and outliers.shape != (n,):
        raise CalibrationError(_method_fault(row, f"returned {outliers.size} outlier flags for {n} postures"))
    defect = _judgement_defect(checked.uncertainty, checked.cross_validation)
    if defect:
        raise CalibrationError(_method_fault(row, f"returned {defect}"))
    return checked


def _judgement_defect(uncertainty, cross_validation) -> str | None:
    """What is wrong with an estimator's ``uncertainty`` and ``cross_validation`` as the presenters and
    the verdict read them (``CalibrationResult``), in a few words; None when both are usable (or None)."""
    def numbers(mapping, key, count):
        try:
            values = np.asarray(mapping[key], dtype=float).reshape(-1)
        except (KeyError, TypeError, ValueError):
            return False
        return values.size == count and bool(np.all(np.isfinite(values) & (values >= 0)))

    if uncertainty is not None and not (isinstance(uncertainty, dict) and numbers(uncertainty, "translation_mm", 3)
                                        and numbers(uncertainty, "rotation_deg", 3)):
        return ("an uncertainty that is not translation_mm and rotation_deg, three finite one-sigma values each "
                f"(got {brief(uncertainty)})")
    if cross_validation is not None and not (
            isinstance(cross_validation, dict) and numbers(cross_validation, "folds", 1)
            and numbers(cross_validation, "rms_mm", 1)
            and ("predicted_rms_mm" not in cross_validation or numbers(cross_validation, "predicted_rms_mm", 1))):
        return f"a cross-validation without folds and rms_mm (crossval.CrossValidation.to_dict; got {brief(cross_validation)})"
    return None


def _method_provider(row: Method) -> str | None:
    """Who provides the row's solver when it is not handeye: the installed package of its entry point,
    or the module of a solver registered in code from outside handeye; None for handeye's own."""
    provider = METHODS.provider(row.name)
    if provider is not None:
        return provider
    module = row.solver.partition(":")[0] if isinstance(row.solver, str) else getattr(row.solver, "__module__", None)
    if module and module.split(".")[0] != __name__.split(".")[0]:
        return f"the module {module} (registered in code)"
    return None


def _method_fault(row: Method, what: str) -> str:
    """One line for a method whose own code failed: which method, who provides it, what to do."""
    provider = _method_provider(row)
    if provider is None:
        return (f"method {row.name} {what}: a fault in handeye, not in the data; run another --method and report it "
                "with the session")
    return (f"method {row.name}, from {provider}, {what}; if handeye's own methods solve this session, the fault is "
            "that package's: run another --method (handeye calibrate --help lists them) and report it to its authors")


def _residuals_by_posture(problem: HandEyeProblem, x: np.ndarray, kept: np.ndarray) -> dict:
    """``{posture index: posture residual}`` of every posture (``quality_words.posture_residuals``)."""
    return {int(i): float(r) for i, r in zip(problem.posture_ids, posture_residuals(problem, x, kept))}


def _with_excluded(problem: HandEyeProblem, result: CalibrationResult) -> CalibrationResult:
    """``result`` (solved without ``problem.excluded``) on the whole ``problem``: the excluded postures
    join the outliers, with their posture residual against the kept postures' mean board points."""
    outliers = {int(i) for i in result.outliers} | set(problem.excluded)
    kept = np.array([int(i) not in outliers for i in problem.posture_ids])
    return replace(result, residuals_mm=_residuals_by_posture(problem, result.x, kept),
                   excluded=dict(problem.excluded), outliers=[int(i) for i in problem.posture_ids if int(i) in outliers])


def calibrate_session(session: Session, method: str | None = None, truth: dict | None = None,
                      progress: Callable[[int, int, str], object] | None = None) -> CalibrationResult:
    """:func:`calibrate` on a session read from disk."""
    return calibrate(problem_from_session(session), method, truth, progress)
