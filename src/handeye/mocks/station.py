"""The embedded mock station: a simulated IRB 1400 behind a real controller server, and a simulated
XB3 on its flange looking at a printed board, with a hidden true camera mount.

What makes it honest:

- The controller is a real server on 127.0.0.1 (the mock of its controller back end) that runs
  the generated RAPID program in the interpreter, driving the simulated arm; the PC talks to it with
  the real drivers. A capture's modules (``SESSION/rapid``) are loaded into it and executed.
- The camera renders real XB3 frames (``mocks.camera``) that go through the real decoding,
  detection and triangulation.
- The arm is not the nominal model: its true kinematics differ from the nominal DH table by small
  link-length and joint-offset errors (a real arm is never exactly its datasheet). The controller
  reports joints and the NOMINAL flange pose, like a real controller; the camera sees the board from
  the TRUE flange pose. So the calibration meets the kind of systematic error a station meets.
- The camera mount (``cam2tool0``) is hidden from the PC; only :attr:`MockStation.truth` holds it.
- The cell is physical: given one (``MockStationSpec.cell``), the arm refuses any move whose
  joint-interpolated path takes any link or what the flange carries into a keep-out volume or the
  board's stand (built around the TRUE board), as a real cell's world zones would stop it; and with
  or without a cell, any move that brings the camera or its bracket into the arm's own links, or two
  links into each other (the robot file's self-collision pairs), as a real arm would crash.
"""

from __future__ import annotations

import os
import secrets
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from ..robot import CellModel
from ..robot import CellGuard
from .robot import self_guard
from ..geometry import STATION_BOARD, BoardGeometry
from ..robot import RobotModel, load_robot
from ..geometry import transform_from_rotation_translation
from ..drivers import StereoModel, nominal_xb3_model
from ..drivers import DEFAULT_PROTOCOL
from ..drivers import ToolData
from .arm_truth import ArmDeviations, true_arm
from .camera import MockCamera, RenderOptions
from .controller import ControllerProgram, RapidControllerServer, start_mock_controller
from .drift import StationFaults
from .robot import SimulatedRobot
from .world import PrintedBoard

if TYPE_CHECKING:
    from .printed_targets import Occlusion

__all__ = ["DEFAULT_BOARD", "DEFAULT_MOUNT", "DEFAULT_START", "MockStation", "MockStationSpec", "perturbed_robot", "cell_guard",
           "flange_camera"]


def _pose(rotvec_deg, translation) -> np.ndarray:
    return transform_from_rotation_translation(Rotation.from_rotvec(np.radians(rotvec_deg)).as_matrix(), translation)


#: The hidden true camera mount of the demo: XB3 beside the flange, optical axis near tool0 z.
DEFAULT_MOUNT = _pose([1.8, -2.4, 90.6], [-118.0, 34.5, 92.0])
#: The board on the inspection table: printed face up, centre at (900, 100, 60) mm in base.
DEFAULT_BOARD = transform_from_rotation_translation(Rotation.from_euler("xyz", [180.0, 0.0, 8.0], degrees=True).as_matrix(),
                                                    [900.0, 100.0, 60.0])
DEFAULT_BOARD[:3, 3] -= DEFAULT_BOARD[:3, :3] @ np.array([180.0, 105.0, 0.0])  # centre of a 13x8, 30 mm grid
#: A posture from which the default camera sees the default board (found by inverse kinematics).
DEFAULT_START = (-1.46, -22.51, 2.22, -0.07, 74.58, -92.01)


def perturbed_robot(nominal: RobotModel, length_mm: float, angle_deg: float, seed: int) -> RobotModel:
    """The nominal robot with random DH errors: lengths ``N(0, length_mm)``, angles ``N(0, angle_deg)``."""
    rng = np.random.default_rng(seed)
    dh = nominal.dh.copy()
    dh[:, 0] += rng.normal(0.0, length_mm, len(dh)) * (dh[:, 0] != 0)
    dh[:, 1] += rng.normal(0.0, length_mm, len(dh)) * (dh[:, 1] != 0)
    dh[:, 2] += rng.normal(0.0, angle_deg, len(dh))
    dh[:, 3] += rng.normal(0.0, angle_deg, len(dh))
    rows = [(i + 1, j + 1, c) for i in range(nominal.dof) for j in range(nominal.dof)
            if i != j and nominal.coupling[i, j] != 0 for c in [nominal.coupling[i, j]]]
    return RobotModel.from_dh(f"{nominal.name} (true arm)", dh, rows, nominal.joint_limits_deg, nominal.max_speed_deg_s)


