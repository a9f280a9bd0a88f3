"""Run a mock controller standalone (what ``handeye mock controller`` calls).

The mock runs RAPID: the modules generated for the chosen protocol (and the station's postures,
timeouts and write key), or the modules of ``--program DIR``. A module the interpreter cannot run is
refused at start, naming the module and line; a program that stops on an error later ends the mock
with that error (exit status 1). A program that ends by itself (EXIT, Stop) or has not opened its link
:data:`LINK_NOTICE_S` seconds after the start is reported in one line on stderr, with what to do; the
mock keeps serving (a PC may load another program).
"""

from __future__ import annotations

import ipaddress
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ...drivers import DEFAULT_PROTOCOL, RAPID_LINKS
from ...rapid import IDLE_TIMEOUT_RANGE, RapidStation, default_station, load_station
from ..backends import mock_protocol_choices, mock_server
from . import start_mock_controller
from .server import RapidControllerServer

if TYPE_CHECKING:
    from ...robot import CellModel
    from ..arm_truth import ArmDeviations
    from ..cell import CellService
    from ..drift import StationFaults
    from ..station import MockStationSpec
    from .pendant import PendantService

__all__ = ["MockControllerOptions", "run_mock_controller", "is_loopback", "LINK_NOTICE_S"]

#: Seconds after the start when a program that has not opened its link (serial channel) is reported.
LINK_NOTICE_S = 3.0


@dataclass(frozen=True)
class MockControllerOptions:
    """Settings of a standalone mock controller.

    Attributes
    ----------
    protocol : str
        Any of :func:`~handeye.mocks.backends.mock_protocols`.
    port : int or None
        None: the mock's default port (``mock_server(protocol).default_port``); 0: any free port.
    host : str
    config : str or None
        Station YAML (the ``rapid generate`` keys) for the approved postures, the acknowledgement
        and idle timeouts and the write key (None: built-in; ``station`` wins when given).
    station : RapidStation or None
        The station already read (``handeye mock controller --config`` reads the full station
        config and passes it here).
    time_scale : float
        Wall-clock seconds per simulated second of motion.
    allowed_client : str or None
        The PC address rendered into the program (``HE_PC_ADDRESS``; None: the station's).
    server_options : dict
        The protocol's mock server's own options by key (``MockServer.options``: ``register_map``,
        ``generation`` ...); the options of another protocol's mock are left out.
    duration_s : float or None
        Stop after this long (None: until Ctrl-C).
    idle_timeout_s : float or None
        The link's idle timeout (None: the station's, default 5 s).
    write_key : str or None
        The key tool writes need (None: the station's; without any, tool writes are refused).
        Never printed.
    program : str or None
        A folder of RAPID modules to run instead of the generated ones (its HeKey.sys, if any, holds
        the key; give the same key with ``write_key`` for the PC's side).
    pendant_port : int or None
        Also serve the FlexPendant on this loopback port (``src/handeye/mocks/controller/pendant.py``: JOG, START, KEY,
        STATE), so a test or a person can play the operator of a guided capture (0: a free port).
    camera_port : int or None
        Also serve the simulated XB3 on the flange (rendered frames) on this port for a rehearsal
        station (0: a free port); None: no camera.
    cell : CellModel or None
        The cell around the arm (``cell`` of the station config): a move whose path (a ``MoveL``'s
        along its TCP line) enters one of its volumes stops the program at that line, naming the volume.
    signals : tuple of (name, type, value)
        Cell I/O signals besides the mock's own (``--signal NAME:TYPE=VALUE``).
    faults : StationFaults or None
        What changed at the station since its calibration (``mock.faults`` of the config): the camera
        renders the changed world (``mocks.drift``).
    arm : ArmDeviations or None
        The arm's true kinematic deviations (``mock.arm`` of the config, ``mocks.arm_truth``); None: random.
    """

    protocol: str = DEFAULT_PROTOCOL
    port: int | None = None
    host: str = "127.0.0.1"
    config: str | None = None
    time_scale: float = 1.0
    allowed_client: str | None = None
    server_options: dict = field(default_factory=dict)
    duration_s: float | None = None
    idle_timeout_s: float | None = None
    write_key: str | None = field(default=None, repr=False)
    station: RapidStation | None = None
    program: str | None = None
    camera_port: int | None = None
    pendant_port: int | None = None
    cell: CellModel | None = None
    signals: tuple = ()
    faults: StationFaults | None = None
    arm: ArmDeviations | None = None


