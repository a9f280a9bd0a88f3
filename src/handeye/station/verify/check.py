"""``handeye verify``: is SESSION's calibration still right, and if not, what changed?

1. SESSION is checked (a capture of this robot and board, its saved result ``result.yaml`` no older
   than its postures, with a passing verdict: ``station.result_file``) and its maximum-likelihood fit
   is made for the test's noise model (``calibration.eiv``: X, the board, the noise, covariances);
   when the latest deliberate write-back in the history is a quick update of SESSION, its X is the
   check's (``station.verify.reference``);
2. the controller's camera tooldata is read and compared with that result (a mismatch is a finding
   of its own: ``tooldata``, whose advice restores the latest write-back, never undoes one);
3. K of SESSION's postures are chosen for diagnostic power and a short path clear of the cell
   (``station.verify.plan``), and revisited with the same RAPID program and links as ``capture``
   (``station.capture.loop``: install, confirm, visit): the measurements are a session beside SESSION;
4. the discrepancies against the fit's prediction are tested at the stated false-alarm rate
   (``calibration.verification``), and a drift explained (``calibration.drift_causes``); when the
   camera moved, the quick update gives a new X with its uncertainty, which ``handeye writeback``
   accepts like a calibration;
5. one record goes into the history beside the sessions (``station.verify.history``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...base import HandEyeError
from ...robot import load_robot
from ...calibration import read_session
from ...calibration import DEFAULT_LEVEL, MIN_VERIFY_POSTURES
from ..capture.loop import CaptureRun, confirm_motion, install_program, release_waiting_posture, visit_postures
from ..config.station import StationConfig
from ..origin import MOCK, REAL, session_origin
from ..runtime import StationLink
from ..config.station_kind import station_kind
from ..config.session_match import station_mismatch
from ..result_file import refuse_stale_result
from .reference import follow
from .tolerance import drift_size, drift_tolerance, tool_difference, verdict_reason
from .plan import (
    TIME_BUDGET,
    TIME_LIMIT,
    TIME_TIGHTEN,
    TIME_TRIES,
    VerifyError,
    capture_time,
    cell_guard,
    create_verify_session,
    order_postures,
    path_time,
    path_time_along,
    verify_folder,
)

if TYPE_CHECKING:
    from ...calibration import Baseline, DriftTest, EivSolution, HandEyeProblem, QuickUpdate
    from ..report.assessment import Assessment
    from .reference import Reference
    from .tolerance import DriftSize, DriftTolerance

__all__ = ["OK", "DRIFT", "INCONCLUSIVE", "EXIT_CODES", "VerifyOutcome", "SessionBaseline", "check_request",
           "session_baseline", "verify"]

OK, DRIFT, INCONCLUSIVE = "ok", "drift", "inconclusive"
#: Exit status of ``handeye verify`` per verdict (errors exit 1).
EXIT_CODES = {OK: 0, DRIFT: 3, INCONCLUSIVE: 4}


@dataclass
class VerifyOutcome:
    """What a check found (``station.verify.result`` turns it into the text, the JSON and the record).

    Attributes
    ----------
    verdict : str
        ``ok``, ``drift`` or ``inconclusive``.
    reason : str
        One line: why (the test's numbers, or what made it inconclusive).
    folder : Path or None
        The check's own session (its measurements).
    postures : list of int
        SESSION's posture numbers revisited, in the order visited.
    measured : int
    test : DriftTest or None
    explanations : list of Explanation
        Best first (empty when inconclusive).
    tool_finding : dict or None
        ``{"held": ToolData, "session": ToolData, "difference": ToolDifference}`` when the controller holds
        another tooldata (DRIFT only when the difference is beyond :attr:`tolerance`).
    update : QuickUpdate or None
    motion_s : float or None
        Robot time of the check (s) by the plan's motion model (``verify_plan.path_time_along``: each
        move synchronised, its slowest axis at full speed) from where the controller reported the arm
        through the postures in the order visited; the same model as :attr:`capture_motion_s`, so
        their ratio is the ratio of robot times. Never read from a mock.
    capture_motion_s : float or None
        The full capture's robot time by the same model (``verify_plan.capture_time``).
    tolerance : DriftTolerance or None
        The smallest change the check acts on (``station.verify.tolerance``).
    size : DriftSize or None
        The detected change's size against it (None: the test found nothing).
    reference : verify_reference.Reference or None
        What the check compared against (SESSION's result, or the quick update written after it).
    standoff : dict or None
        The measured error at the stand-off against ``calibrate --kinematics``'s prediction
        (``verify.standoff_check``); None when SESSION has no current prediction.
    """

    verdict: str
    reason: str
    folder: Path | None = None
    postures: list = field(default_factory=list)
    measured: int = 0
    test: DriftTest | None = None
    explanations: list = field(default_factory=list)
    tool_finding: dict | None = None
    update: QuickUpdate | None = None
    motion_s: float | None = None
    baseline: SessionBaseline | None = None
    capture_motion_s: float | None = None
    tolerance: DriftTolerance | None = None
    size: DriftSize | None = None
    reference: Reference | None = None
    standoff: dict | None = None

    @property
    def beyond_tolerance(self) -> bool:
        """The test found a change and it is larger than the tolerance (``station.verify.tolerance``)."""
        return self.size is not None and self.size.beyond


def check_request(config: StationConfig, session_dir: Path, postures: int):
    """SESSION as ``verify`` needs it, or a one-line refusal (VerifyError): a capture on this station
    (controller, camera, robot and board: ``station.config.session_match``) with its plan on record, and K
    at least :data:`MIN_VERIFY_POSTURES`."""
    if postures < MIN_VERIFY_POSTURES:
        raise VerifyError(f"--postures {postures} is too few: the test and its diagnosis need at least "
                          f"{MIN_VERIFY_POSTURES} revisited postures")
    session = read_session(session_dir)
    record = session.extra.get("capture")
    if isinstance(record, dict) and isinstance(record.get("verify_of"), dict):
        of = record["verify_of"].get("session", "its session")
        raise VerifyError(f"{session_dir} holds the measurements of a check of {of}, not a calibration: verify --against "
                          f"{of} (a quick update written from this check is what that check follows)")
    if session_origin(session, session_dir) not in (MOCK, REAL) or not isinstance(record, dict) \
            or "plan_joints_deg" not in record:
        raise VerifyError(f"{session_dir} was not captured by handeye capture (simulated or imported): verify revisits "
                          "the recorded postures of a capture on this station; capture one (handeye capture) and "
                          "calibrate it")
    mismatch = station_mismatch(session, session_dir, config)
    if mismatch is not None:
        raise VerifyError(mismatch)
    _check_joints(session, session_dir)
    refuse_stale_result(session_dir)
    usable = [p for p in session.postures if p.joints_deg is not None and p.index < len(record["plan_joints_deg"])]
    if len(usable) < postures:
        raise VerifyError(f"{session_dir} holds {len(usable)} postures with joint angles; --postures {postures} asks "
                          "for more")
    return session


def _check_joints(session, session_dir: Path) -> None:
    """Refuse SESSION when a posture's joint angles are missing or do not reproduce its flange pose: its
    calibration then models the robot's noise on the flange poses, the check (which revisits by joint
    angles) on the joints, and the two cannot be compared."""
    from ...calibration import session_joint_mismatch

    missing = [p.index for p in session.postures if p.joints_deg is None]
    found = session_joint_mismatch(session)
    if not missing and found is None:
        return
    what = found.line() if found is not None else \
        f"postures {', '.join(map(str, missing))} hold no joint angles (joints_deg)"
    raise VerifyError(f"{session_dir}: {what}: verify revisits postures by their joint angles and compares under "
                      "the calibration's joint noise model; correct or remove those postures' files and calibrate "
                      "again, or capture a new session; nothing moved")


@dataclass(frozen=True)
class SessionBaseline:
    """SESSION solved again: its assessment, the ML solution, the baseline of the check and its problem."""

    assessment: Assessment
    solution: EivSolution
    baseline: Baseline
    problem: HandEyeProblem


def session_baseline(config: StationConfig, session, session_dir: Path, progress=lambda m: None) -> SessionBaseline:
    """SESSION's saved result (``station.result_file``: solved and saved first when it has none) judged
    against the config's thresholds, and its maximum-likelihood fit for the test's noise model; refuse
    one without a passing result or whose result is older than its postures."""
    from ...calibration import solve_eiv
    from ...calibration import baseline_from_solution
    from ..report.assessment import assess
    from ..report.quality import config_thresholds
    from ..result_file import ResultError, current_outcome

    try:
        outcome = current_outcome(session, session_dir, say=progress)
    except ResultError:
        raise
    except HandEyeError as exc:
        raise VerifyError(f"{session_dir} has no calibration result ({exc}): capture more postures and calibrate it "
                          "before verifying") from None
    assessment = assess(outcome, config_thresholds(config))
    verdict, problem = assessment.verdict, outcome.problem
    if verdict is None or problem is None:  # assess judges with the thresholds given; current_outcome reads the problem
        raise VerifyError(f"{session_dir}'s calibration could not be judged: calibrate it again (handeye calibrate)")
    if not verdict.passed:
        raise VerifyError(f"{session_dir}'s calibration failed its quality verdict ({verdict.line()}): "
                          "there is no good calibration to verify; recalibrate (handeye capture, calibrate)")
    if problem.excluded:
        problem = problem.subset(~problem.excluded_mask)
    solution = solve_eiv(problem, folds=0)
    return SessionBaseline(assessment, solution, baseline_from_solution(solution), problem)


def _tool_finding(config: StationConfig, link: StationLink, base: SessionBaseline, reference) -> dict | None:
    """The controller's camera tooldata against the result the check follows (SESSION's, or the quick update
    written after it: ``station.verify.reference``): None when they agree to the last digit."""
    from ..writeback import _same_to_last_digit, tooldata_from_result

    held = link.controller.read_tool()
    expected = tooldata_from_result(reference.result or base.assessment.result, config)
    if _same_to_last_digit(held, expected):
        return None
    return {"held": held, "session": expected, "reference": reference,
            "difference": tool_difference(held, expected, drift_tolerance(config))}


def _chosen(config, session, base: SessionBaseline, robot, here, count: int, progress=lambda m: None):
    """SESSION's posture numbers to revisit (informative, then ordered) and their jointtargets.

    The time the choice is held to is the check's real path (from ``here``, where the robot stands,
    through the chosen postures in the order they are visited clear of the cell; the program has no
    move home) against the full capture's robot time (``verify_plan.capture_time``): aimed at
    :data:`TIME_BUDGET` of it and chosen again with a tighter budget while above :data:`TIME_LIMIT`.
    When no choice fits (a short session: K of its few postures are more than a fifth of its path),
    the shortest one tried is taken and ``progress`` says so.
    """
    from ...calibration import informative_postures

    record = session.extra["capture"]
    plan = np.array(record["plan_joints_deg"], float)
    problem, sol = base.problem, base.solution
    if problem.joints_deg is None:
        raise VerifyError("the session holds no joint angles, so its postures cannot be revisited: capture it again")
    ids = np.array([int(i) for i in problem.posture_ids])
    allowed = ~np.asarray(sol.outliers, bool) & (ids < len(plan))
    full = capture_time(robot, record)
    targets = plan[np.minimum(ids, len(plan) - 1)]
    guard = cell_guard(config, robot, record)
    budget, best = TIME_BUDGET * full, (np.inf, None)
    for _ in range(TIME_TRIES):
        picked = informative_postures(base.baseline, sol.observations, problem.joints_deg, robot, count, allowed,
                                      path_time=lambda chosen: path_time(robot, here, targets[chosen]), budget=budget)
        order = order_postures(robot, here, plan[ids[picked]], guard)
        numbers = [int(ids[picked[i]]) for i in order]
        took = path_time_along(robot, here, plan[numbers])
        best = min(best, (took, numbers), key=lambda b: b[0])
        if took <= TIME_LIMIT * full:
            break
        budget *= TIME_TIGHTEN
    took, numbers = best
    if numbers is None:  # TIME_TRIES >= 1: the loop always made a choice
        raise VerifyError(f"no choice of {count} postures was tried (TIME_TRIES = {TIME_TRIES})")
    if took > TIME_LIMIT * full:
        progress(f"the check's {count} postures take {took / max(full, 1e-9):.0%} of the capture's robot time from where "
                 f"the robot stands ({len(plan)} postures in the session; the aim is {TIME_BUDGET:.0%})")
    return numbers, plan[numbers]


class _Stop:
    """``stop_when`` of the check's posture loop: stop at the first posture where no board at all is seen
    (the check cannot diagnose a station whose board is out of view), or once the postures left cannot
    bring the measured ones to :data:`MIN_VERIFY_POSTURES`; ``reason`` says which, in one line."""

    def __init__(self, numbers, session_name: str):
        self.numbers, self.session_name = list(numbers), session_name
        self.visited = self.measured = 0
        self.reason: str | None = None

    def __call__(self, report) -> bool:
        self.visited += 1
        self.measured += bool(report.ok)
        n = self.numbers[report.index] if 0 <= report.index < len(self.numbers) else report.index
        if not report.ok and report.board_absent:
            self.reason = (f"board not seen at posture {n} of {self.session_name} (no checkerboard in the image; "
                           f"stopped after {self.visited} of {len(self.numbers)} postures): check that the board is "
                           "on its stand, lit and in the camera's view (nothing in front of the lens), then run "
                           "verify again")
        elif self.measured + len(self.numbers) - self.visited < MIN_VERIFY_POSTURES:
            self.reason = (f"{self.measured} of {self.visited} postures measured so far (the board was not measured "
                           f"at posture {n} of {self.session_name}: {report.message}); the test needs "
                           f"{MIN_VERIFY_POSTURES} of {len(self.numbers)}: check the view and run verify again")
        return self.reason is not None


def _revisit(config, link: StationLink, folder: Path, session, numbers, joints, progress, confirm, on_posture):
    """Visit the chosen postures with the capture's program and loop; returns (the count of postures
    measured, None) or (that count, the reason the check cannot go on: the link failed, the board is not
    seen, :class:`_Stop`). ``on_posture`` receives each report named by SESSION's posture number."""
    from ...drivers import StationError

    station = station_kind(config, link, session_origin(session, session.path))  # SESSION's origin too: its X is moved
    created = create_verify_session(config, session, session_dir=Path(session.path), indices=numbers, joints=joints,
                                    folder=folder, station=station)
    created.path = folder
    run = CaptureRun(created, np.round(joints, 4), created.extra["capture"]["plan_score"])
    stop = _Stop(numbers, Path(session.path).name)
    try:
        install_program(config, folder, run.plan_joints, link, progress, run.board2base)
        confirm_motion(config, folder, run, link, confirm, progress)
        release_waiting_posture(link.controller, run.done, progress)
        captured, skipped = visit_postures(config, folder, run, link, lambda r: on_posture(_renumbered(r, numbers)),
                                           stop_when=stop)
        if link.stop_program is not None:
            link.stop_program()
    except StationError as exc:  # the postures measured before it are on disk (the check's own folder): they count
        return len(list((folder / "postures").glob("[0-9]*.yaml"))), f"the link failed during the check ({exc})"
    for index, why in skipped.items():
        progress(f"posture {numbers[index]} of the session not measured: {why}")
    return len(captured), stop.reason