@dataclass(frozen=True)
class MockStationSpec:
    """What the embedded station looks like.

    Attributes
    ----------
    protocol : str
        Controller link: any back end a mock serves (:func:`~handeye.mocks.backends.mock_protocols`).
    cam2tool0 : ndarray, shape (4, 4)
        The hidden true camera mount.
    board2base : ndarray, shape (4, 4)
        The board's target frame in base.
    board : BoardGeometry
    start_joints_deg : tuple
        Where the arm stands at power-up (the camera sees the board from there).
    kinematic_error_mm, kinematic_error_deg : float
        Standard deviation of the true arm's DH errors against the nominal table.
    time_scale : float
        Wall-clock seconds per simulated second of motion.
    speed_fraction : float
        Fraction of the axis speeds used by the moves.
    stereo : StereoModel or None
        The simulated head's geometry (default: the nominal XB3 wide pair).
    seed : int
        Seeds the arm's errors and the sensor noise.
    idle_timeout_s : float
        The controller link's idle timeout (``controller.idle_timeout_s``).
    write_key : str, optional
        The write key the controller expects for tool writes (``controller.write_key``); None: a
        random key for this run, handed to the PC through :meth:`MockStation.controller_options`.
    cell : CellModel, optional
        The cell around the arm (``cell`` of the station config); its board stand is built around the
        true board. None: an empty cell, every move allowed.
    zone_tcp_mm : tuple of float, shape (3,), optional
        With world zones: the TCP (tool0) the controller's zones watch; moves taking it into a zone
        (as the controller sees the volumes) are refused too.
    faults : StationFaults
        What changed since the calibration (``mock.faults``): the camera renders the changed world;
        ``cam2tool0`` and ``board2base`` are the station as it was.
    state_file : str or None
        Where the controller keeps its PERS tool data between runs (a file beside the sessions); None:
        a fresh controller each run.
    arm : ArmDeviations or None
        The true arm's deviations from its DH table given explicitly (``mock.arm``,
        :mod:`~handeye.mocks.arm_truth`); None: random ones (``kinematic_error_mm`` / ``_deg``).
    """

    protocol: str = DEFAULT_PROTOCOL
    cam2tool0: np.ndarray = field(default_factory=lambda: DEFAULT_MOUNT.copy())
    board2base: np.ndarray = field(default_factory=lambda: DEFAULT_BOARD.copy())
    board: BoardGeometry = STATION_BOARD
    start_joints_deg: tuple = DEFAULT_START
    kinematic_error_mm: float = 0.05
    kinematic_error_deg: float = 0.002
    time_scale: float = 0.02
    speed_fraction: float = 0.5
    stereo: StereoModel | None = None
    render: RenderOptions | None = None
    robot: str = "IRB1400"
    seed: int = 7
    idle_timeout_s: float = 5.0
    write_key: str | None = field(default=None, repr=False)
    cell: CellModel | None = None
    zone_tcp_mm: tuple | None = None
    faults: StationFaults = field(default_factory=StationFaults)
    state_file: str | None = None
    arm: ArmDeviations | None = None
    #: ``mock.occlude``: a band over the board at a share of the postures (``mocks.printed_targets.Occlusion``).
    occlude: Occlusion | None = None


class MockStation:
    """A running mock station (context manager: starts the server, stops it and its threads).

    Attributes
    ----------
    server
        The controller server (``.robot`` is the simulated arm).
    camera : MockCamera
    truth : dict
        ``cam2tool0`` (hidden mount), ``board2base``, ``true_robot`` (the arm's real kinematics).
    """

    def __init__(self, spec: MockStationSpec = MockStationSpec()):
        self.spec = spec
        self.nominal = load_robot(spec.robot)
        start = np.asarray(spec.start_joints_deg, float)
        self.arm = SimulatedRobot([start], model=spec.robot, speed_fraction=spec.speed_fraction,
                                  time_scale=spec.time_scale, start_joints=start, guard=self._cell_guard(spec))
        self.server: RapidControllerServer | None = None
        # The station's key, or one made for this run: the server and the PC's options share it.
        self._write_key = spec.write_key if spec.write_key is not None else secrets.token_hex(16)
        self.state = read_state(spec.state_file)
        self.camera, self.truth = flange_camera(spec, self.arm, self.state["runs"])
        self.true_robot = self.truth["true_robot"]

    def _cell_guard(self, spec: MockStationSpec) -> CellGuard | None:
        return cell_guard(spec, self.nominal)

    def start(self) -> MockStation:
        if self.server is None:
            server = start_mock_controller(self.spec.protocol, robot=self.arm, idle_timeout_s=self.spec.idle_timeout_s,
                                           write_key=self._write_key, start=False)
            if self.spec.state_file is not None:  # the controller keeps its PERS tool data between runs
                server.keep_tool, server.kept_tool = True, self.state["tool"]
            self.server = server.start()
        return self

    def stop(self) -> None:
        if self.server is not None:
            if self.spec.state_file is not None:
                write_state(self.spec.state_file, self.arm.tool, self.state["runs"] + 1)
            self.server.stop()
            self.server = None
        self.camera.close()

    def __enter__(self) -> MockStation:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def controller_options(self) -> dict:
        """Keyword arguments for ``drivers.controller.open_controller(spec.protocol, ...)`` (write key included)."""
        return dict(self._live_server().client_options())

    @property
    def write_key(self) -> str:
        """The key its controller's HeKey.sys holds (the station's, or one made for this run)."""
        return self._write_key

    def load_program(self, program: ControllerProgram | str | os.PathLike[str]) -> None:
        """Load a generated program (a folder of modules, e.g. ``SESSION/rapid``) into the controller and
        run it; HeKey.sys stays loaded."""
        self._live_server().load_program(program)

    def _live_server(self) -> RapidControllerServer:
        if self.server is None:
            raise RuntimeError("the mock station is not started: call start() or use it in a with-block")
        return self.server


