"""A scripted operator at the standalone mock controller's pendant port (``handeye mock controller
--pendant-port``): rehearses a guided capture end to end with nobody at the station.

:class:`PendantClient` speaks the port's line protocol (``src/handeye/mocks/controller/pendant.py``: ``JOG``, ``START``,
``KEY``, ``STATE``). :class:`PendantOperator` plays the operator of the guided program in a thread: at each
prompt it presses *Capture*, jogs to the next of its postures, presses Start; when its list is done it
presses *Done*. Its postures are usually a planned capture's (``capture --plan-only`` measures the board
from where the arm stands and plans around it: ``plan_joints_deg`` of that session's record), as an
operator who knows the cell would choose them.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from handeye.station.guided.pendant_client import PendantClient, PendantState

__all__ = ["PendantClient", "PendantOperator", "PendantState"]


class PendantOperator:
    """Plays the guided program's operator through a pendant port (see the module docstring).

    Parameters
    ----------
    address : str
        ``HOST:PORT`` of the pendant port.
    postures : ndarray, shape (n, dof)
        Where to jog, in order (deg).
    progress : callable
        One line per step.
    done : bool
        Press Done after the last posture (False: leave the last prompt unanswered).
    pause : callable, optional
        ``pause(k)`` before offering posture ``k`` (1-based): a test interrupts the PC there.
    timeout_s : float
        Longest wait for one prompt.

    Attributes
    ----------
    replies : list of str
        The pendant's reply to every jog.
    error : Exception or None
        Why the operator stopped early.
    """

    def __init__(self, address: str, postures, progress: Callable[[str], None] = lambda message: None,
                 done: bool = True, pause: Callable[[int], None] | None = None, timeout_s: float = 120.0):
        self.address, self.postures = address, np.asarray(postures, float)
        self.progress, self.done, self.pause, self.timeout_s = progress, done, pause, timeout_s
        self.replies: list[str] = []
        self.error: Exception | None = None
        self._thread = threading.Thread(target=self._run, name="pendant-operator", daemon=True)

    def start(self) -> PendantOperator:
        self._thread.start()
        return self

    def join(self, timeout: float | None = None) -> bool:
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _run(self) -> None:
        client = PendantClient(self.address, self.timeout_s)
        try:
            for k, joints in enumerate(self.postures, start=1):
                if self.pause is not None:
                    self.pause(k)
                state = client.wait("prompt", self.timeout_s)
                self.progress(f"operator: the pendant says {state.text!r}; Capture, jog to posture {k}")
                client.ask(f"KEY {state.key('Capture')}")
                client.wait("stopped", self.timeout_s)
                reply = client.jog(joints)
                self.replies.append(reply)
                if not reply.startswith("OK"):
                    self.progress(f"operator: the pendant says {reply}")
                client.ask("START")
            if self.done:
                state = client.wait("prompt", self.timeout_s)
                self.progress("operator: Done")
                client.ask(f"KEY {state.key('Done')}")
        except Exception as exc:  # the test or the benchmark reads it
            self.error = exc
        finally:
            client.close()
