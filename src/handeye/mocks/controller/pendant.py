"""The mock controller's FlexPendant, reachable from outside: a loopback line port where a test, or a person
rehearsing, plays the operator (``handeye mock controller --pendant-port P``).

ASCII lines ended by LF, one request, one reply (``OK ...`` or ``ERR <why>``)::

    JOG j1 j2 j3 j4 j5 j6   move the arm as a jog would (deg, axis angles), reply once it stands still:
                            OK j1 .. j6 (where it stands); a jog whose path comes within the cell margin of
                            a keep-out volume stops there: ERR jog stopped: <what, which volume> (the arm
                            stands where it stopped; the pendant shows the message)
    START                   continue a program stopped by Stop \\NoRegain: OK | ERR <why>
    KEY n                   answer the pendant's prompt (TPReadFK: function key 1-5; UIMessageBox: button n)
    STATE                   OK <execution> <keys> | <last pendant line>; execution: running, prompt (a
                            question waits for KEY), stopped (waiting for START), ended, error, none (no
                            program); keys: the answers offered (1=Capture,5=Done) or -

The mock does not model the operating mode or the enabling device: it refuses a jog only while the
program moves the arm. Jogs are checked against the cell (``--config`` with a ``cell``) exactly as the
program's moves are.
"""

from __future__ import annotations

import logging
import socketserver
import threading
from collections.abc import Sequence
from typing import TYPE_CHECKING, cast

import numpy as np

from ..side_port import TOO_LONG, SidePort, _Server, read_line

if TYPE_CHECKING:
    from .server import RapidControllerServer

__all__ = ["PendantService", "PENDANT_COMMANDS"]

log = logging.getLogger(__name__)

#: The pendant port's requests.
PENDANT_COMMANDS = ("JOG", "START", "KEY", "STATE")
#: Longest request line taken (bytes before its newline); a longer one is refused whole.
MAX_LINE = 200


class _Handler(socketserver.StreamRequestHandler):
    server: _Server  # the side port's

    def handle(self) -> None:
        service = cast(PendantService, self.server.service)  # the pendant port's server serves its PendantService
        while True:
            line = read_line(self.rfile, MAX_LINE)
            if not line:
                return
            if line is TOO_LONG:
                reply = f"ERR request line longer than {MAX_LINE} bytes: refused whole, nothing done"
            else:
                reply = self._answer(service, line)
            self.wfile.write(reply.encode("ascii", "replace") + b"\n")
            self.wfile.flush()

    @staticmethod
    def _answer(service: PendantService, line: bytes) -> str:
        try:
            return service.answer(line.decode("ascii", "replace").strip())
        except Exception as exc:  # one bad request never ends the port
            log.exception("pendant port")
            return f"ERR {type(exc).__name__}: {exc}"


class PendantService(SidePort):
    """The pendant port of a running mock controller (see the module docstring).

    Parameters
    ----------
    controller : RapidControllerServer
        Its ``flexpendant`` (prompts, Start) and ``robot`` (jogs).
    host, port : str, int
        Where the port listens (0: a free port).
    """

    def __init__(self, controller: RapidControllerServer, host: str = "127.0.0.1", port: int = 0):
        self.controller = controller
        super().__init__(_Handler, host, port, "mock-pendant")
        self._jog_lock = threading.Lock()

    def banner(self) -> str:
        return (f"  pendant: JOG j1..j6, START, KEY n, STATE on {self.host}:{self.port} "
                "(one line each; see handeye mock controller --help)")

    # ------------------------------------------------------------------ requests
    def answer(self, line: str) -> str:
        words = line.split()
        if not words:
            return "ERR empty request: JOG j1..j6, START, KEY n or STATE"
        command, args = words[0].upper(), words[1:]
        if command not in PENDANT_COMMANDS:
            return f"ERR unknown request {command[:16]!r}: JOG j1..j6, START, KEY n or STATE"
        if command == "STATE":
            return self.state()
        if command == "START":
            why = self.controller.flexpendant.start()
            return f"ERR {why}" if why else "OK"
        if command == "KEY":
            if len(args) != 1 or not args[0].isdigit():
                return "ERR KEY takes one key number (TPReadFK 1-5, UIMessageBox button 1..n)"
            why = self.controller.flexpendant.answer(int(args[0]))
            return f"ERR {why}" if why else "OK"
        return self.jog(args)

    def state(self) -> str:
        runner, pendant = self.controller.program, self.controller.flexpendant
        task = None if runner is None else runner.task
        if task is None:
            execution = "none"
        elif not task.running:
            execution = "error" if task.error else "ended"
        elif pendant.stopped:
            execution = "stopped"
        elif pendant.prompt is not None:
            execution = "prompt"
        else:
            execution = "running"
        prompt = pendant.prompt
        keys = ",".join(f"{k}={label}" for k, label in sorted(prompt.keys.items())) if prompt else "-"
        return f"OK {execution} {keys} | {pendant.last_line}"

    def jog(self, args: Sequence[str]) -> str:
        robot = self.controller.robot
        try:
            target = np.array([float(a) for a in args], float)
        except ValueError:
            return f"ERR JOG takes {robot.model.dof} axis angles in degrees"
        if len(target) != robot.model.dof or not np.all(np.isfinite(target)):
            return f"ERR JOG takes {robot.model.dof} axis angles in degrees"
        with self._jog_lock:
            if robot.is_moving:
                return "ERR the arm is moving (a program move): wait, or stop the program"
            try:
                _, violation = robot.jog(target)
            except ValueError as exc:
                return f"ERR {exc}"
            robot.wait_until_stopped()
        if violation is not None:
            message = f"jog stopped: {violation.describe()} (keep-out volume)"
            self.controller.flexpendant.write(f"motion supervision: {message}")
            return f"ERR {message}"
        return "OK " + " ".join(f"{v:.4f}" for v in robot.current_joints)