def _renumbered(report, numbers):
    """``report`` of the check's posture ``i`` (its own session counts 0..K-1) named by SESSION's number
    ``numbers[i]``, as the check's other lines name it (``revisiting postures 13, 11, 25``)."""
    from dataclasses import replace

    if not 0 <= report.index < len(numbers):
        return report
    own, theirs = f"posture {report.index}", f"posture {numbers[report.index]}"
    message = theirs + report.message[len(own):] if report.message.startswith(own) else report.message
    return replace(report, index=numbers[report.index], message=message)


def verify(config: StationConfig, session_dir, link: StationLink, postures: int = 5, level: float = DEFAULT_LEVEL,
           progress: Callable[[str], None] = lambda m: None, confirm=None,
           on_posture=lambda report: None, base: SessionBaseline | None = None) -> VerifyOutcome:
    """Check SESSION's calibration on the connected station (see the module docstring); ``base``:
    SESSION solved already (:func:`session_baseline`; the benchmark checks one session many times).

    Raises
    ------
    VerifyError
        SESSION cannot be checked (refusals in one line); nothing is written then.
    """
    session_dir = Path(session_dir)
    session = check_request(config, session_dir, postures)
    session.path = session_dir
    reference = follow(session_dir)  # the latest deliberate write-back: SESSION's result or its quick update
    base = base if base is not None else session_baseline(config, session, session_dir, progress)
    following = reference.line()
    if following:
        progress(following)
    base = replace(base, baseline=reference.apply(base.baseline))
    robot = load_robot(config.robot)
    tool = _tool_finding(config, link, base, reference)
    here = link.controller.read_joints()  # where the controller reports the arm: the check's path starts there
    numbers, joints = _chosen(config, session, base, robot, here, postures, progress)
    progress(f"revisiting postures {', '.join(map(str, numbers))} of {session_dir.name}")
    folder = verify_folder(session_dir)
    measured, failure = _revisit(config, link, folder, session, numbers, joints, progress, confirm, on_posture)
    tolerance = drift_tolerance(config)
    outcome = VerifyOutcome(INCONCLUSIVE, failure or "", folder, numbers, measured,
                            tool_finding=tool, motion_s=path_time_along(robot, here, joints), baseline=base,
                            capture_motion_s=capture_time(robot, session.extra["capture"]), tolerance=tolerance,
                            reference=reference)
    if failure is None:
        judge(outcome, folder, base, robot, level, numbers, session_dir)
    if tool is not None and tool["difference"].beyond and outcome.verdict != INCONCLUSIVE:
        outcome.verdict = DRIFT
        outcome.reason = (f"the controller's camera tooldata differs from {session_dir.name}'s by "
                          f"{tool['difference'].text()}, beyond the tolerance {tolerance.text()}; the board "
                          f"check: {outcome.reason}")
    return outcome


