"""Guided posture capture: plan, program the robot, visit every posture, measure, persist, resume.

Each posture has one number, the number of its file (``postures/NNN.yaml`` -> NNN, from 0): every
line the operator reads names it, as calibrate and the report do. Only the link to the controller
counts from 1, as the RAPID program's ``jtHePost<k>`` do: posture ``index`` is the controller's
``k = index + 1`` (the program's comments say so beside each jointtarget). For each posture of the plan:

1. ask the RAPID program to move there (``MoveAbsJ ... fine``) and wait until the robot is at rest;
2. read the joints and the flange pose, and cross-check the pose against our kinematics;
3. grab a stereo frame, find the board, triangulate its corners, judge the quality (retrying the
   grab a few times);
4. write the posture file atomically (``postures/NNN.yaml``);
5. acknowledge, so the program may take the next request.

Interrupted anywhere (Ctrl-C, a kill, a lost link), running the same command again reads the
session, skips the postures already on disk, acknowledges a posture the robot is still waiting at if
its file was written, and goes on: every posture ends up on disk exactly once. What a kill left half
done before the first move is finished on the rerun: the preview drawn again from the plan recorded
in ``session.yaml``, the RAPID modules not yet written written (:func:`repair_plan`); what cannot be
rebuilt is named in one line.

:func:`capture` runs four steps, each a function of its own, on the connected station
(``station.runtime.StationLink``):

- plan or resume (:func:`open_capture`): :func:`plan_session` measures the board at the start
  posture, plans and scores the postures and creates the session with its capture record
  (``capture.station: mock|real``); :func:`resume_session` reads that record back and refuses to
  resume a session of the other station. A new plan keeps clear of the cell (``cell`` of the
  station config, ``station.cell.plan``), and its preview (``station.cell.preview``) is written to
  ``SESSION/preview.png`` (before ``session.yaml``; a resumed plan without it gets it drawn again,
  :func:`repair_plan`);
- program (:func:`install_program`): the RAPID modules written once into ``SESSION/rapid``, loaded
  when the station can, and the wait until the controller runs them (``plan_only`` stops before:
  plan, preview and program on disk, nothing moved);
- confirmation: at a real station the first move waits for the operator's yes (``confirm``); the
  embedded mock moves without asking and says so;
- release (:func:`release_waiting_posture`): the posture the robot may still wait at is acknowledged;
- posture loop (:func:`visit_postures`): steps 1-5 above for every posture not yet on disk.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...geometry import BoardGeometry
from ...calibration import compact_points_from_corners
from ...base import HandEyeError
from ...base import remove_stale_temporaries
from ...robot import load_robot
from ...calibration import MAX_AXIS_SPREAD_DEG
from ...calibration import Posture, Session, create_session, read_session, write_posture, write_yaml_atomic
from ...geometry import pose_from_transform, rotation_error_deg, transform_from_pose, translation_error_mm
from ...robot import PinholeView, ViewSampling
from ...drivers import CameraError
from ...drivers import NoBoardInView, SquareSizeMismatch
from ...drivers import triangulate_images
from .events import CAPTURED, SKIPPED, CaptureStarted, Measured, Prompt, Verdict
from ..config.station import StationConfig
from ..origin import MOCK, REAL, session_origin
from ..config.station_kind import station_kind
from ..cell.plan import cell_check
from .planning import PlanScore, PosturePlan, plan_postures
from ..report.quality import config_thresholds
from ..runtime import StationLink

if TYPE_CHECKING:
    from ...drivers import Camera, Controller, StereoFrame, StereoModel
    from ...robot import RobotModel

__all__ = [
    "CaptureError",
    "CaptureRun",
    "CaptureSummary",
    "PostureReport",
    "capture",
    "confirm_motion",
    "install_program",
    "measure_board",
    "measure_with_retries",
    "measure_posture",
    "grab_observer",
    "measurement_line",
    "read_flange",
    "store_posture",
    "open_capture",
    "plan_line",
    "plan_session",
    "recorded_plan",
    "release_waiting_posture",
    "repair_plan",
    "resume_session",
    "stereo_views",
    "visit_postures",
    "write_program",
]


_STATION_NAMES = {MOCK: "mock station (embedded, or a rehearsal)", REAL: "real station"}


class CaptureError(HandEyeError):
    """The capture cannot go on (no board at the start, program not loaded, pose mismatch)."""


@dataclass
class PostureReport:
    """What happened at one posture (for the progress display).

    Attributes
    ----------
    index : int
        The posture's number: its file's (``postures/NNN.yaml``), as calibrate and the report name it.
    total : int
        Postures planned (guided: captured so far).
    ok : bool
    message : str
    quality : dict
    attempts : int
    elapsed_s : float
    done : int
        Postures visited so far, this one included (for a progress bar).
    board_absent : bool
        The last grab found no checkerboard at all (``NoBoardInView``): the board is out of view.
    """

    index: int
    total: int
    ok: bool
    message: str
    quality: dict = field(default_factory=dict)
    attempts: int = 1
    elapsed_s: float = 0.0
    done: int = 0
    board_absent: bool = False


@dataclass
class CaptureSummary:
    """Outcome of :func:`capture`.

    Attributes
    ----------
    session : Path
    planned : int
    captured : list of int
        Posture numbers (the files' ``NNN``, from 0) written in this run.
    already : list of int
        Posture numbers found on disk when the run started (resume).
    skipped : dict
        Posture number -> reason, for postures that failed quality in this run.
    duration_s : float
    plan_score : dict
    preview : Path or None
        ``SESSION/preview.png`` when it is there (None: it could not be drawn, the output said why).
    """

    session: Path
    planned: int
    captured: list
    already: list
    skipped: dict
    duration_s: float
    plan_score: dict
    preview: Path | None = None

    @property
    def complete(self) -> bool:
        return len(self.captured) + len(self.already) == self.planned


def stereo_views(model: StereoModel) -> tuple[PinholeView, PinholeView]:
    """Left and right pinhole views of a stereo model (for planning: distortion ignored)."""
    w, h = model.image_size
    k1, k2 = model.K1, model.K2
    left = PinholeView(w, h, float(k1[0, 0]), float(k1[0, 2]), float(k1[1, 2]))
    right_in_left = np.eye(4)
    right_in_left[:3, :3] = np.asarray(model.R).T
    right_in_left[:3, 3] = -np.asarray(model.R).T @ np.asarray(model.T).ravel()
    right = PinholeView(w, h, float(k2[0, 0]), float(k2[0, 2]), float(k2[1, 2]), right_in_left)
    return left, right


def measure_board(camera: Camera, model: StereoModel, board: BoardGeometry, timeout_s: float = 2.0):
    """Grab one frame and triangulate the board: ``TriangulationResult`` (raises CameraError)."""
    frame = camera.grab(timeout_s)
    return _triangulate(frame, model, board), frame


def _triangulate(frame, model, board: BoardGeometry):
    named = board if getattr(board, "kind", "checkerboard") != "checkerboard" else f"{board.corners[0]}x{board.corners[1]}"
    return triangulate_images(frame.left, frame.right, board=named, square_mm=board.square_mm, model=model)


def _quality_problem(result, config: StationConfig) -> str | None:
    q = result.quality
    c = config.capture
    if q.get("row_disagreement_max_px", 0.0) > c.max_row_disagreement_px:
        return (f"left/right rows disagree by {q['row_disagreement_max_px']:.2f} px (> {c.max_row_disagreement_px:g}): "
                "check the stereo calibration file and that both images are from the same frame")
    if q.get("plane_rms_mm", 0.0) > c.max_plane_rms_mm:
        return f"board not flat in the measurement ({q['plane_rms_mm']:.2f} mm RMS > {c.max_plane_rms_mm:g}): glare or a bent board?"
    lo, hi = c.distance_mm
    if not lo <= q.get("distance_mm", lo) <= hi:
        return f"board at {q['distance_mm']:.0f} mm, outside {lo:g}-{hi:g} mm"
    return None


def _start_compact(measured, board):
    """Compact points (and board pose) of the start posture's measurement; a partial view by its ids."""
    if measured.corner_ids is None:
        return compact_points_from_corners(measured.points_mm[None], board)
    from ...calibration import board_arrays, compact_points_from_fit

    posture = Posture(index=0, points_mm=measured.points_mm, corner_ids=measured.corner_ids)
    points, seen, poses = board_arrays([posture], board, board.square_mm)
    return compact_points_from_fit(points, seen, poses, board, board.square_mm)


def _session_record(session_dir: Path) -> Session | None:
    if (session_dir / "session.yaml").exists():
        return read_session(session_dir)
    return None


def _write_header(session_dir: Path, session: Session) -> None:
    write_yaml_atomic(session_dir / "session.yaml", session.header())


def _new_plan(config: StationConfig, link: StationLink, progress) -> PosturePlan:
    """Measure the board at the start posture and plan the postures around it (``station.capture.planning``)."""
    robot = load_robot(config.robot)
    here = link.controller.read_joints()
    start = np.asarray(config.plan.start_joints_deg, float) if config.plan.start_joints_deg is not None else here
    if np.max(np.abs(start - here)) > 0.05:
        raise CaptureError(f"the robot stands at {np.round(here, 2).tolist()}, not at plan.start_joints_deg "
                           f"{np.round(start, 2).tolist()}: jog it there (board in view), then run capture again")
    camera, model = link.camera, link.stereo_model
    if camera is None or model is None:  # every capturing link is opened with its camera and stereo model
        raise CaptureError("the station link has no camera (or stereo model) to measure the board with")
    try:
        measured, _ = measure_board(camera, model, config.target, config.camera.grab_timeout_s)
    except SquareSizeMismatch as exc:
        raise CaptureError(f"at the start posture: {exc}") from None
    except CameraError as exc:
        raise CaptureError(f"no board at the start posture ({exc}); point the camera at the board from about 0.9 m") from None
    compact = _start_compact(measured, config.target)
    progress(f"board found at the start posture, {measured.quality['distance_mm']:.0f} mm away; planning "
             f"{config.plan.postures} postures ...")
    p = config.plan
    sampling = ViewSampling(distance_mm=p.distance_mm, cone_deg=p.cone_deg, roll_deg=p.roll_deg, aim_mm=p.aim_mm,
                            joint_margin_deg=p.joint_margin_deg)
    # keep the camera on the robot's side of the board
    board2base = robot.forward_transform(start) @ config.camera.nominal_mount_transform() @ compact.target2cam[0]
    side = -np.array([board2base[0, 3], board2base[1, 3], 0.0])
    if np.linalg.norm(side) > 1e-6:
        sampling = ViewSampling(**{**sampling.__dict__, "side": tuple(side / np.linalg.norm(side))})
    return plan_postures(robot, start, compact.target2cam[0], config.camera.nominal_mount_transform(), config.target,
                         p.postures, sampling, stereo_views(model), p.seed,
                         thresholds=config_thresholds(config), cell=cell_check(config),
                         partial_views=p.partial_views)


@dataclass
class CaptureRun:
    """The session a capture works on and its plan (new, or read back when resuming).

    Attributes
    ----------
    session : Session
        As on disk when the run started; its capture record (``extra['capture']``) is updated and
        rewritten after each posture.
    plan_joints : ndarray, shape (n, dof)
        Planned joint angles (deg), rounded as embedded in the RAPID program; row ``i`` is posture ``i``
        (``postures/NNN.yaml``), the controller's posture ``i + 1``.
    plan_score : dict
        The plan's :class:`~handeye.station.capture.planning.PlanScore` as recorded in the session.
    """

    session: Session
    plan_joints: np.ndarray
    plan_score: dict

    @property
    def board2base(self) -> np.ndarray | None:
        """The board estimate the plan was made for (its stand is a world zone), when recorded."""
        estimate = self.session.extra["capture"].get("board_estimate")
        return None if estimate is None else transform_from_pose(estimate["position_mm"], estimate["quaternion_wxyz"])

    @property
    def done(self) -> set:
        """Session indices (0-based) of the postures on disk."""
        return {p.index for p in self.session.postures}


def plan_line(score: PlanScore, postures: int) -> str:
    """The plan as the operator reads it, in the verdict's quality words (``calibration.quality_words``),
    and what the cell check rejected."""
    rejected = (f"; clear of the cell: {score.rejected_postures} postures and {score.rejected_moves} moves rejected "
                f"({'; '.join(score.rejections)})" if score.rejections else "; clear of the cell, nothing rejected")
    return (f"plan: {postures} postures; rotation-axis spread {score.rotation_axis_spread_deg:.1f} deg "
            f"({MAX_AXIS_SPREAD_DEG:.1f} = even over the sphere); relative rotation angle between postures median "
            f"{score.median_pair_angle_deg:.0f} deg (min {score.min_pair_angle_deg:.0f}); motion "
            f"{score.motion_time_s:.0f} s at full speed; expected accuracy about {score.predicted_sigma_mm:.2f} mm / "
            f"{score.predicted_sigma_deg:.3f} deg (simulated){rejected}")


def plan_session(config: StationConfig, session_dir: Path, link: StationLink, progress: Callable[[str], None]) -> CaptureRun:
    """Plan the postures and create the session with its capture record (``capture.station: mock|real``)."""
    plan = _new_plan(config, link, progress)
    plan_score = plan.score.to_dict()
    progress(plan_line(plan.score, len(plan.joints_deg)))
    for partial in plan.partial:  # ChArUco: postures planned with the board partly out of view
        progress(f"plan: {partial.line()}")
    for note in plan.notes:
        progress(f"plan warning: {note}")
    session = Session(setup="eye_in_hand", robot=config.robot, target=config.target, extra={"capture": {
        "station": station_kind(config, link),
        "plan_joints_deg": [[round(float(v), 4) for v in row] for row in plan.joints_deg],
        "start_joints_deg": [round(float(v), 4) for v in plan.start_joints_deg],
        "plan_score": plan_score,
        **({"plan_partial": [{"posture": p.number, "in_view": round(p.in_view, 3)} for p in plan.partial]}
           if plan.partial else {}),
        "board_estimate": pose_from_transform(plan.board2base),
        "nominal_mount": pose_from_transform(plan.cam2tool0),
        "skipped": {},
        "config": config.to_dict(),
    }})
    from ..cell.preview import write_preview

    preview = write_preview(session_dir / "preview.png", load_robot(config.robot), plan)  # before the plan: a kill
    create_session(session_dir, session)  # between the two leaves no plan, and the rerun plans anew
    progress(f"plan preview (the cell from above and from the side, the flange path, the numbered postures): "
             f"{preview}")
    return CaptureRun(session, np.round(plan.joints_deg, 4), plan_score)  # as embedded in the RAPID program


#: What drawing a plan's preview again needs from the capture record in ``session.yaml``.
_PREVIEW_KEYS = ("plan_joints_deg", "start_joints_deg", "board_estimate", "nominal_mount")


def recorded_plan(session: Session, config: StationConfig) -> PosturePlan:
    """The plan of a capture as its record in ``session.yaml`` holds it (to draw its preview again),
    checked against the cell of ``config``.

    Raises
    ------
    CaptureError
        Naming what the record lacks (``start_joints_deg``: planned by an older handeye).
    """
    record = session.extra.get("capture", {})
    target = session.target
    lacking = [key for key in _PREVIEW_KEYS if key not in record] + (["target"] if target is None else [])
    if lacking or target is None:
        raise CaptureError(f"session.yaml records no {', '.join(lacking)}")
    try:
        joints = np.array(record["plan_joints_deg"], float)
        start = np.array(record["start_joints_deg"], float)
        board2base, cam2tool0 = (transform_from_pose(record[key]["position_mm"], record[key]["quaternion_wxyz"])
                                 for key in ("board_estimate", "nominal_mount"))
        score = PlanScore.from_dict(record.get("plan_score", {}))
    except (KeyError, TypeError, ValueError) as exc:
        raise CaptureError(f"its capture record in session.yaml is unreadable ({exc})") from None
    return PosturePlan(joints, board2base, cam2tool0, score, start, target, [], cell_check(config))


def repair_plan(config: StationConfig, session_dir: Path, session: Session, progress: Callable[[str], None]) -> Path | None:
    """Resume: draw ``SESSION/preview.png`` again when a kill left it out (from :func:`recorded_plan`), or
    say in one line why it cannot be; returns the preview's path when it is there."""
    from ..cell.preview import write_preview

    path = session_dir / "preview.png"
    if path.is_file():
        return path
    try:
        plan = recorded_plan(session, config)
        robot = load_robot(session.robot or config.robot)
    except HandEyeError as exc:
        progress(f"{path} is missing and cannot be drawn again: {exc}; the capture goes on without a preview")
        return None
    progress(f"plan preview drawn again (a run was interrupted before writing it): {write_preview(path, robot, plan)}")
    return path


def resume_session(config: StationConfig, session_dir: Path, session: Session, progress: Callable[[str], None],
                   link: StationLink | None = None) -> CaptureRun:
    """Read the plan of a capture on disk; refuse one made on the other station (mock vs real:
    :func:`~handeye.station.config.station_kind.station_kind` of ``config`` and ``link``)."""
    record = session.extra["capture"]
    if record.get("mode") == "guided":
        raise CaptureError(f"{session_dir} was captured in guided mode: resume it with capture --guided, or start a new "
                           "session folder")
    recorded = session_origin(session)
    if recorded in (MOCK, REAL) and recorded != station_kind(config, link):
        raise CaptureError(f"{session_dir} was captured on the {_STATION_NAMES[recorded]}; resume it on the same "
                           f"station ({'--mock, or the rehearsal config' if recorded == MOCK else '--config STATION.yaml with the real hardware'}) "
                           "or start a new session folder")
    plan_joints = np.array(record["plan_joints_deg"], float)
    remove_stale_temporaries(session_dir)  # a killed run may leave one beside the (whole) file it was replacing
    progress(f"resuming {session_dir}: {len(session.postures)} of {len(plan_joints)} postures on disk")
    return CaptureRun(session, plan_joints, record.get("plan_score", {}))


def open_capture(config: StationConfig, session_dir: Path, link: StationLink, progress: Callable[[str], None]) -> CaptureRun:
    """The capture's session: resumed when ``session_dir`` holds a capture, else planned and created."""
    session = _session_record(session_dir)
    if session is None:
        return plan_session(config, session_dir, link, progress)
    if "capture" not in session.extra:
        raise CaptureError(f"{session_dir} holds a session that was not made by capture; choose a new folder")
    return resume_session(config, session_dir, session, progress, link)


def _session_program(config: StationConfig, plan_joints: np.ndarray, board2base, link: StationLink | None) -> list:
    """The RAPID modules of the plan (``rapid.generate.RapidModule``), as :func:`write_program` writes them."""
    from ...drivers import RAPID_LINKS
    from ...rapid import render_program
    from ...rapid import station_from_dict

    data = config.rapid_dict(plan_joints, board2base)
    if link is not None and link.is_mock and link.mock is not None and data["controller"]["write_key"] is None:
        # the embedded station's controller holds a key of its own (HeKey.sys, handed to the PC): its
        # link module asks HeKey for it. The key itself never goes into the program modules.
        data["controller"]["write_key"] = link.mock.write_key
    return render_program(station_from_dict(data, config.source, links=RAPID_LINKS), plan_joints)


def _same_text(path: Path, text: str) -> bool:
    try:
        return path.read_text(encoding="ascii", errors="replace") == text
    except OSError:
        return False


def write_program(config: StationConfig, session_dir: Path, plan_joints: np.ndarray, progress: Callable[[str], None],
                  board2base: np.ndarray | None = None, link: StationLink | None = None) -> Path:
    """Write the RAPID program into ``SESSION/rapid`` (with ``cell.world_zones`` the keep-out volumes and
    the stand of the board at ``board2base`` as world zones); returns the folder. On the embedded mock
    station (``link``) the program asks the mock's HeKey for the write key.

    Written once: modules on disk are never rewritten. A folder a kill left half written (some modules
    missing, those present as this config generates them) is completed; one whose modules differ is
    refused (CaptureError naming them)."""
    from ...rapid import write_modules

    rapid_dir = session_dir / "rapid"
    modules = _session_program(config, plan_joints, board2base, link)
    missing = [m for m in modules if not (rapid_dir / m.filename).is_file()]
    if not missing:
        return rapid_dir
    present = [m for m in modules if m not in missing]
    differ = [m.filename for m in present if not _same_text(rapid_dir / m.filename, m.text)]
    if differ:
        raise CaptureError(f"{rapid_dir} lacks {', '.join(m.filename for m in missing)} and its {', '.join(differ)} "
                           "differ from the program this config generates: delete that folder (nothing has moved "
                           "with it) and run the same command again")
    write_modules(missing, rapid_dir)
    progress(f"RAPID program written to {rapid_dir}" if not present else
             f"RAPID program in {rapid_dir} completed (a run was interrupted while writing it): "
             f"{', '.join(m.filename for m in missing)} written")
    return rapid_dir


def install_program(config: StationConfig, session_dir: Path, plan_joints: np.ndarray, link: StationLink,
                    progress: Callable[[str], None], board2base: np.ndarray | None = None) -> None:
    """Write the RAPID program (:func:`write_program`), load it when the station can, and wait until the
    controller runs a program with the plan's posture count."""
    rapid_dir = write_program(config, session_dir, plan_joints, progress, board2base, link)
    if link.load_program is not None:
        link.load_program(plan_joints, rapid_dir)
        link.controller.close()  # the posture count is read at connect: read it again
        link.controller.connect()
    _wait_for_program(link.controller, len(plan_joints), rapid_dir, progress)


def release_waiting_posture(controller: Controller, done: set, progress: Callable[[str], None]) -> None:
    """Resume: a robot still waiting at a posture whose file is on disk (a run stopped between the
    grab and the ACK) is acknowledged, so the program takes the next request."""
    status = controller.status()
    if status.moving:
        status = controller.wait_at_rest()
    if status.awaiting_ack and status.posture:
        k = status.posture  # the controller's number: posture k - 1 of the session
        if (k - 1) in done:
            controller.acknowledge(k)
            progress(f"posture {k - 1} was already on disk: acknowledged")


def visit_postures(config: StationConfig, session_dir: Path, run: CaptureRun, link: StationLink, on_posture: Callable,
                   stop_after: int | None = None, observer: Callable | None = None,
                   stop_when: Callable[[PostureReport], bool] | None = None) -> tuple[list, dict]:
    """The posture loop: move, measure, write each posture not yet on disk, record skips, acknowledge.

    Returns the posture numbers (the files' ``NNN``) captured in this run and ``{number: reason}`` of those
    skipped. The controller is asked for posture ``index + 1`` (its program counts from 1). ``observer``
    receives the ``station.capture.events`` of each posture (Prompt, Measured per grab, Verdict).
    ``stop_when(report)``, when given, ends the loop after a posture for which it is true (a check that
    can no longer reach its minimum); a posture whose grab sees no board at all is then not grabbed again.
    """
    observer = observer or (lambda event: None)
    controller, robot = link.controller, load_robot(config.robot)
    total, done = len(run.plan_joints), run.done
    record = run.session.extra["capture"]
    captured, skipped = [], {}
    remaining = [index for index in range(total) if index not in done]
    for n, index in enumerate(remaining):
        if stop_after is not None and n >= stop_after:
            break
        t0 = time.monotonic()
        k = index + 1  # the controller's number of the posture
        status = controller.status()
        if not (status.awaiting_ack and status.posture == k):
            observer(Prompt("move", f"moving to posture {index} ({len(done) + n + 1} of {total})", index))
            controller.goto_posture(k, expected_joints=run.plan_joints[index])
        report = _capture_posture(config, session_dir, link, robot, index, total, run.plan_joints[index], observer,
                                  retry_absent=stop_when is None)
        report.elapsed_s, report.done = time.monotonic() - t0, len(done) + n + 1
        if report.ok:
            captured.append(index)
            record["skipped"].pop(str(index), None)
        else:
            skipped[index] = report.message
            record["skipped"][str(index)] = report.message
        run.session.extra["capture"] = record
        _write_header(session_dir, run.session)
        controller.acknowledge(k)
        on_posture(report)
        if stop_when is not None and stop_when(report):
            break
    return captured, skipped


def capture(
    config: StationConfig,
    session_dir: str | Path,
    link: StationLink,
    progress: Callable[[str], None] = lambda message: None,
    on_posture: Callable[[PostureReport], None] = lambda report: None,
    stop_after: int | None = None,
    plan_only: bool = False,
    confirm: Callable[[str], bool] | None = None,
    observer: Callable | None = None,
) -> CaptureSummary:
    """Run (or resume) a capture into ``session_dir``: plan (or resume), program, confirm, release a
    posture left waiting, visit the postures.

    Parameters
    ----------
    config : StationConfig
    session_dir : path
        New or existing session (resumed when it holds a capture plan).
    link : StationLink
        The connected station (``station.runtime.open_station``): its controller and camera, the
        stereo model, and ``load_program(postures, rapid_dir)`` when the station can put the generated
        program on the controller itself (the mock can). Without it, the operator loads
        ``rapid_dir/*.mod`` and the capture waits until the controller reports the plan's posture count.
    progress : callable
        Receives one-line messages.
    on_posture : callable
        Receives a :class:`PostureReport` after each posture.
    stop_after : int, optional
        Stop after this many postures of this run (tests of the resume).
    plan_only : bool
        Plan (or read the plan back), write the preview and the RAPID program, and stop: nothing moves.
    confirm : callable, optional
        ``confirm(question) -> bool``, asked once before the first move of this run at a real station
        (the operator's yes). Without it a real station refuses to move; the embedded mock moves
        without asking and says so.
    observer : callable, optional
        Receives the ``station.capture.events`` from the capture thread (the live view): CaptureStarted
        once the session is open, then per posture Prompt, Measured (each grab) and Verdict.

    Raises
    ------
    CaptureError, ControllerError, CameraError
    """
    started = time.monotonic()
    session_dir = Path(session_dir)
    run = open_capture(config, session_dir, link, progress)
    preview = repair_plan(config, session_dir, run.session, progress)
    if plan_only:
        write_program(config, session_dir, run.plan_joints, progress, run.board2base, link)
        progress("plan only: nothing moved; " + (f"look at {preview}, then " if preview is not None else "")
                 + "run the same command without --plan-only to capture")
        return CaptureSummary(session_dir, len(run.plan_joints), [], sorted(run.done), {},
                              time.monotonic() - started, run.plan_score, preview)
    install_program(config, session_dir, run.plan_joints, link, progress, run.board2base)
    confirm_motion(config, session_dir, run, link, confirm, progress)
    already = sorted(run.done)
    if observer is not None:
        observer(CaptureStarted("planned", str(session_dir), list(run.session.postures),
                                dict(run.session.extra["capture"].get("skipped", {})), run.plan_joints))
    release_waiting_posture(link.controller, run.done, progress)
    captured, skipped = visit_postures(config, session_dir, run, link, on_posture, stop_after, observer)
    if link.stop_program is not None and stop_after is None:
        link.stop_program()  # the PC started it (RWS); a resumed capture loads and starts it again
        progress("RAPID program stopped: the capture went through the plan")
    return CaptureSummary(session_dir, len(run.plan_joints), captured, already, skipped, time.monotonic() - started,
                          run.plan_score, preview)


def confirm_motion(config: StationConfig, session_dir: Path, run: CaptureRun, link: StationLink,
                   confirm: Callable[[str], bool] | None, progress: Callable[[str], None]) -> None:
    """Before the first move of a run: a real station asks the operator (``confirm``) and refuses without a
    yes; the embedded mock moves without asking and says so. Nothing to move: nothing asked."""
    left = len(run.plan_joints) - len(run.done)
    if left <= 0:
        return
    speed = f"{config.motion.speed_override_pct:g} % of {config.motion.speed_tcp_mm_s:g} mm/s"
    if link.is_mock:
        progress(f"moving the mock robot through {left} postures at {speed} without asking (mock station; "
                 "a real station asks first)")
        return
    preview = session_dir / "preview.png"
    question = (f"move the robot through {left} postures at {speed}, MoveAbsJ, checked against the cell"
                + (f" (preview: {preview})?" if preview.is_file() else "?"))
    if confirm is None:
        raise CaptureError("motion needs the operator's confirmation: answer the prompt at a terminal, or give --yes "
                           "to move without asking (scripts)")
    if not confirm(question):
        raise CaptureError("not confirmed: nothing moved; run the same command again when ready (it resumes)")


def _wait_for_program(controller, total: int, rapid_dir: Path, progress, timeout_s: float = 600.0) -> None:
    info = controller.info()
    if info.postures == total:
        return
    progress(f"the controller's program holds {info.postures} postures, the plan {total}: load the modules in "
             f"{rapid_dir} into the robot task and start main (waiting up to {timeout_s / 60:.0f} min)")
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        time.sleep(2.0)
        controller.close()
        controller.connect()
        if controller.info().postures == total:
            return
    raise CaptureError(f"the controller never reported the plan's {total} postures; load {rapid_dir}/*.mod and retry")


def read_flange(config: StationConfig, link: StationLink, robot: RobotModel, label: str) -> tuple[np.ndarray, np.ndarray]:
    """Joints and flange pose (``tool02base``) of the robot at rest, the pose checked against our kinematics
    of the joints (CaptureError naming ``label`` when they disagree)."""
    joints = link.controller.read_joints()
    pose = link.controller.read_tool0_pose()
    tool02base = transform_from_pose(pose.position_mm, pose.quaternion_wxyz)
    expected = robot.forward_transform(joints)
    mismatch = float(translation_error_mm(expected, tool02base))
    if mismatch > config.capture.max_pose_mismatch_mm or rotation_error_deg(expected, tool02base) > 0.05:
        raise CaptureError(f"{label}: the controller's flange pose is {mismatch:.2f} mm from our {robot.name} "
                           "kinematics of its joints: check the robot model, and that CRobT uses tool0 and wobj0")
    return joints, tool02base


def measure_with_retries(config: StationConfig, link: StationLink, on_grab: Callable | None = None) -> tuple:
    """Grab and triangulate until the quality holds (``capture.retries`` more tries): ``(result, frame,
    problem, attempts)``, ``problem`` None when the measurement is good. ``on_grab(result, frame, problem)``,
    when given, after every grab (``result`` None when the board was not measured)."""
    return measure_posture(config, link, on_grab)[:4]


def measure_posture(config: StationConfig, link: StationLink, on_grab: Callable | None = None,
                    retry_absent: bool = True) -> tuple:
    """:func:`measure_with_retries` and whether the last grab saw no checkerboard at all:
    ``(result, frame, problem, attempts, absent)``; ``retry_absent=False``: no retry after such a grab
    (retries help a blurred, glaring or badly lit board, not one that is out of view)."""
    camera = link.camera
    if camera is None:  # every capturing link is opened with its camera (station.runtime)
        raise CaptureError("the station link has no camera to measure the board with")
    problem = "no frame"
    result = frame = None
    attempts, absent = 0, False
    for attempts in range(1, config.capture.retries + 2):
        grabbed = None
        try:
            grabbed = camera.grab(config.camera.grab_timeout_s)
            result, frame = _triangulate(grabbed, link.stereo_model, config.target), grabbed
        except CameraError as exc:
            problem, absent = str(exc), isinstance(exc, NoBoardInView)
            if on_grab is not None and grabbed is not None:
                on_grab(None, grabbed, problem)
            if absent and not retry_absent:
                break
            continue
        absent = False
        problem = _quality_problem(result, config)
        if on_grab is not None:
            on_grab(result, frame, problem)
        if problem is None:
            break
    return result, frame, problem, attempts, absent


def store_posture(config: StationConfig, session_dir: Path, index: int, joints: np.ndarray, tool02base: np.ndarray,
                  result, frame: StereoFrame | None, **extra: object) -> None:
    """Write posture ``index`` (0-based) of the session atomically: pose, joints, corners, quality, ``extra``
    (and the images when ``capture.save_images``)."""
    extra = {"quality": {key: (round(v, 4) if isinstance(v, float) else v) for key, v in result.quality.items()},
             **extra, "captured_at": time.strftime("%Y-%m-%dT%H:%M:%S")}
    if config.capture.save_images and frame is not None:
        import cv2

        images = session_dir / "images"
        images.mkdir(exist_ok=True)
        cv2.imwrite(str(images / f"{index:03d}_left.png"), frame.left)
        cv2.imwrite(str(images / f"{index:03d}_right.png"), frame.right)
        extra["images"] = [f"images/{index:03d}_left.png", f"images/{index:03d}_right.png"]
    write_posture(session_dir, Posture(index=index, tool0_in_base=tool02base, joints_deg=joints,
                                       points_mm=result.points_mm, extra=extra,
                                       corner_ids=getattr(result, "corner_ids", None)))


def measurement_line(quality: dict) -> str:
    """``104 corners at 912 mm, rows 0.08 px, plane 0.14 mm``."""
    return (f"{quality['corners']} corners at {quality['distance_mm']:.0f} mm, rows "
            f"{quality['row_disagreement_max_px']:.2f} px, plane {quality['plane_rms_mm']:.2f} mm")


def grab_observer(observer: Callable | None, index: int, tool02base: np.ndarray) -> Callable | None:
    """``on_grab`` of :func:`measure_with_retries` that hands each grab to ``observer`` as a ``Measured`` event."""
    if observer is None:
        return None
    return lambda result, frame, problem: observer(Measured(index, frame, result, problem, tool02base))


def _capture_posture(config, session_dir, link: StationLink, robot, index, total, planned,
                     observer: Callable | None = None, retry_absent: bool = True) -> PostureReport:
    """Steps 2-4 at posture ``index`` (the robot at rest there): check the pose, measure, write the posture file
    (``retry_absent``: :func:`measure_posture`)."""
    observer = observer or (lambda event: None)
    joints, tool02base = read_flange(config, link, robot, f"posture {index}")
    if np.max(np.abs(joints - planned)) > 0.05:
        raise CaptureError(f"posture {index}: the robot stands at {np.round(joints, 3).tolist()}, not at the planned "
                           f"{np.round(planned, 3).tolist()}: is the right program loaded?")
    result, frame, problem, attempts, absent = measure_posture(config, link, grab_observer(observer, index, tool02base),
                                                               retry_absent)
    if problem is not None:
        report = PostureReport(index, total, False, f"posture {index} skipped after {attempts} attempt(s): {problem}",
                               result.quality if result is not None else {}, attempts, board_absent=absent)
        observer(Verdict(index, SKIPPED, report.message, report.quality))
        return report
    if result is None:  # measure_posture: no problem means the last grab was measured
        raise CaptureError(f"posture {index}: no measurement although no problem was reported")
    store_posture(config, session_dir, index, joints, tool02base, result, frame, controller_posture=index + 1)
    report = PostureReport(index, total, True, f"posture {index}: {measurement_line(result.quality)}", result.quality,
                           attempts)
    observer(Verdict(index, CAPTURED, report.message, result.quality, tool02base, result.points_mm))
    return report
