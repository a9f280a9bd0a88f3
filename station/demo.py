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
from dataclasses import dataclass, replace
from pathlib import Path

from ..calibration.errors import HandEyeError
from ..calibration.session import read_session
from ..calibration.solve import calibrate, problem_from_session
from ..calibration.transforms import pose_from_transform, rotation_error_deg, translation_error_mm
from .capture import capture
from .config import StationConfig, default_config
from .runtime import open_station
from .writeback import writeback

__all__ = ["DemoOptions", "run_demo", "DEMO_MARKER"]

#: A file that marks a folder as a demo's own, so a rerun may replace it.
DEMO_MARKER = ".handeye-demo"


@dataclass(frozen=True)
class DemoOptions:
    session: str = "handeye_demo"
    postures: int = 30
    protocol: str = "socket"
    seed: int = 7
    report: bool = True


def _fresh_folder(path: Path) -> None:
    if path.exists():
        if not (path / DEMO_MARKER).exists():
            raise HandEyeError(f"{path} exists and is not a demo folder; choose another with --session")
        shutil.rmtree(path)
    path.mkdir(parents=True)
    (path / DEMO_MARKER).write_text("created by handeye demo; the next demo run replaces this folder\n")


def run_demo(options: DemoOptions = DemoOptions(), config: StationConfig | None = None,
             progress=lambda message: None, on_posture=lambda report: None) -> dict:
    """Run the demo; returns the JSON mapping of ``handeye demo`` (conventions.md keys first)."""
    started = time.monotonic()
    config = config or default_config()
    config = replace(config, plan=replace(config.plan, postures=options.postures),
                     mock=replace(config.mock, protocol=options.protocol, seed=options.seed))
    folder = Path(options.session)
    _fresh_folder(folder)
    session_dir = folder / "session"
    with open_station(config, mock=True) as link:
        progress(f"mock station up: IRB 1400 on {link.controller.address} ({options.protocol}), XB3 serial "
                 f"{link.camera.serial}")
        summary = capture(config, session_dir, link.controller, link.camera, link.stereo_model, link.load_program,
                          progress=progress, on_posture=on_posture)
        captured_s = time.monotonic() - started
        session = read_session(session_dir)
        problem = problem_from_session(session)
        result = calibrate(problem)
        progress(f"calibrated {problem.n} postures in {result.runtime_s * 1000:.0f} ms (robust default), "
                 f"outliers: {result.outliers or 'none'}")
        verdict = _verdict(result, problem, config)
        report_path = None
        if options.report:
            report_path = _report(session_dir, problem, result, verdict)
        outcome = writeback(session_dir, config, result, link.controller,
                            verdict_passed=verdict["passed"], verdict_reason=verdict["summary"], progress=progress)
        truth = link.truth_cam2tool0
    errors = {"rotation_error_deg": float(rotation_error_deg(result.x, truth)),
              "translation_error_mm": float(translation_error_mm(result.x, truth))}
    return {
        "camera_pose": {"parent": "tool0", **pose_from_transform(result.x)},
        "truth_camera_pose": {"parent": "tool0", **pose_from_transform(truth)},
        "postures_captured": len(summary.captured) + len(summary.already),
        "readback_ok": bool(outcome.readback_ok),
        "errors": errors,
        "uncertainty": result.uncertainty,
        "outliers": result.outliers,
        "metrics": result.metrics,
        "verdict": verdict,
        "tooldata": outcome.literal,
        "session": str(session_dir),
        "report": str(report_path) if report_path else None,
        "plan_score": summary.plan_score,
        "protocol": options.protocol,
        "capture_s": captured_s,
        "runtime_s": result.runtime_s,
        "wall_s": time.monotonic() - started,
    }


def _verdict(result, problem, config) -> dict:
    """The quality verdict as a plain mapping (``passed``, ``summary``, ``checks``)."""
    from .quality import QualityThresholds, verdict

    v = verdict(result, problem, QualityThresholds.from_dict(config.quality))
    failed = [c for c in v.checks if not c.passed]
    return {"passed": bool(v.passed),
            "summary": "all checks passed" if not failed else "; ".join(f"{c.name} {c.value:.4g} > {c.limit:g}" for c in failed),
            "checks": [{"name": c.name, "value": float(c.value), "limit": float(c.limit), "passed": bool(c.passed)}
                       for c in v.checks]}


def _report(session_dir, problem, result, verdict_mapping):
    from .report import comparison_results, write_report
    from .quality import QualityThresholds, verdict
    from ..rapid.literals import pose_literal

    v = verdict(result, problem, QualityThresholds.from_dict({}))
    return write_report(session_dir / "report.html", session_dir, problem, result, comparison_results(problem), v,
                        pose_literal(result.x), title="handeye demo: mock station")
