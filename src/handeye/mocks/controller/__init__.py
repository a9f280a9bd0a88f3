"""Mock ABB controller: real servers on 127.0.0.1 that EXECUTE the generated RAPID program.

``start_mock_controller(PROTOCOL)`` (any of :func:`mock_protocols`) builds a simulated IRB 1400
(:class:`~handeye.mocks.robot.SimulatedRobot`), loads the RAPID modules of that link into the
interpreter (generated for the station, or ``program=DIR``), binds them to real TCP sockets, a serial
line or a Modbus gateway and to the arm, and runs ``main``. Use it as a context manager so threads
and sockets are released::

    with start_mock_controller("socket", time_scale=0.01) as server:
        with open_controller("socket", **server.client_options()) as robot:
            robot.goto_posture(1)
            assert np.allclose(robot.read_joints(), server.robot.current_joints, atol=1e-3)

Every server has ``.robot`` (true state: ``current_joints``, ``tool0_pose()``, ``tool`` (the
program's PERS tooldata), ``arrival_hooks``), ``.program`` (the RAPID runner: ``.task``,
``.pendant``, ``.error``), ``.flexpendant`` (the operator's side of TPReadFK, UIMessageBox and Stop
\\NoRegain: ``answer(key)``, ``start()``; served from outside by ``pendant.PendantService``),
``.faults`` (see :class:`Faults`), ``.host``, ``.port`` and
``.client_options()`` (keyword arguments for ``open_controller``, the idle timeout and the write key
included). A program the interpreter cannot run is refused at start with its module and line.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import Any

import numpy.typing as npt

from ...drivers import DEFAULT_PROTOCOL
from ...rapid import RapidStation, default_station
from ..backends import mock_protocols, mock_server
from ..robot import SimulatedRobot
from .faults import Faults
from .line_server import SerialControllerServer, SocketControllerServer
from .modbus_server import ModbusControllerServer
from .rws_server import RwsControllerServer
from .runner import RapidRunner
from .server import DEFAULT_IDLE_TIMEOUT_S, RapidControllerServer
from .signals import CELL_SIGNALS, CellSignals
from .sources import ControllerProgram, generated_program, program_from_folder

__all__ = [
    "start_mock_controller",
    "mock_protocols",
    "mock_server",
    "DEFAULT_IDLE_TIMEOUT_S",
    "Faults",
    "RapidRunner",
    "RapidControllerServer",
    "ControllerProgram",
    "generated_program",
    "program_from_folder",
    "SocketControllerServer",
    "SerialControllerServer",
    "ModbusControllerServer",
    "RwsControllerServer",
    "CellSignals",
    "CELL_SIGNALS",
]


def _program(protocol, program, station, postures, ack_timeout_s, idle_timeout_s, write_key, allowed_client):
    if isinstance(program, ControllerProgram):
        return program
    if program is not None:
        return program_from_folder(program, protocol)
    return generated_program(protocol, station, postures=postures, ack_timeout_s=ack_timeout_s,
                             idle_timeout_s=idle_timeout_s, write_key=write_key, pc_address=allowed_client)


def start_mock_controller(protocol: str = DEFAULT_PROTOCOL, *, host: str = "127.0.0.1", port: int = 0,
                          postures: npt.ArrayLike | None = None,
                          robot: SimulatedRobot | None = None, time_scale: float = 1.0, speed_fraction: float = 0.25,
                          ack_timeout_s: float | None = 30.0, allowed_client: str | None = None,
                          faults: Faults | None = None,
                          idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None,
                          program: ControllerProgram | str | os.PathLike[str] | None = None,
                          station: RapidStation | None = None, start: bool = True,
                          signals: Iterable[tuple[str, str, float]] = (),
                          **server_options: Any) -> RapidControllerServer:  # options: each server's own
    """A started mock controller of ``protocol`` running its RAPID program.

    Parameters
    ----------
    protocol : str
        Any back end a mock serves (:func:`mock_protocols`; default
        :data:`~handeye.drivers.controller.backends.DEFAULT_PROTOCOL`).
    host, port : str, int
        Where to listen (port 0: a free port; read ``server.port``).
    postures : array-like, shape (n, dof), optional
        Approved postures rendered into HeMain (default: the station's, the built-in 12).
    robot : SimulatedRobot, optional
        An existing simulated arm (then ``time_scale`` and ``speed_fraction`` are ignored).
    time_scale : float
        Wall-clock seconds per simulated second of motion (tests: 0.001-0.01).
    ack_timeout_s : float or None
        The program's acknowledgement timeout (state LATE after it; None: never, in practice).
    allowed_client : str, optional
        Socket: the PC address the program accepts (``HE_PC_ADDRESS``; default 127.0.0.1).
    idle_timeout_s : float
        The link's idle timeout rendered into the program (and the gateway's, for Modbus).
    write_key : str, optional
        The station's write key: rendered into HeKey.sys, loaded with the program; None: tool writes
        are refused by the program.
    program : ControllerProgram or path, optional
        Run these modules (a folder of .mod/.sys files) instead of generating them.
    station : RapidStation, optional
        The station the modules are generated for (default: the built-in one).
    start : bool
        Start the server (default); else call ``server.start()`` or use ``with``.
    signals : iterable of (name, type, value)
        Cell I/O signals besides :data:`~handeye.mocks.controller.signals.CELL_SIGNALS` (``server.cell_signals``).
    **server_options
        The mock server's own options (``MockServer.options`` of the protocol: the Modbus mock's
        ``register_map``, path or RegisterMap; the RWS mock's ``generation``, 1 or 2 ...); None or
        an option its server does not take is left out. A :class:`MockVariant` protocol brings its own
        (``mock_variants()``).
    """
    mock = mock_server(protocol)
    variant, protocol = getattr(protocol, "options", {}), str(protocol)
    source = _program(protocol, program, station, postures, ack_timeout_s, idle_timeout_s, write_key,
                      allowed_client)
    if robot is None:
        robot = SimulatedRobot(postures if postures is not None else (station or default_station()).postures,
                               time_scale=time_scale, speed_fraction=speed_fraction)
    offered = {**variant, **{name: value for name, value in server_options.items() if value is not None}}
    taken = [setting.key for setting in mock.settings()]
    server = mock.load()(source, robot, host, port, faults=faults, idle_timeout_s=idle_timeout_s, write_key=write_key,
                         **{name: offered[name] for name in taken if name in offered})
    server.protocol = str(protocol).lower()
    server.cell_signals = CellSignals(extra=signals)
    return server.start() if start else server