def cell_guard(spec: MockStationSpec, robot: RobotModel | None = None) -> CellGuard:
    """The physical cell of ``spec`` (its stand around the true board) and the arm itself: entering a volume
    or one of the arm's own bodies (margin 0) is refused, moves sampled every 5 mm; without a cell, the
    arm's self-collision alone (what it carries: :data:`~handeye.robot.cell.DEFAULT_CARRIED`)."""
    if spec.cell is None:
        return self_guard(robot or load_robot(spec.robot))
    zones = None
    if spec.zone_tcp_mm is not None:
        zones = (spec.zone_tcp_mm, spec.cell.world_zone_volumes(spec.board2base, spec.board))
    return CellGuard(robot or load_robot(spec.robot), spec.cell.volumes(spec.board2base, spec.board), spec.cell.carried,
                     margin_mm=0.0, step_mm=5.0, tcp_zones=zones)


def read_state(path: str | os.PathLike[str] | None) -> dict:
    """What the embedded controller kept from its earlier runs (``state_file``): ``runs`` and ``tool``
    (its PERS tool data, a ToolData, or None); a missing or unreadable file is a fresh controller."""
    import json
    from pathlib import Path

    fresh = {"runs": 0, "tool": None}
    if path is None or not Path(path).is_file():
        return fresh
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        tool = data.get("tool")
        return {"runs": int(data.get("runs", 0)),
                "tool": None if tool is None else ToolData(tuple(tool["position_mm"]), tuple(tool["quaternion_wxyz"]),
                                                           float(tool["mass_kg"]), tuple(tool["cog_mm"]))}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return fresh


def write_state(path: str | os.PathLike[str], tool: ToolData, runs: int) -> None:
    """Keep the controller's PERS tool data and its run count in ``path`` (written atomically)."""
    import json

    from ..base import write_text_atomic

    value = {"position_mm": list(tool.position_mm), "quaternion_wxyz": list(tool.quaternion_wxyz),
             "mass_kg": tool.mass_kg, "cog_mm": list(tool.cog_mm)}
    write_text_atomic(path, json.dumps({"format": "handeye-mock-controller/1", "runs": int(runs), "tool": value},
                                       indent=1) + "\n")


def flange_camera(spec: MockStationSpec, arm: SimulatedRobot, run: int = 0) -> tuple[MockCamera, dict]:
    """The simulated XB3 on ``arm``'s flange, and the hidden truth it is rendered from (its sensor
    noise seeded by ``spec.seed`` and ``run``, the station's run count: fresh noise in each run).

    The camera sees the board from the TRUE flange pose: the arm's joints through the perturbed
    kinematics (the controller reports the nominal one), times the hidden mount ``spec.cam2tool0``.

    Returns
    -------
    camera : MockCamera
    truth : dict
        ``cam2tool0``, ``board2base``, ``true_robot`` and ``dh_deviation`` (true minus nominal DH table,
        ``(k, 4)``).
    """
    nominal = load_robot(spec.robot)
    if spec.arm is not None:
        true_robot = true_arm(nominal, spec.arm)
    else:
        true_robot = perturbed_robot(nominal, spec.kinematic_error_mm, spec.kinematic_error_deg, spec.seed)
    faults = spec.faults
    mount = faults.mount(spec.cam2tool0)
    board2base = faults.board(spec.board2base)

    def cam2base():
        return true_robot.forward_transform(faults.axes(arm.current_joints)) @ mount

    model = spec.stereo if spec.stereo is not None else nominal_xb3_model()
    camera = MockCamera(model=model, board=PrintedBoard(spec.board), target2base=board2base,
                        cam2base=cam2base, options=spec.render, seed=spec.seed if not run else [spec.seed, run],
                        occlude=spec.occlude)
    return camera, {"cam2tool0": mount, "board2base": board2base, "true_robot": true_robot,
                    "dh_deviation": true_robot.dh - nominal.dh}