def is_loopback(host: str) -> bool:
    """True for 127.x.x.x, ::1 and ``localhost``: only this machine can reach a server bound there."""
    if str(host).lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(str(host)).is_loopback
    except ValueError:
        return False


def _banner(server: RapidControllerServer, options: MockControllerOptions, postures: int, idle_timeout_s: float) -> str:
    runs = f"RAPID from {options.program}" if options.program else f"the RAPID generated for {options.protocol}"
    head = f"mock {options.protocol} controller (simulated IRB 1400 running {runs}, {postures} approved postures)"
    # where it listens, its link and the flags that reach it are the server's own (its protocol's module)
    return (f"{head}{server.listening()}; stop with Ctrl-C\n  {server.link_note(idle_timeout_s)}\n"
            f"  try: handeye robot joints --protocol {options.protocol} {server.client_flags()} --json")


def _warn(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run_mock_controller(options: MockControllerOptions, announce: Callable[[str], object] = print,
                        warn: Callable[[str], object] = _warn) -> int:
    """Start the mock, announce where it listens, serve until Ctrl-C (or ``duration_s``); returns 0.

    ``warn`` receives one line when the mock listens on an address other machines can reach.
    """
    from ...drivers import InvalidRequest
    from ...drivers import check_write_key

    if options.protocol not in mock_protocol_choices():  # that protocol's plug-in only is loaded
        raise InvalidRequest(f"unknown protocol {options.protocol!r}; choose one of {mock_protocol_choices().listed()}")
    if not options.time_scale > 0:
        raise InvalidRequest(f"--time-scale must be > 0; got {options.time_scale}")
    station = options.station or (load_station(options.config, links=RAPID_LINKS) if options.config
                                  else default_station())
    idle = station.idle_timeout_s if options.idle_timeout_s is None else options.idle_timeout_s
    low, high = IDLE_TIMEOUT_RANGE
    if not low <= idle <= high:
        raise InvalidRequest(f"--idle-timeout must be {low:g} to {high:g} s; got {idle:g}")
    key = check_write_key(options.write_key if options.write_key is not None else station.write_key, "--write-key")
    port = mock_server(options.protocol).default_port if options.port is None else options.port
    if not is_loopback(options.host):
        warn(f"warning: the mock controller listens on {options.host}, not a loopback address: anyone on that network "
             "can move the robot's mock and write its tool data; it is for testing only")
    spec = _cell_spec(options)
    robot = (_rehearsal_arm(station, options, spec)
             if options.camera_port is not None or options.cell or options.pendant_port is not None else None)
    try:
        server = start_mock_controller(options.protocol, host=options.host, port=port, postures=station.postures,
                                       robot=robot,
                                       time_scale=options.time_scale, ack_timeout_s=station.ack_timeout_s,
                                       allowed_client=options.allowed_client,
                                       idle_timeout_s=idle, write_key=key, station=station, program=options.program,
                                       signals=options.signals, **options.server_options)
    except OSError as exc:
        raise InvalidRequest(f"cannot listen on {options.host}:{port} ({exc}); pick another --port "
                             "(0 = any free port)") from None
    server.keep_tool = True  # a controller's PERS tool data outlives the programs loaded after a write-back
    cell = pendant = None
    try:
        if options.camera_port is not None:
            cell = _start_cell(server, options.host, options.camera_port, spec)
        if options.pendant_port is not None:
            pendant = _start_pendant(server, options.pendant_port)
        announce(_banner(server, options, len(server.robot.postures), idle)
                 + "".join(f"\n{side.banner()}" for side in (cell, pendant) if side is not None))
        failure = _serve(server, options.duration_s, warn)
    except KeyboardInterrupt:
        failure = None
    finally:
        for side in (cell, pendant):
            if side is not None:
                side.stop()
        server.stop()
    if failure:
        warn(f"the mock controller's RAPID program {failure}; {server.fix_hint(error=True)}")
        return 1
    announce("mock controller stopped")
    return 0


def _serve(server: RapidControllerServer, duration_s: float | None, warn: Callable[[str], object] = _warn) -> str | None:
    """Serve until Ctrl-C or ``duration_s``; ``stopped on an error: ...`` if the RAPID program stopped on one.

    ``warn`` gets one line when the program ends by itself (EXIT, Stop) and when it has not opened its
    link :data:`LINK_NOTICE_S` seconds after it started (each once per program run).
    """
    end = None if duration_s is None else time.monotonic() + duration_s
    watch = _ProgramWatch(server, warn)
    while True:
        failure = watch.look()
        if failure or (end is not None and time.monotonic() >= end):
            return failure
        time.sleep(0.1 if end is None else max(0.0, min(0.1, end - time.monotonic())))


class _ProgramWatch:
    """Looks at the mock's running RAPID program and says, once per run, what the operator must know."""

    def __init__(self, server: RapidControllerServer, warn: Callable[[str], object]):
        self.server, self.warn = server, warn
        self.task, self.since, self.said = None, 0.0, set()

    def look(self) -> str | None:
        """The program's error (``stopped on an error: ...``), or None after saying what is new."""
        runner = self.server.program
        task = runner.task if runner is not None else None
        if runner is None or task is None:
            return None
        if self.server.program_error:
            return runner.end_reason
        if task is not self.task:  # a new run (a PC loaded another program)
            self.task, self.since, self.said = task, time.monotonic(), set()
        if runner.end_reason:
            self._say("end", f"the mock controller's RAPID program {runner.end_reason}: the PC cannot reach the mock "
                             f"any more; {self.server.fix_hint()}")
        elif self.server.link_open is False and time.monotonic() - self.since >= LINK_NOTICE_S:
            looped = f" (its main ran to its end {runner.main_returns} times)" if runner.main_returns else ""
            self._say("link", f"the mock controller's RAPID program has not opened its {self.server.kind} link "
                              f"{LINK_NOTICE_S:g} s after it started{looped}: the PC cannot connect; "
                              f"{self.server.fix_hint()}")
        return None

    def _say(self, what: str, line: str) -> None:
        if what not in self.said:
            self.said.add(what)
            self.warn(line)


def _cell_spec(options: MockControllerOptions) -> MockStationSpec:
    """The mock cell around the arm: the demo's board and camera, the config's keep-out volumes."""
    from ..station import MockStationSpec

    if options.faults is None:  # the spec's own default (nothing changed)
        return MockStationSpec(protocol=options.protocol, cell=options.cell, arm=options.arm)
    return MockStationSpec(protocol=options.protocol, cell=options.cell, faults=options.faults, arm=options.arm)


def _rehearsal_arm(station: RapidStation, options: MockControllerOptions, spec: MockStationSpec):
    """The arm of a mock with a camera or a cell: standing where the camera sees the board, as an operator
    leaves it; the cell's volumes (if any) guard its moves."""
    from ..robot import SimulatedRobot
    from ..station import DEFAULT_START, cell_guard

    return SimulatedRobot(station.postures, model=station.robot, time_scale=options.time_scale,
                          start_joints=DEFAULT_START, guard=cell_guard(spec))


def _start_pendant(server: RapidControllerServer, port: int) -> PendantService:
    """The FlexPendant's loopback port (``src/handeye/mocks/controller/pendant.py``)."""
    from .pendant import PendantService

    try:
        return PendantService(server, host="127.0.0.1", port=port).start()
    except OSError as exc:
        from ...drivers import InvalidRequest

        raise InvalidRequest(f"cannot listen on 127.0.0.1:{port} for the pendant ({exc}); pick "
                             "another --pendant-port (0 = any free port)") from None


def _start_cell(server: RapidControllerServer, host: str, port: int, spec: MockStationSpec) -> CellService:
    """The simulated XB3 on the arm's flange, served for a rehearsal station (``mocks.cell``)."""
    from ..cell import CellService

    return CellService(server, host=host, port=port, spec=spec).start()
