"""Mock ABB controller: real servers on 127.0.0.1 behaving like the generated RAPID program.

``start_mock_controller("socket" | "serial" | "modbus")`` builds a simulated IRB 1400
(:class:`~handeye.mocks.robot.SimulatedRobot`), the program's state machine
(:class:`RapidProgram`) and the server of that protocol, starts it and returns it. Use it as a
context manager so threads and sockets are released::

    with start_mock_controller("socket", time_scale=0.01) as server:
        with open_controller("socket", **server.client_options()) as robot:
            robot.goto_posture(1)
            assert np.allclose(robot.read_joints(), server.robot.current_joints, atol=1e-3)

Every server has ``.robot`` (true state: ``current_joints``, ``tool0_pose()``, ``tool``,
``arrival_hooks``), ``.program``, ``.faults`` (see :class:`Faults`), ``.host``, ``.port`` and
``.client_options()`` (keyword arguments for ``open_controller``, the idle timeout and the write
key included).
"""

from __future__ import annotations

from ...rapid.station import default_station
from ..backends import mock_protocols, mock_server
from ..robot import SimulatedRobot
from .faults import Faults
from .line_server import DEFAULT_IDLE_TIMEOUT_S, LineSession, SerialControllerServer, SocketControllerServer
from .modbus_server import ModbusControllerServer
from .program import ProgramRefusal, RapidProgram

__all__ = [
    "start_mock_controller",
    "mock_protocols",
    "mock_server",
    "DEFAULT_IDLE_TIMEOUT_S",
    "Faults",
    "RapidProgram",
    "ProgramRefusal",
    "LineSession",
    "SocketControllerServer",
    "SerialControllerServer",
    "ModbusControllerServer",
]


def start_mock_controller(protocol: str = "socket", *, host: str = "127.0.0.1", port: int = 0, postures=None,
                          robot: SimulatedRobot | None = None, time_scale: float = 1.0, speed_fraction: float = 0.25,
                          ack_timeout_s: float | None = 30.0, allowed_client: str | None = None,
                          register_map=None, faults: Faults | None = None, publish_period_s: float = 0.005,
                          idle_timeout_s: float = DEFAULT_IDLE_TIMEOUT_S, write_key: str | None = None,
                          start: bool = True):
    """A started mock controller server of ``protocol``.

    Parameters
    ----------
    protocol : str
        ``socket``, ``serial`` (TCP stream for pyserial's ``socket://`` URL), ``modbus``, or any
        back end a mock serves (:func:`mock_protocols`).
    host, port : str, int
        Where to listen (port 0: a free port; read ``server.port``).
    postures : array-like, shape (n, dof), optional
        Approved postures (default: the built-in station's 12).
    robot : SimulatedRobot, optional
        An existing simulated robot (then ``postures``, ``time_scale``, ``speed_fraction`` are ignored).
    time_scale : float
        Wall-clock seconds per simulated second of motion (tests: 0.001-0.01).
    ack_timeout_s : float or None
        Posture acknowledgement timeout of the program (state LATE after it).
    allowed_client : str, optional
        Socket server only: the single client address accepted (the RAPID module's PC address).
    register_map : path or RegisterMap, optional
        Modbus only.
    idle_timeout_s : float
        The link's idle timeout (``controller.idle_timeout_s``): socket closes a PC silent this
        long, serial forgets the session, Modbus (the gateway) closes the silent connection.
    write_key : str, optional
        The station's write key: tool writes need it (``KEY`` / ``tool_key``); None refuses them.
    start : bool
        Start the server (default); else call ``server.start()`` or use ``with``.
    """
    mock = mock_server(protocol)
    if robot is None:
        if postures is None:
            postures = default_station().postures
        robot = SimulatedRobot(postures, time_scale=time_scale, speed_fraction=speed_fraction)
    program = RapidProgram(robot, ack_timeout_s=ack_timeout_s)
    offered = {"allowed_client": allowed_client, "register_map": register_map, "publish_period_s": publish_period_s}
    server = mock.load()(program, host, port, faults=faults, idle_timeout_s=idle_timeout_s, write_key=write_key,
                         **{name: offered[name] for name in mock.options})
    server.protocol = str(protocol).lower()
    return server.start() if start else server
