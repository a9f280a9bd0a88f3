"""What the live view shows, kept from the capture's events (``station.capture.events``).

:class:`ViewState` folds the events into the page's JSON: the posture list (each posture's quality,
or why it was skipped), the coverage in the quality words (``calibration.quality_words``: image
cells, rotation axes, distance spread), what is still missing and the hint (``station.guided.capture.
what_is_missing``, the same words the guided capture prints), the progress, GOOD ENOUGH, for a planned
capture the plan seen from above and from the side with the current posture and the time left, and,
once the postures allow a solve, the calibration (:class:`Predictor`) that predicts where the next
frame's corners should be; once the run is over (``CaptureEnded``), how it ended in place of the hint
and the current posture (what is missing without the advice to capture more). It runs in the view's
thread, never in the capture's.
"""

from __future__ import annotations

import time

import numpy as np

from ...base import HandEyeError
from ...robot import load_robot
from ...calibration import MIN_POSTURES
from ...calibration import AXIS_SPREAD_NAME, board_distances_mm, distance_spread_mm, hand_axis_coverage, image_cells
from ...calibration import Posture, Session
from ..capture.loop import stereo_views
from ..capture.events import CAPTURED, SKIPPED, CaptureEnded, CaptureStarted, Prompt, Verdict
from ..guided.capture import postures_needed, what_is_missing
from ..report.quality import config_thresholds, direction_name

__all__ = ["PREDICTION_METHOD", "Predictor", "ViewState"]

#: The solver of the view's running calibration: the paper's all-postures method, fast and without selection.
PREDICTION_METHOD = "mc"


class Predictor:
    """A running calibration of the postures captured so far, and where it predicts the board's corners.

    Parameters
    ----------
    session : Session
        Set-up, robot and board of the capture (its postures are replaced by the captured ones).
    stereo_model : drivers.camera.stereo.StereoModel
        ``K1, D1`` (left), ``K2, D2, R, T`` (right in left, mm).
    """

    def __init__(self, session: Session, stereo_model):
        self.session, self.model = session, stereo_model
        self.cam2tool0 = None
        self.board_base = None  # (m, 3): the board's corners in the base frame, mean over the postures (eq. 21)
        self.d_org_mm = None
        self.reason = f"a calibration needs {MIN_POSTURES} postures"

    def update(self, postures: list) -> None:
        """Solve again with ``postures`` (``calibration.session.Posture``, flange pose and corners)."""
        from ...calibration import fixed_points
        from ...calibration import calibrate, problem_from_session

        if len(postures) < MIN_POSTURES:
            self.cam2tool0, self.reason = None, f"a calibration needs {MIN_POSTURES} postures ({len(postures)} so far)"
            return
        session = Session(self.session.setup, self.session.robot, self.session.target, list(postures))
        try:
            problem = problem_from_session(session)
            result = calibrate(problem, PREDICTION_METHOD)
        except HandEyeError as exc:
            self.cam2tool0, self.reason = None, str(exc).splitlines()[0]
            return
        self.cam2tool0 = result.x
        self.board_base = fixed_points(problem.hand, result.x, problem.points_cam).mean(axis=0)
        self.d_org_mm, self.reason = float(result.metrics.get("d_org_mm", np.nan)), ""

    def predict_px(self, tool02base) -> tuple[np.ndarray, np.ndarray] | None:
        """The corners ``(m, 2)`` in the left and the right raw image where the calibration expects them
        with the flange at ``tool02base`` (4, 4); None without a calibration."""
        import cv2

        if self.cam2tool0 is None or tool02base is None:
            return None
        base2cam = np.linalg.inv(np.asarray(tool02base, float) @ self.cam2tool0)
        points = self.board_base @ base2cam[:3, :3].T + base2cam[:3, 3]
        if np.any(points[:, 2] <= 0):
            return None
        zero = np.zeros(3)
        left, _ = cv2.projectPoints(points, zero, zero, self.model.K1, self.model.D1)
        rvec, _ = cv2.Rodrigues(np.asarray(self.model.R, float))
        right, _ = cv2.projectPoints(points, rvec, np.asarray(self.model.T, float).ravel(), self.model.K2, self.model.D2)
        return left.reshape(-1, 2), right.reshape(-1, 2)


