"""Guided capture with the guided RAPID program (``src/handeye/rapid/guided.py``): every link but RWS, no option.

An IRC5 does not jog while a program runs in the motion task, so over these links the PC cannot watch
the joints while the operator jogs (:mod:`handeye.station.guided.capture` does, over Robot Web Services, or on
the embedded mock). Here the program in the motion task drives the dialogue: the PC sends its verdict on
the posture offered last and the hint for the next (:meth:`Controller.guide`); the pendant shows them;
the operator presses *Capture*, jogs, presses Start; the program offers where the arm stands (state
``AT k``); the PC reads the joints and the flange pose, judges the posture (a keep-out volume within the
cell margin, too close to one captured, the board not seen) and captures it exactly as the planned
capture does, acknowledges, and sends the next verdict. *Done* on the pendant ends the run.

The session is the guided session of :mod:`handeye.station.guided.capture` (``capture.mode: guided``); the same
resume rules hold: a PC that died while the program waited at ``AT k`` finds it there and judges that
posture (one already on disk is too close to itself: never stored twice).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

from ...rapid import VERDICT_CODES, hint_code_for, hint_text, verdict_text
from ..capture.loop import CaptureError, PostureReport, grab_observer, measure_with_retries, read_flange
from ..capture.events import NOT_CAPTURED, TOO_CLOSE, Prompt
from ..config.station import StationConfig
from .capture import GuidedSummary, _GuidedRun
from ..runtime import StationLink

__all__ = ["pendant_guided_capture", "uses_guided_program", "hint_of", "install_guided_program"]


def uses_guided_program(config: StationConfig, link: StationLink) -> bool:
    """Whether ``capture --guided`` runs the guided RAPID program: over a line (socket or serial) and over Modbus (the
    links whose program the operator cannot jog beside); not over Robot Web Services (the PC reads the
    joints with no program) nor on the embedded mock (its simulated operator jogs beside the program)."""
    from ...rapid import GUIDED_LINKS
    from ...rapid import LINK_MODULES

    return not link.is_mock and LINK_MODULES.get(config.link_protocol) in GUIDED_LINKS


def hint_of(missing) -> int:
    """The hint code (``rapid.guided.HINTS``) of what the set lacks first (0: nothing)."""
    return 0 if not missing else hint_code_for(missing[0].word, missing[0].advice)


def install_guided_program(config: StationConfig, session_dir: Path, link: StationLink, progress) -> Path:
    """Write the guided program into ``SESSION/rapid`` (once), load it where the station can, and wait until
    the controller runs it (a program with no posture)."""
    from ...drivers import RAPID_LINKS
    from ...rapid import render_guided_program, write_modules
    from ...rapid import default_station, station_from_dict
    from ..capture.loop import _wait_for_program

    rapid_dir = session_dir / "rapid"
    station = station_from_dict(config.rapid_dict(default_station().postures), config.source, links=RAPID_LINKS)
    modules = render_guided_program(station, prompt=config.guided.prompt)
    missing = [m for m in modules if not (rapid_dir / m.filename).is_file()]
    if missing:
        write_modules(missing, rapid_dir)
        progress(f"guided RAPID program written to {rapid_dir} (HeGuide: prompts on the FlexPendant, stops for you "
                 "to jog, offers the posture on Start)")
    if link.load_program is not None:
        link.load_program(None, rapid_dir)
        link.controller.close()
        link.controller.connect()
    _wait_for_program(link.controller, 0, rapid_dir, progress)
    return rapid_dir


class _PendantRun(_GuidedRun):
    """The guided loop's state with the program's dialogue (see the module docstring)."""

    def how_to_capture(self) -> str:
        """What the operator does for a posture to be captured: the guided program's keys and Start."""
        return ("on the pendant press Capture, jog the robot to a new posture with the board in view and press Start: "
                "the posture where it stands is captured, or refused with the reason; Done ends the capture")

    def how_to_stop(self) -> str:
        return "add more (Capture on the pendant) or press Done"

    def offered(self, k: int) -> str:
        """Judge the k-th posture the operator offered; the verdict's name (``rapid.guided.VERDICTS``)."""
        g, index = self.config.guided, self.state.next_index
        joints, tool02base = read_flange(self.config, self.link, self.robot, f"offered posture {k}")
        near = self.guard.posture_violation(joints)
        if near is not None:
            self.refuse(index, NOT_CAPTURED, f"not captured: {near.describe()} (keep-out volume; cell.margin_mm "
                                             f"{self.guard.margin_mm:g}): jog away from it")
            return "NEAR_VOLUME"
        rot, dist, _ = self.state.nearest(tool02base)
        if rot < g.min_step_deg and dist < g.min_step_mm:
            self.refuse(index, TOO_CLOSE, f"not captured: {rot:.1f} deg and {dist:.0f} mm from a captured posture: move "
                                          f"on (at least {g.min_step_deg:g} deg or {g.min_step_mm:g} mm)")
            return "TOO_CLOSE"
        result, frame, problem, attempts = measure_with_retries(self.config, self.link,
                                                                grab_observer(self.observer, index, tool02base))
        if problem is not None:
            self.refuse(index, NOT_CAPTURED, f"not captured after {attempts} attempt(s): {problem}; turn back towards "
                                             "the board", result.quality if result is not None else {})
            return "NOT_SEEN"
        self.store(index, joints, tool02base, result, frame, attempts)
        return "CAPTURED" if self.missing() else "GOOD_ENOUGH"

    def prompt(self, verdict: str) -> None:
        """Send ``verdict`` and the hint of what is missing; the pendant prompts."""
        missing = self.missing()
        hint = hint_of(missing)
        self.link.controller.guide(VERDICT_CODES[verdict], hint)
        line = f"pendant: {verdict_text(VERDICT_CODES[verdict])}; next: {hint_text(hint)}"
        self.progress(line)
        self.observer(Prompt("jog", line))


