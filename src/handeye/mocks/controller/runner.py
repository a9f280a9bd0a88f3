"""The controller's robot task: the RAPID program loaded, linked against the mock's bindings, and run.

:class:`RapidRunner` is what a mock controller has instead of a program of its own: it loads a
:class:`~handeye.mocks.controller.sources.ControllerProgram` into the interpreter (refused with the
module and line when the interpreter cannot run it), takes the approved postures from the program's
``CONST jointtarget`` data onto the simulated arm, makes the arm's tool data the program's ``PERS
tooldata``, and runs ``main`` in a thread. Loading another program stops the running one first (its
sockets and channels close), as loading modules into a stopped task does.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ...drivers import ToolData
from ...rapid import RapidError
from ...rapid import Bindings, Program, Task, load_program

if TYPE_CHECKING:
    from ..robot import SimulatedRobot
    from .sources import ControllerProgram

__all__ = ["RapidRunner", "approved_postures", "tooldata_of"]

log = logging.getLogger(__name__)

#: How long a program may take from start until it first waits for the PC.
START_TIMEOUT_S = 15.0


def approved_postures(program: Program) -> np.ndarray:
    """The program's CONST jointtargets in declaration order: the postures it can move to, (n, 6)."""
    rows = []
    for symbol in program.data:
        if symbol.storage == "CONST" and symbol.type.name == "jointtarget" and not symbol.dims:
            robax = symbol.box[0].fields["robax"].fields
            rows.append([robax[f"rax_{i}"] for i in range(1, 7)])
    return np.array(rows, float).reshape(-1, 6)


class RapidRecord(Protocol):
    """A RAPID record value of the interpreter: its components by name (records nest)."""

    fields: dict[str, Any]


def tooldata_of(record: RapidRecord) -> ToolData:
    """A RAPID tooldata value as the drivers' :class:`ToolData`."""
    frame, load = record.fields["tframe"].fields, record.fields["tload"].fields
    trans, rot, cog = frame["trans"].fields, frame["rot"].fields, load["cog"].fields
    return ToolData(tuple(trans[c] for c in "xyz"), tuple(rot[c] for c in ("q1", "q2", "q3", "q4")),
                    load["mass"], tuple(cog[c] for c in "xyz"))


class RapidRunner:
    """Loads and runs the RAPID program of a mock controller.

    Parameters
    ----------
    robot : SimulatedRobot
    bindings : Bindings
        The mock's world (sockets, serial line, gateway signals, the arm, the pendant).
    name : str
        What log lines call the controller (``mock socket controller``).
    """

    def __init__(self, robot: SimulatedRobot, bindings: Bindings, name: str = "mock controller"):
        self.robot, self.bindings, self.name = robot, bindings, name
        self.program: Program | None = None
        self.task: Task | None = None
        self.loaded: ControllerProgram | None = None
        self._tool_symbol = None

    # ------------------------------------------------------------------ loading
    def load(self, source: ControllerProgram) -> Program:
        """Link ``source`` (a ControllerProgram); the arm takes its approved postures.

        Raises
        ------
        RapidLoadError
            The interpreter cannot run a module (its name and line in the message).
        """
        program = load_program(source.modules, signals=self.bindings.signals())
        if program.main is None:
            raise RapidError(f"{source.origin}: no module declares PROC main (load HeMain)")
        postures = approved_postures(program)
        if len(postures):
            self.robot.load_program(postures)
        self._tool_symbol = self._find_tool(program, source.tool_name)
        self.program, self.loaded = program, source
        self.robot.tool_source = self.tool if self._tool_symbol is not None else None
        return program

    @staticmethod
    def _find_tool(program: Program, name: str | None):
        tools = [s for s in program.data if s.storage == "PERS" and s.type.name == "tooldata" and not s.dims]
        if name is not None:
            tools = [s for s in tools if s.name.lower() == name.lower()] or tools
        return tools[0] if tools else None

    def tool(self) -> ToolData:
        """The camera's tool data: the program's PERS tooldata now."""
        return tooldata_of(self._tool_datum().box[0])

    def _tool_datum(self):
        if self._tool_symbol is None:
            raise RapidError(f"{self.name}: the loaded program declares no PERS tooldata (load HeTool)")
        return self._tool_symbol

    @property
    def has_tool(self) -> bool:
        return self._tool_symbol is not None

    def set_tool(self, tool: ToolData) -> None:
        """Put ``tool`` into the program's PERS tooldata (a value the controller kept from before)."""
        record = self._tool_datum().box[0]
        frame, load = record.fields["tframe"].fields, record.fields["tload"].fields
        trans, rot, cog = frame["trans"].fields, frame["rot"].fields, load["cog"].fields
        for name, value in zip("xyz", tool.position_mm):
            trans[name] = float(value)
        for name, value in zip(("q1", "q2", "q3", "q4"), tool.quaternion_wxyz):
            rot[name] = float(value)
        load["mass"] = float(tool.mass_kg)
        for name, value in zip("xyz", tool.cog_mm):
            cog[name] = float(value)

    # ------------------------------------------------------------------ running
    def start(self, timeout: float = START_TIMEOUT_S) -> None:
        """Run ``main`` until it first waits for the PC (or stops: then raise with the reason)."""
        if self.program is None or self.loaded is None:
            raise RapidError(f"{self.name}: no RAPID program is loaded; load one before starting it")
        self.task = Task(self.program, self.bindings)
        self.task.start()
        end = time.monotonic() + timeout
        while not self.task.wait_idle(0.05):
            if self.task.main_returns or not self.task.running or time.monotonic() > end:
                break  # main ran to its end without waiting, or the program ended: the server tells how
        if not self.task.wait_idle(0) and self.task.running and not self.task.main_returns:
            log.warning("%s: the RAPID program did not wait for the PC within %g s", self.name, timeout)
        if self.task.state == "error":
            raise RapidError(f"{self.name}: the RAPID program ({self.loaded.origin}) stopped at start: "
                             f"{self.task.error}")

    def stop(self) -> None:
        if self.task is not None:
            self.task.stop()

    def reload(self, source: ControllerProgram) -> None:
        """Stop the running program, load ``source`` and start it (the arm stays where it is)."""
        self.stop()
        self.load(source)
        self.start()

    def hold(self, held: bool) -> None:
        if self.task is not None:
            self.task.hold(held)

    @property
    def running(self) -> bool:
        return self.task is not None and self.task.running

    @property
    def error(self) -> str | None:
        """Why the program stopped on an error (None while it runs or after a normal stop)."""
        return None if self.task is None else self.task.error

    @property
    def end_reason(self) -> str | None:
        """How the program ended by itself, in words (``stopped on an error: HeMain.mod:5: ERR_DIVZERO
        ...``, ``ended on EXIT at HeMain.mod:4``); None while it runs or when it was asked to stop."""
        task = self.task
        if task is None or task.running:
            return None
        if task.error:
            return f"stopped on an error: {task.error}"
        if task.ended:
            return f"ended on {task.ended}"
        return None

    @property
    def main_returns(self) -> int:
        """How many times ``main`` ran to its end (continuous mode starts it again)."""
        return 0 if self.task is None else self.task.main_returns

    @property
    def pendant(self) -> list[str]:
        return [] if self.task is None else list(self.task.pendant)
