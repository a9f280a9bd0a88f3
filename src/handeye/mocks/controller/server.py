"""What every mock controller server shares: the RAPID program run by the interpreter on the
simulated arm, behind the endpoint of its link (a TCP socket, a serial line, a gateway, a web server).

A server is built from a :class:`~handeye.mocks.controller.sources.ControllerProgram` and a
:class:`~handeye.mocks.robot.SimulatedRobot`; :meth:`start` opens the endpoint, loads the program
(refused with the module and line when the interpreter cannot run it) and runs it until it waits for
the PC. :meth:`load_program` replaces the program (what loading a capture's modules does).
"""

from __future__ import annotations

import logging
import os
from typing import TYPE_CHECKING

from ...drivers import check_write_key
from ...drivers import ToolData
from ...rapid import Bindings, RapidError
from ...rapid import FlexPendant
from .arm import ArmBinding
from .faults import Faults
from .runner import RapidRunner
from .signals import CellSignals
from .sources import ControllerProgram, keep_system_modules, program_from_folder

if TYPE_CHECKING:
    from typing_extensions import Self

    from ..robot import SimulatedRobot

__all__ = ["RapidControllerServer", "DEFAULT_IDLE_TIMEOUT_S"]

log = logging.getLogger(__name__)

#: The RAPID modules' default idle timeout (``controller.idle_timeout_s``).
DEFAULT_IDLE_TIMEOUT_S = 5.0