def _wait_for_operator(run: _PendantRun, stop: threading.Event, wait_s: float):
    """The program's state once the operator acted (AT k or DONE), None when stopped; CaptureError after
    ``guided.operator_timeout_s``."""
    limit, waited = run.config.guided.operator_timeout_s, 0.0
    while not stop.is_set():
        status = run.link.controller.wait_operator(wait_s)
        if status is not None:
            return status
        waited += wait_s
        if waited >= limit:
            raise CaptureError(f"nobody answered the pendant for {limit:g} s (guided.operator_timeout_s); the postures "
                               f"on disk stay in {run.session_dir}: run the same command to go on")
    return None


def pendant_guided_capture(
    config: StationConfig,
    session_dir,
    link: StationLink,
    progress: Callable[[str], None] = lambda message: None,
    on_posture: Callable[[PostureReport], None] = lambda report: None,
    stop: threading.Event | None = None,
    observer: Callable | None = None,
    wait_s: float = 0.5,
) -> GuidedSummary:
    """Run (or resume) a guided capture with the guided RAPID program until the operator presses Done,
    ``stop`` is set, Ctrl-C, or ``guided.max_postures`` postures are on disk.

    Parameters
    ----------
    config, session_dir, link, progress, on_posture, stop
        As :func:`handeye.station.guided.capture.guided_capture`.
    observer : callable, optional
        Receives the ``station.capture.events`` (the live view): CaptureStarted, a Prompt (``jog``) with
        the pendant's verdict and hint, Measured (each grab) and Verdict, as in ``guided_capture``.
    wait_s : float
        How long one wait for the operator lasts before ``stop`` is looked at again, s.

    Raises
    ------
    CaptureError, ControllerError, CameraError
    """
    import time

    started, session_dir, stop = time.monotonic(), Path(session_dir), stop or threading.Event()
    install_guided_program(config, session_dir, link, progress)
    run = _PendantRun(config, session_dir, link, progress, on_posture, observer)
    already = len(run.state.tool02base)
    run.say_missing()
    status, verdict = link.controller.status(), "START"
    if status.awaiting_ack:  # a PC that stopped while the program offered a posture: judge it now
        verdict = _judge(run, status.posture)
    asking = status.state in ("PROMPT", "JOG")  # the pendant asks already (Modbus: a PC stopped meanwhile)
    while not stop.is_set() and len(run.state.tool02base) < config.guided.max_postures:
        if not asking:
            run.prompt(verdict)
        asking = False
        status = _wait_for_operator(run, stop, wait_s)
        if status is None:
            break
        if status.state == "DONE":
            progress("the operator pressed Done")
            break
        verdict = _judge(run, status.posture)
    if len(run.state.tool02base) >= config.guided.max_postures:
        progress(f"{config.guided.max_postures} postures (guided.max_postures): done")
    return GuidedSummary(session_dir, run.captured, already, run.missing(), time.monotonic() - started)


def _judge(run: _PendantRun, k: int) -> str:
    verdict = run.offered(k)
    run.link.controller.acknowledge(k)
    return verdict