def _quality_row(posture: int, word: str, quality: dict, reason: str = "") -> dict:
    keep = ("corners", "distance_mm", "row_disagreement_max_px", "plane_rms_mm")
    return {"index": int(posture), "word": word, "reason": reason,
            "quality": {k: (round(float(quality[k]), 3) if isinstance(quality[k], float) else quality[k])
                        for k in keep if k in quality}}


class ViewState:
    """The page's state, folded from capture events (see the module docstring).

    Parameters
    ----------
    config : StationConfig
        ``quality`` (thresholds), ``guided`` (targets), ``robot``, ``target``.
    stereo_model : drivers.camera.stereo.StereoModel
    clock : callable
        Monotonic seconds (time left).
    """

    def __init__(self, config, stereo_model, clock=time.monotonic):
        self.config, self.clock = config, clock
        self.thresholds = config_thresholds(config)
        self.view = stereo_views(stereo_model)[0]
        self.predictor = Predictor(Session("eye_in_hand", config.robot, config.target), stereo_model)
        self.mode, self.session_dir = "", ""
        self.postures: dict = {}  # index -> Posture (captured, on disk)
        self.rows: dict = {}  # index -> the posture list's row
        self.cells: set = set()
        self.distances: dict = {}
        self.plan = None
        self.prompt = {"kind": "", "text": "waiting for the capture to start", "posture": None}
        self.last = None
        self.ended = None  # the CaptureEnded event, once the run is over
        self.visit_times: list = []
        self._last_verdict_at = None

    # -------------------------------------------------------------------------------- events in
    def apply(self, event) -> None:
        """Fold one event (CaptureStarted, Prompt, Verdict) into the state."""
        if isinstance(event, CaptureStarted):
            self._start(event)
        elif isinstance(event, Prompt):
            self.prompt = {"kind": event.kind, "text": event.text, "posture": event.posture}
        elif isinstance(event, Verdict):
            self._verdict(event)
        elif isinstance(event, CaptureEnded):
            self.ended = event
            self.prompt = {"kind": "ended", "text": event.text, "posture": None}

    def _start(self, event: CaptureStarted) -> None:
        self.mode, self.session_dir = event.mode, event.session_dir
        for posture in event.postures:
            if posture.tool0_in_base is not None and posture.points_mm is not None:
                self._add(posture.index, posture.tool0_in_base, posture.points_mm)
                self.rows[posture.index] = _quality_row(posture.index, "on disk", posture.extra.get("quality", {}))
        for index, reason in event.skipped.items():
            self.rows.setdefault(int(index), _quality_row(int(index), SKIPPED, {}, reason))
        if event.plan_joints is not None:
            robot = load_robot(self.config.robot)
            flange = np.array([robot.forward_transform(j)[:3, 3] for j in np.asarray(event.plan_joints, float)])
            self.plan = {"flange_mm": np.round(flange, 1).tolist(), "total": len(flange)}
        self.predictor.update(list(self.postures.values()))

    def _add(self, index: int, tool02base, points_mm) -> None:
        points = np.asarray(points_mm, float)
        self.postures[int(index)] = Posture(int(index), tool0_in_base=np.asarray(tool02base, float), points_mm=points)
        self.distances[int(index)] = float(board_distances_mm(points[None])[0])
        self.cells |= image_cells(self.view.project(points), self.view.width, self.view.height)

    def _verdict(self, event: Verdict) -> None:
        now = self.clock()
        if self.mode == "planned" and event.word in (CAPTURED, SKIPPED):
            if self._last_verdict_at is not None:
                self.visit_times.append(now - self._last_verdict_at)
            self._last_verdict_at = now
        self.last = {"posture": event.posture, "word": event.word, "text": event.text}
        if event.word == CAPTURED:
            self._add(event.posture, event.tool02base, event.points_mm)
            self.rows[event.posture] = _quality_row(event.posture, CAPTURED, event.quality)
            self.predictor.update([self.postures[k] for k in sorted(self.postures)])
        elif event.word == SKIPPED:
            self.rows[event.posture] = _quality_row(event.posture, SKIPPED, event.quality, event.text)

    # ------------------------------------------------------------------------------ the page's JSON
    def coverage(self) -> dict:
        """The coverage words of the captured postures, and the axes for the sphere drawing."""
        poses = np.array([self.postures[k].tool0_in_base for k in sorted(self.postures)]).reshape(-1, 4, 4)
        distances = np.array([self.distances[k] for k in sorted(self.distances)])
        coverage = hand_axis_coverage(poses, "tool0")
        g = self.config.guided
        return {"cells": [[(r, c) in self.cells for c in range(3)] for r in range(3)], "cells_seen": len(self.cells),
                "cells_needed": g.min_image_cells, "axes": np.round(coverage.axes, 3).tolist(),
                "spread_deg": round(coverage.spread_deg, 1), "spread_needed_deg": self.thresholds.min_rotation_axis_spread_deg,
                "median_angle_deg": round(coverage.median_angle_deg, 1),
                "weakest": np.round(coverage.weakest_direction, 3).tolist() if len(poses) >= 2 else None,
                "weakest_name": direction_name(coverage.weakest_direction, "tool0") if len(poses) >= 2 else "",
                "distances_mm": np.round(distances, 0).tolist(), "distance_spread_mm": round(distance_spread_mm(distances), 0),
                "distance_spread_needed_mm": g.min_distance_spread_mm}

    def missing(self) -> list:
        poses = np.array([self.postures[k].tool0_in_base for k in sorted(self.postures)]).reshape(-1, 4, 4)
        distances = np.array([self.distances[k] for k in sorted(self.distances)])
        return what_is_missing(poses, distances, self.cells, self.thresholds, self.config.guided)

    def _progress(self) -> dict:
        count = len(self.postures)
        if self.plan is not None:
            total = self.plan["total"]
            visited = len([r for r in self.rows.values() if r["word"] in (CAPTURED, SKIPPED, "on disk")])
            per = float(np.median(self.visit_times)) if self.visit_times else None
            left = None if per is None else round(per * max(total - visited, 0), 1)
            return {"count": count, "total": total, "visited": visited, "time_left_s": left}
        return {"count": count, "total": postures_needed(self.thresholds), "visited": count, "time_left_s": None}

    def _hint(self, missing: list, coverage: dict) -> dict:
        """The page's "next" box: the first thing missing and which way to turn, GOOD ENOUGH, or, once the run
        is over, how it ended (nothing more to do at the robot)."""
        if self.ended is not None:
            word = "FINISHED" if self.ended.ok else "STOPPED"
            return {"text": f"{word}: {self.ended.text}", "word": "", "axis": None, "turn": ""}
        hint = missing[0] if missing else None
        turn = next((m for m in missing if m.word == AXIS_SPREAD_NAME), None)  # the arrow: which way to turn next
        return {"text": hint.advice if hint else "GOOD ENOUGH: add more or stop", "word": hint.word if hint else "",
                "axis": coverage["weakest"] if turn is not None else None, "turn": turn.advice if turn is not None else ""}

    def to_json(self) -> dict:
        """The page's state (see the module docstring)."""
        missing = self.missing()
        coverage = self.coverage()
        current = self.prompt.get("posture") if self.ended is None else None
        plan = None if self.plan is None else {**self.plan, "current": current, "done": sorted(self.postures),
                                               "skipped": sorted(k for k, r in self.rows.items() if r["word"] == SKIPPED)}
        p = self.predictor
        return {"mode": self.mode, "session": self.session_dir, "progress": self._progress(),
                "postures": [self.rows[k] for k in sorted(self.rows)], "coverage": coverage,
                "missing": [m.line() if self.ended is None else m.shortfall() for m in missing],
                "good_enough": not missing, "hint": self._hint(missing, coverage),
                "ended": None if self.ended is None else {"text": self.ended.text, "ok": self.ended.ok},
                "prompt": self.prompt, "last": self.last, "plan": plan,
                "calibration": {"ok": p.cam2tool0 is not None, "reason": p.reason, "method": PREDICTION_METHOD,
                                "d_org_mm": None if p.d_org_mm is None or not np.isfinite(p.d_org_mm) else round(p.d_org_mm, 2)}}
