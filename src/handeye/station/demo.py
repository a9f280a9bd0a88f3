"""``handeye demo``: the whole station job on the embedded mock robot and camera.

Starts the mock station (a simulated IRB 1400 with small kinematic errors behind a real controller
server on 127.0.0.1, a simulated XB3 with a hidden true mount), measures the board, plans the
postures, writes the RAPID program and loads it, captures every posture through the real drivers,
calibrates with the recommended default, judges the result, writes the tool data back through the
controller link, reads it back, and compares the recovered camera pose with the hidden truth.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from ..base import HandEyeError
from ..base import make_folder, write_failure, write_text_atomic
from ..geometry import pose_from_transform, rotation_error_deg, translation_error_mm
from ..drivers import DEFAULT_PROTOCOL
from .report.assessment import Assessment, assess, comparison_methods
from .calibrate import calibrate_session_folder
from .capture.loop import PostureReport, capture
from .config.station import StationConfig, default_config
from .origin import MOCK
from .report.quality import Verdict, config_thresholds
from .report.document import write_report
from .runtime import open_station
from .writeback import writeback

__all__ = ["DemoOptions", "run_demo", "DEMO_MARKER"]

#: A file that marks a folder as a demo's own, so a rerun may replace it.
DEMO_MARKER = ".handeye-demo"


@dataclass(frozen=True)
class DemoOptions:
    session: str = "handeye_demo"
    postures: int = 30
    protocol: str = DEFAULT_PROTOCOL
    seed: int = 7
    report: bool = True
    kinematics: bool = False
    #: The board (``--board``): None keeps the config's (the station's checkerboard).
    board: object = None
    #: ``mock.occlude`` for the run (``--occlude``), or None.
    occlude: object = None


def _fresh_folder(path: Path) -> None:
    """An empty demo folder at ``path``: created, or a previous demo's replaced (anything else is refused)."""
    if path.exists():
        if not (path / DEMO_MARKER).exists():
            raise HandEyeError(f"{path} exists and is not a demo folder; choose another with --session")
        try:
            shutil.rmtree(path)
        except OSError as exc:
            raise write_failure(path, exc, "replace the demo folder") from None
    make_folder(path)
    write_text_atomic(path / DEMO_MARKER, "created by handeye demo; the next demo run replaces this folder\n")


def run_demo(options: DemoOptions = DemoOptions(), config: StationConfig | None = None,
             progress: Callable[[str], None] = lambda message: None,
             on_posture: Callable[[PostureReport], None] = lambda report: None) -> dict:
    """Run the demo; returns the JSON mapping of ``handeye demo`` (``mock: true``, then the
    conventions.md keys)."""
    started = time.monotonic()
    config = config or default_config()
    config = replace(config, plan=replace(config.plan, postures=options.postures),
                     mock=replace(config.mock, protocol=options.protocol, seed=options.seed,
                                  occlude=options.occlude if options.occlude is not None else config.mock.occlude))
    if options.board is not None:
        config = replace(config, target=options.board)
    folder = Path(options.session)
    _fresh_folder(folder)
    session_dir = folder / "session"
    with open_station(config, mock=True) as link:
        if link.camera is None:  # open_station(mock=True): the embedded station, its camera with it
            raise HandEyeError("the demo's mock station opened without its camera")
        progress(f"mock station up: IRB 1400 on {link.controller.address} ({options.protocol}), XB3 serial "
                 f"{link.camera.serial}")
        summary = capture(config, session_dir, link, progress=progress, on_posture=on_posture)
        captured_s = time.monotonic() - started
        assessment = _assess(session_dir, config, options.report, progress)
        result, verdict = assessment.result, _judged(assessment)
        report_path = None
        if options.report:
            report_path = write_report(session_dir / "report.html", assessment, title="handeye demo: mock station")
            progress(f"report written to {report_path}")
        outcome = writeback(session_dir, config, result, link.controller, verdict_passed=verdict.passed,
                            verdict_reason=verdict.line(), progress=progress, origin=MOCK, mock_controller=True)
        truth = link.truth_cam2tool0
        if truth is None:  # the embedded mock always knows its hidden mount
            raise HandEyeError("the mock station did not give its hidden camera mount to compare with")
        hidden = link.mock.truth["dh_deviation"] if link.mock is not None else None
    errors = {"rotation_error_deg": float(rotation_error_deg(result.x, truth)),
              "translation_error_mm": float(translation_error_mm(result.x, truth))}
    return {
        "mock": True,
        "camera_pose": {"parent": "tool0", **pose_from_transform(result.x)},
        "truth_camera_pose": {"parent": "tool0", **pose_from_transform(truth)},
        "postures_captured": len(summary.captured) + len(summary.already),
        "readback_ok": bool(outcome.readback_ok),
        "errors": errors,
        "uncertainty": result.uncertainty,
        "outliers": result.outliers,
        "metrics": result.metrics,
        "verdict": verdict.to_json(),
        "tooldata": outcome.literal,
        "session": str(session_dir),
        "report": str(report_path) if report_path else None,
        "plan_score": summary.plan_score,
        "protocol": options.protocol,
        "capture_s": captured_s,
        "runtime_s": result.runtime_s,
        "wall_s": time.monotonic() - started,
        **_kinematics(assessment, config, options, hidden, progress),
    }


def _kinematics(assessment: Assessment, config: StationConfig, options: DemoOptions, hidden, progress) -> dict:
    """With the option (or ``kinematics.identify``): the identified arm next to the mock's hidden one."""
    if not (options.kinematics or config.kinematics.identify):
        return {}
    from .kinematics_step import hidden_offsets, identify_outcome, kinematics_json

    ident, standoff = identify_outcome(assessment, config.kinematics.standoff_mm)
    progress("identified the arm's kinematics with the camera")
    entry = kinematics_json(ident, standoff)
    if hidden is not None:
        entry["hidden"] = hidden_offsets(hidden)
    return {"kinematics": entry}


def _judged(assessment: Assessment) -> Verdict:
    """The verdict of an assessment made with thresholds (:func:`_assess` always gives them)."""
    if assessment.verdict is None:
        raise HandEyeError(f"the demo's calibration of {assessment.session_path} was not judged")
    return assessment.verdict


def _assess(session_dir: Path, config: StationConfig, compare: bool, progress) -> Assessment:
    """Calibrate the captured session (the default estimator) and assess it against the config's thresholds,
    with the method comparison when the report is wanted."""
    from ..rapid import tooldata_literal

    from .result_file import save_result

    outcome = calibrate_session_folder(session_dir)
    result, problem = outcome.result, outcome.problem
    if problem is None:  # calibrate_session_folder solves the session's problem and keeps it
        raise HandEyeError(f"the calibration of {session_dir} kept no problem")
    progress(f"calibrated {problem.n} postures in {result.runtime_s * 1000:.0f} ms (the default estimator), "
             f"outliers: {result.outliers or 'none'}; saved in {save_result(outcome)}")
    assessment = assess(outcome, config_thresholds(config), methods=comparison_methods() if compare else (),
                        tooldata_literal=tooldata_literal(result.x, config.tool.mass_kg, config.tool.cog_mm))
    for reason in assessment.comparison_failures.values():  # a plug-in's method that failed or took too long
        progress(f"not compared: {reason}")
    progress(_judged(assessment).line())
    return assessment
