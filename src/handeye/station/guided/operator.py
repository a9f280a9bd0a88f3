"""The embedded mock station's operator, for rehearsing ``capture --guided`` end to end (``--mock``).

The guided capture watches an arm the operator jogs with the pendant; the embedded mock station has
no pendant, so on its own the guided capture would wait forever. :class:`MockOperator` plays the
operator: it plans postures around the board as an operator who knows the cell would choose them
(``station.capture.planning``, clear of the cell's volumes, ``plan.postures`` of them: ``--postures``),
jogs the simulated arm to each in turn, rests there until the guided capture has taken it (or
:data:`PATIENCE_S` more have passed), says each step on a line of its own, and when the list is done
ends the run (``stop``), as the operator's Ctrl-C would. The guided capture itself is the same code
a real station runs: it sees nothing but the joints and the camera.

A rehearsal config (``camera.mock_arm``: a standalone ``handeye mock controller``) is played from
outside through the mock's pendant port (``--pendant-port``).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from typing import TYPE_CHECKING

import numpy as np

from ...base import HandEyeError
from ...robot import load_robot
from ...geometry import invert_transforms
from ..cell.plan import cell_check
from ..config.station import StationConfig
from ..capture.planning import plan_postures
from ..report.quality import config_thresholds
from ..runtime import StationLink

if TYPE_CHECKING:
    from ...mocks import MockStation

__all__ = ["PATIENCE_S", "MockOperator", "guided_refusal", "mock_operator", "operator_postures"]

#: How long the simulated operator waits at a rest, beyond the move and ``guided.still_s``, for the
#: capture (a grab, its retries, the posture file) before jogging on, s.
PATIENCE_S = 15.0


def guided_refusal(config: StationConfig) -> str | None:
    """Why ``capture --guided`` cannot run on this station, or None. A rehearsal (``camera.mock_arm``) runs:
    the standalone mock's ``--pendant-port`` lets a person or a test play the operator (jogs, Start, keys)."""
    return None


def _embedded(link: StationLink) -> MockStation:
    """The embedded mock station the simulated operator works on (refused on any other station)."""
    if link.mock is None:
        raise HandEyeError("the simulated operator jogs the embedded mock arm: this station is not the embedded mock")
    return link.mock


def operator_postures(config: StationConfig, link: StationLink) -> np.ndarray:
    """Joint angles ``(n, dof)`` (deg) the simulated operator jogs to, in order: ``plan.postures`` postures
    around the mock's board, planned from where the arm stands, clear of the cell."""
    robot = load_robot(config.robot)
    mock = _embedded(link)
    start = np.asarray(mock.arm.current_joints, float)
    mount = config.camera.nominal_mount_transform()
    board2base = np.asarray(mock.truth["board2base"], float)  # the operator sees where the board is
    view = invert_transforms(robot.forward_transform(start) @ mount) @ board2base
    plan = plan_postures(robot, start, view, mount, config.target, config.plan.postures, seed=config.plan.seed,
                         thresholds=config_thresholds(config), cell=cell_check(config))
    return plan.joints_deg


class MockOperator:
    """A simulated operator jogging the embedded mock arm through ``postures`` (see the module docstring).

    Parameters
    ----------
    config : StationConfig
        ``guided.still_s`` (how long a rest must last).
    link : StationLink
        The embedded mock station (``link.mock.arm`` is jogged).
    postures : ndarray, shape (n, dof)
        Where to jog, in order (deg).
    stop : threading.Event
        Set by the operator when done (it ends the guided capture); set from outside, the operator stops.
    progress : callable
        One line per step.
    """

    def __init__(self, config: StationConfig, link: StationLink, postures, stop: threading.Event,
                 progress: Callable[[str], None] = lambda message: None):
        self.config, self.arm, self.postures = config, _embedded(link).arm, np.asarray(postures, float)
        self.stop, self.progress = stop, progress
        self._taken = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mock-operator", daemon=True)

    def captured(self, report=None) -> None:
        """The guided capture took a posture (its ``on_posture``): the operator may jog on."""
        self._taken.set()

    def start(self) -> MockOperator:
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop jogging (the run ended, or Ctrl-C) and wait for the operator's thread."""
        self.stop.set()
        self._thread.join(timeout=10.0)

    def _wait_for_capture(self, timeout_s: float) -> bool:
        """Rest until the capture took the posture (True), the run stops or ``timeout_s`` pass (False)."""
        deadline = time.monotonic() + timeout_s
        while not self.stop.is_set() and time.monotonic() < deadline:
            if self._taken.wait(0.05):
                return True
        return False

    def _run(self) -> None:
        n = len(self.postures)
        try:
            for k, joints in enumerate(self.postures, start=1):
                if self.stop.is_set():
                    return
                self._taken.clear()
                self.progress(f"operator (simulated): jogging to rest point {k} of {n} (the capture numbers what it takes)")
                move_s = self.arm.start_move(joints)
                if not self._wait_for_capture(move_s + self.config.guided.still_s + PATIENCE_S) and not self.stop.is_set():
                    self.progress(f"operator (simulated): nothing captured at rest point {k}; jogging on")
            self.progress(f"operator (simulated): all {n} postures visited; ending the run as Ctrl-C would")
        except (HandEyeError, ValueError) as exc:
            self.progress(f"operator (simulated) stopped: {exc}")
        finally:
            self.stop.set()


@contextmanager
def mock_operator(config: StationConfig, link: StationLink, stop: threading.Event, progress=lambda message: None):
    """Yield a started :class:`MockOperator` on the embedded mock station (None on any other: a person
    jogs), and stop it on exit."""
    if not link.is_mock:
        yield None
        return
    progress(f"the embedded mock station has no pendant: a simulated operator plans {config.plan.postures} postures "
             "around the board and jogs the arm to each (--postures N), so the guided capture runs end to end; "
             "Ctrl-C stops it")
    operator = MockOperator(config, link, operator_postures(config, link), stop, progress).start()
    try:
        yield operator
    finally:
        operator.close()
