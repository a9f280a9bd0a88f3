"""The outside world of a RAPID program, as the interpreter asks for it.

A controller gives a program sockets, serial channels, I/O signals, the arm and the FlexPendant.
The interpreter asks for them through :class:`Bindings`; whoever runs a program provides them (the
mock controller in ``handeye.mocks`` provides real TCP sockets with fault injection, a serial line,
the Modbus gateway's signals and the simulated arm). Each binding is duck-typed; the classes below
document what is asked and give simple implementations for tests.

Blocking calls receive the :class:`~handeye.rapid.interpreter.runtime.Task`: they wait with
``task.idle(seconds, readable=[socket, ...])`` so that interrupts run and a stop request ends the
wait. Failures a program can handle are raised as ``RapidRuntimeError("ERR_...")``.
"""

from __future__ import annotations

from typing import Any, TYPE_CHECKING
import logging
from collections.abc import Callable
from dataclasses import dataclass, field

from .errors import RapidFatalError

if TYPE_CHECKING:
    from .runtime import Task
    from .pendant import FlexPendant

__all__ = ["Bindings", "SocketBinding", "SerialBinding", "IoBinding", "MotionBinding", "MemoryIo", "FixedArm"]

log = logging.getLogger(__name__)


class SocketBinding:
    """Sockets of the PC Interface option (``SocketCreate`` ...). Handles are the binding's own objects."""

    def create(self, task: Task) -> Any:
        raise NotImplementedError

    def bind(self, handle: Any, address: str, port: int) -> None:
        raise NotImplementedError

    def listen(self, handle: Any) -> None:
        raise NotImplementedError

    def accept(self, task: Task, handle: Any, timeout: float | None) -> tuple:
        """``(client handle, client address)``; ``ERR_SOCK_TIMEOUT`` when nobody came in time."""
        raise NotImplementedError

    def connect(self, task: Task, handle: Any, address: str, port: int, timeout: float | None) -> None:
        raise NotImplementedError

    def receive(self, task: Task, handle: Any, max_bytes: int, timeout: float | None, exact: bool = False) -> bytes:
        """Whatever arrived, at most ``max_bytes`` (exactly that many with ``exact``); ``ERR_SOCK_TIMEOUT``,
        ``ERR_SOCK_CLOSED``."""
        raise NotImplementedError

    def send(self, task: Task, handle: Any, data: bytes) -> None:
        raise NotImplementedError

    def close(self, handle: Any) -> None:
        raise NotImplementedError

    def status(self, handle: Any) -> str:
        """``created``, ``bound``, ``listening``, ``connected`` or ``closed``."""
        raise NotImplementedError


class SerialBinding:
    """Serial channels (``Open "sio1:", dev \\Bin`` ...)."""

    def open(self, task: Task, name: str, binary: bool) -> Any:
        raise NotImplementedError

    def read_line(self, task: Task, handle: Any, timeout: float | None) -> bytes:
        """One line without its LF (at most 80 characters); ``ERR_DEV_MAXTIME`` when none came in time."""
        raise NotImplementedError

    def write(self, task: Task, handle: Any, data: bytes) -> None:
        raise NotImplementedError

    def clear(self, handle: Any) -> None:
        raise NotImplementedError

    def close(self, handle: Any) -> None:
        raise NotImplementedError


class IoBinding:
    """The I/O signals of the controller's configuration."""

    def signals(self) -> dict:
        """Signal name -> ``signaldi``, ``signaldo``, ``signalgi``, ``signalgo``, ``signalai`` or ``signalao``."""
        raise NotImplementedError

    def read(self, name: str) -> float:
        raise NotImplementedError

    def write(self, name: str, value: float) -> None:
        raise NotImplementedError

    def bits(self, name: str) -> int:
        """Width of a group signal."""
        return 16