def judge(outcome: VerifyOutcome, folder: Path, base: SessionBaseline, robot, level: float, numbers,
          session_dir: Path | None = None) -> None:
    """The test, the explanations, the quick update and (SESSION with a stand-off prediction) the error at
    the stand-off on the check's measurements (into ``outcome``)."""
    from ...calibration import explain, quick_update
    from ...calibration import observations
    from ...calibration import problem_from_session
    from ...calibration import discrepancy, drift_test

    if outcome.measured < MIN_VERIFY_POSTURES:
        outcome.reason = (f"{outcome.measured} of {len(numbers)} postures measured (the board was not seen at the "
                          f"others); the test needs {MIN_VERIFY_POSTURES}: check the view and run verify again")
        return
    tolerance = outcome.tolerance
    if tolerance is None:  # verify() sets it before judging
        raise VerifyError("the check's drift tolerance was not set before judging its measurements")
    problem = problem_from_session(read_session(folder), check_consistency=False)
    obs = observations(problem)
    disc = discrepancy(base.baseline, obs, problem.joints_deg)
    outcome.test = drift_test(disc, base.baseline, level)
    if session_dir is not None:
        from .standoff_check import standoff_comparison

        outcome.standoff = standoff_comparison(session_dir, problem, base.baseline, numbers)
    outcome.explanations = explain(disc, base.baseline, robot)
    outcome.size = drift_size(outcome.explanations, outcome.test, tolerance)
    outcome.verdict = DRIFT if outcome.size is not None and outcome.size.beyond else OK
    outcome.reason = verdict_reason(outcome.test, outcome.size, tolerance)
    best = next((e for e in outcome.explanations if e.cause != "none"), None) if outcome.verdict == DRIFT else None
    if best is not None and best.cause == "camera":
        outcome.update = quick_update(base.baseline, obs, problem.joints_deg)