class RapidControllerServer:
    """Base of the mock servers (see the module docstring).

    Parameters
    ----------
    program : ControllerProgram
        The modules loaded into the robot task.
    robot : SimulatedRobot
    host, port : str, int
        Where the link's endpoint listens (port 0: a free one; see :attr:`port` after :meth:`start`).
    faults : Faults, optional
    idle_timeout_s : float
        The PC's idle timeout in :meth:`client_options` (the program's own is in its link module).
    write_key : str, optional
        The key the PC sends for tool writes (the program's HeKey.sys holds it; None: none).
    """

    kind = "controller"

    def __init__(self, program: ControllerProgram, robot: SimulatedRobot, host: str = "127.0.0.1", port: int = 0, faults: Faults | None = None, *,
                 idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None):
        if not (isinstance(idle_timeout_s, (int, float)) and 0 < idle_timeout_s < float("inf")):
            raise ValueError(f"idle_timeout_s must be a positive number of seconds; got {idle_timeout_s!r}")
        self.source, self.robot = program, robot
        self.host, self._requested_port = host, port
        self.faults = faults or Faults()
        self.idle_timeout_s = float(idle_timeout_s)
        self._write_key = check_write_key(write_key)
        self.runner: RapidRunner | None = None
        self.protocol = self.kind
        #: The cell's I/O signals beside the link's (a test or the pendant sets an input: ``cell_signals.set``).
        self.cell_signals = CellSignals()
        #: With ``keep_tool`` the PERS tool data is kept across program loads (a controller's persistent
        #: value): ``kept_tool`` is put into each program loaded (None: the module's own value, until a
        #: program is replaced). Without it each program starts with the value its module declares.
        self.keep_tool = False
        self.kept_tool: ToolData | None = None
        #: The FlexPendant the program prompts on (TPReadFK, UIMessageBox) and stops for (Stop \NoRegain);
        #: the operator's side is played by a test or the pendant port (``src/handeye/mocks/controller/pendant.py``).
        self.flexpendant = FlexPendant()

    # ------------------------------------------------------------------ what each link adds
    def _open_endpoint(self) -> Bindings:
        """Open the link's endpoint; return the program's bindings (the arm added by the caller)."""
        raise NotImplementedError

    def _close_endpoint(self) -> None:
        raise NotImplementedError

    def _arming(self) -> None:
        """Just before a program starts (the socket server forgets that the last one listened)."""

    def _wait_ready(self) -> None:
        """Return once the program serves the link (the socket program listens ...)."""

    def _live_runner(self) -> RapidRunner:
        """The runner of the started server (a stopped one has none)."""
        if self.runner is None:
            raise RapidError(f"mock {self.kind} controller: not started; call start() first")
        return self.runner

    def _run(self, program: ControllerProgram) -> None:
        self._arming()
        runner = self._live_runner()
        runner.load(program)
        if self.keep_tool and self.kept_tool is not None and runner.has_tool:
            runner.set_tool(self.kept_tool)  # a PERS keeps its value when modules are loaded again
        runner.start()
        self._wait_ready()

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> Self:
        if self.runner is not None:
            return self
        bindings = self._open_endpoint()
        bindings.io = self.cell_signals.over(bindings.io)
        bindings.motion = ArmBinding(self.robot)
        bindings.pendant = self._pendant
        bindings.flexpendant = self.flexpendant
        self.runner = RapidRunner(self.robot, bindings, f"mock {self.kind} controller")
        try:
            self._run(self.source)
        except BaseException:
            self.runner.stop()
            self.runner = None
            self._close_endpoint()
            raise
        self.faults.watch_stall(self._stall)
        return self

    def stop(self) -> None:
        if self.runner is None:
            return
        self.runner.stop()
        self._close_endpoint()
        self.runner = None

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def load_program(self, program: ControllerProgram | str | os.PathLike[str]) -> None:
        """Stop the running program, load ``program`` (a ControllerProgram, or a folder of modules) and
        start it; the system modules loaded before (HeKey.sys) stay, as on a controller. Loading the
        modules that run already changes nothing (the program is not restarted)."""
        if not isinstance(program, ControllerProgram):
            program = program_from_folder(program, self.protocol)
        program = keep_system_modules(program, self.source)
        if sorted((m.source, m.text) for m in program.modules) == sorted((m.source, m.text) for m in self.source.modules):
            return  # the same modules are loaded already: the program keeps running (a resumed capture)
        runner = self._live_runner()
        runner.stop()
        if self.keep_tool and runner.has_tool:
            self.kept_tool = runner.tool()
        self.source = program
        self._run(program)

    def _stall(self, stalled: bool) -> None:
        if self.runner is not None:
            self.runner.hold(stalled)

    def _pendant(self, text: str) -> None:
        log.info("mock %s controller, FlexPendant: %s", self.kind, text)

    # ------------------------------------------------------------------ state
    @property
    def program(self) -> RapidRunner | None:
        """The running :class:`~handeye.mocks.controller.runner.RapidRunner`."""
        return self.runner

    @property
    def running(self) -> bool:
        return self.runner is not None and self.runner.running

    @property
    def program_error(self) -> str | None:
        """Why the RAPID program stopped on an error, if it did."""
        return None if self.runner is None else self.runner.error

    @property
    def port(self) -> int:
        """Where the endpoint listens (the port asked for until :meth:`start` binds it)."""
        raise NotImplementedError

    @property
    def link_open(self) -> bool | None:
        """Whether the RAPID program opened its end of the link (the socket program listens, the serial
        program opened its channel); None where the mock cannot tell (Modbus signals, RWS)."""
        return None

    def fix_hint(self, error: bool = False) -> str:
        """What to do when the program does not serve the link (``error``: it stopped on an error), for the
        messages."""
        origin = str(self.source.origin)
        where = "the generated modules" if origin.startswith("generated") else f"the modules in {origin}"
        if error:
            return f"fix that line of {where} (or leave out --program) and start the mock again"
        return (f"its main must open the link and serve the PC, as the modules of `handeye rapid generate` do: fix "
                f"{where} (or leave out --program) and start the mock again")

    @property
    def has_write_key(self) -> bool:
        """True when the mock was given a write key (tool writes possible after KEY / with tool_key)."""
        return self._write_key is not None

    # ------------------------------------------------------------------ its banner (handeye mock controller)
    def listening(self) -> str:
        """Where a client reaches it, after the banner's head (`` listening on HOST:PORT``)."""
        return f" listening on {self.host}:{self.port}"

    def link_note(self, idle_timeout_s: float) -> str:
        """The banner's line on the link: its idle timeout and whether tool writes are possible."""
        writes = ("tool writes need the write key (KEY / tool_key)" if self.has_write_key else
                  "tool writes refused: no write key (start it with --write-key KEY or --config STATION.yaml)")
        return f"idle timeout {idle_timeout_s:g} s; {writes}"

    def client_options(self) -> dict:
        """Keyword arguments of ``open_controller`` that reach it (its idle timeout and write key included)."""
        raise NotImplementedError

    def client_flags(self) -> str:
        """The ``handeye robot`` flags that reach it."""
        return f"--host {self.host} --port {self.port}"

    def _client_key(self, options: dict) -> dict:
        if self._write_key is not None:
            options["write_key"] = self._write_key
        return options