class MotionBinding:
    """The robot arm."""

    def joints(self) -> list:
        """Axis angles now (deg, six of them)."""
        raise NotImplementedError

    def flange(self) -> tuple:
        """``(position mm, quaternion w x y z)`` of tool0 in the base (world) frame now."""
        raise NotImplementedError

    def move_joints(self, task: Task, joints, speed: dict, zone: dict, tool) -> None:
        """Move all axes to ``joints`` and return when the arm stands still there (``task.idle`` meanwhile)."""
        raise NotImplementedError

    def move_path(self, task: Task, configurations, speed: dict, zone: dict, tool, what: str) -> None:
        """Move through the joint configurations ``(n, 6)`` in turn (``MoveJ``: one; ``MoveL``: its samples
        along the TCP line) and return when the arm stands still at the last; the whole path is checked
        first (``RapidFatalError`` naming ``what`` and what it would violate; the arm does not move)."""
        raise NotImplementedError

    def model(self):
        """The arm's kinematics (:class:`~handeye.robot.kinematics.RobotModel`)."""
        from ...robot import load_robot

        return load_robot("IRB1400")

    def world_zone(self, number: int, zone: dict | None) -> None:
        """A world zone supervised from now on (``zone``), or no longer (``None``)."""


@dataclass
class Bindings:
    """What a task can reach; ``None`` where the controller has nothing of that kind."""

    sockets: SocketBinding | None = None
    serial: SerialBinding | None = None
    io: IoBinding | None = None
    motion: MotionBinding | None = None
    pendant: Callable[[str], object] | None = None  # callable(text) for TPWrite, or None to log it
    #: The operator's pendant (``rapid.interpreter.pendant.FlexPendant``): TPReadFK, UIMessageBox and
    #: Stop \NoRegain wait for it; None: nobody answers (they stop the program; Stop ends it).
    flexpendant: FlexPendant | None = None
    sysinfo: dict = field(default_factory=lambda: {"LanIp": "127.0.0.1", "SystemName": "handeye",
                                                    "RobotType": "IRB 1400", "SWVersion": "6.0",
                                                    "CtrlId": "handeye-interpreter", "SerialNo": "0"})

    def signals(self) -> dict:
        return dict(self.io.signals()) if self.io is not None else {}

    def write_pendant(self, text: str) -> None:
        if self.flexpendant is not None:
            self.flexpendant.write(text)
        if self.pendant is not None:
            self.pendant(text)
        else:
            log.info("TPWrite: %s", text)

    def need(self, kind: str, what: str):
        binding = getattr(self, kind)
        if binding is None:
            raise RapidFatalError(f"{what}: this controller has no {kind}")
        return binding


class MemoryIo(IoBinding):
    """Signals held in a dict (tests): ``MemoryIo({"diStart": "signaldi", ...})``."""

    def __init__(self, signals: dict, bits: int = 16):
        self._types = dict(signals)
        self.values = {name: 0.0 for name in signals}
        self._bits = bits

    def signals(self) -> dict:
        return self._types

    def read(self, name: str) -> float:
        return self.values[name]

    def write(self, name: str, value: float) -> None:
        self.values[name] = float(value)

    def bits(self, name: str) -> int:
        return self._bits


class FixedArm(MotionBinding):
    """An arm that reaches every target at once (tests of programs, not of motion)."""

    def __init__(self, joints=(0.0,) * 6, flange=((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))):
        self._joints = list(joints)
        self._flange = flange
        self.moves: list = []
        self.paths: list = []  # the configurations of every move_path
        self.zones: dict = {}

    def joints(self) -> list:
        return list(self._joints)

    def flange(self) -> tuple:
        return self._flange

    def move_joints(self, task: Task, joints, speed, zone, tool) -> None:
        self.moves.append(list(joints))
        self._joints = list(joints)

    def move_path(self, task: Task, configurations, speed, zone, tool, what: str) -> None:
        self.paths.append([list(map(float, c)) for c in configurations])
        self.move_joints(task, self.paths[-1][-1], speed, zone, tool)

    def world_zone(self, number: int, zone) -> None:
        if zone is None:
            self.zones.pop(number, None)
        else:
            self.zones[number] = zone
