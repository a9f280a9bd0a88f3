"""Opening the station's hardware, real or the embedded mock, behind one object.

Which one is decided by the configuration alone (:attr:`StationConfig.is_mock`): a real config opens
the real controller and camera, and when they cannot be reached the call fails; it never falls back
to the mock. ``--mock`` on the command line turns a config into the mock one (``config.as_mock()``).

A rehearsal config (:attr:`StationConfig.is_rehearsal`: ``camera.backend: mock`` with
``camera.mock_arm``) opens the real drivers of its controller link and the camera of a standalone
``handeye mock controller --camera-port``; before anything moves, the camera's mock is asked which
controller its arm belongs to, and a config whose ``controller`` section names another one is
refused: the mock camera never silently watches a real robot.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, cast

import numpy as np

from .config.station import StationConfig

if TYPE_CHECKING:
    from ..drivers import Camera, Controller, StereoModel
    from ..mocks import MockStation, MockStationSpec


@dataclass
class StationLink:
    """A connected controller and camera, and what the capture needs to know about them.

    Attributes
    ----------
    controller : drivers.controller.Controller
    camera : drivers.camera.Camera
    stereo_model : drivers.camera.stereo.StereoModel
    load_program : callable or None
        ``load_program(postures, rapid_dir)`` puts a generated program on the controller (the mock
        loads the modules of ``rapid_dir`` and runs them; a real controller is loaded by the operator).
    mock : mocks.station.MockStation or None
        The embedded station, with its hidden truth.
    rehearsal : str or None
        A rehearsal station: the ``HOST:PORT`` of the mock controller's camera (its truth stays there).
    stop_program : callable or None
        ``stop_program()`` stops RAPID execution at the end of a capture, where the PC started it
        (Robot Web Services); None: the program is left to the operator.
    """

    controller: Controller
    camera: Camera | None = None
    stereo_model: StereoModel | None = None
    load_program: Callable | None = None
    mock: MockStation | None = None
    rehearsal: str | None = None
    stop_program: Callable | None = None

    @property
    def is_mock(self) -> bool:
        return self.mock is not None

    @property
    def truth_cam2tool0(self) -> np.ndarray | None:
        return None if self.mock is None else self.mock.truth["cam2tool0"]


def _controller_options(config: StationConfig) -> dict:
    """The keyword options of ``open_controller`` for the config's controller: where it is, as its
    back end's registry entry builds it from the ``controller`` section, and the link settings."""
    from ..drivers import CONTROLLERS

    c = config.controller
    common = {"timeout": c.timeout_s, "motion_timeout": c.motion_timeout_s, "robot": config.robot,
              "idle_timeout": c.idle_timeout_s, "write_key": c.write_key}
    return {**CONTROLLERS[config.link_protocol].link_options(c), **common}


def _camera_options(config: StationConfig) -> dict:
    """The keyword options of ``open_camera`` for the config's camera, as its back end builds them."""
    from ..drivers import CAMERAS

    return CAMERAS[config.camera.backend].camera_options(config.camera)


#: The embedded mock controller's memory (its PERS tool data), in the folder of the sessions.
MOCK_STATE_FILE = "mock_controller_state.json"


def mock_state_file(session_dir: str | Path | None) -> Path | None:
    """Where the embedded mock station keeps its controller's PERS values for the sessions beside
    ``session_dir`` (None: no session folder, a fresh controller)."""
    return None if session_dir is None else Path(session_dir).resolve().parent / MOCK_STATE_FILE


def mock_spec(config: StationConfig, state_file: str | Path | None = None) -> MockStationSpec:
    """The embedded mock station described by the configuration's ``mock`` section (``state_file``: where its
    controller keeps its PERS tool data between runs, :func:`mock_state_file`)."""
    from ..mocks import MockStationSpec

    m = config.mock
    zone_tcp = tuple(config.camera.nominal_mount[0]) if config.cell.world_zones else None
    return MockStationSpec(protocol=m.protocol, board=config.target, kinematic_error_mm=m.kinematic_error_mm,
                           kinematic_error_deg=m.kinematic_error_deg, time_scale=m.time_scale, seed=m.seed,
                           idle_timeout_s=config.controller.idle_timeout_s, write_key=config.controller.write_key,
                           cell=config.cell.model(), zone_tcp_mm=zone_tcp, faults=m.faults.model(), arm=m.arm.model(),
                           state_file=None if state_file is None else str(state_file), occlude=m.occlude)


#: What every output says when the embedded mock station is in use.
MOCK_BANNER = ("MOCK: the embedded mock station (a simulated IRB 1400 and XB3 on 127.0.0.1); nothing here moves, "
               "measures or writes a real robot")


def rehearsal_banner(config: StationConfig) -> str:
    """What every output of a rehearsal says first."""
    return (f"MOCK: rehearsal: the camera is the simulated XB3 of `handeye mock controller` at {config.camera.mock_arm}, "
            f"on the arm of that mock controller ({config.controller.protocol}); nothing here moves, measures or writes "
            "a real robot")


def _same_host(a: str, b: str) -> bool:
    import socket

    if a in ("0.0.0.0", "", "::") or b in ("0.0.0.0", "", "::"):
        return True
    try:
        return socket.gethostbyname(a) == socket.gethostbyname(b)
    except OSError:
        return a == b


def check_rehearsal(config: StationConfig) -> dict:
    """The mock controller the rehearsal camera belongs to, checked against the config's controller.

    Raises
    ------
    ConfigError
        The camera's mock serves another controller than ``controller`` names (or none).
    CameraError
        No rehearsal camera answers at ``camera.mock_arm``.
    """
    from ..base import ConfigError
    from ..mocks import cell_info

    from ..drivers import CONTROLLERS

    arm = config.camera.mock_arm
    if arm is None:
        raise ConfigError("not a rehearsal: camera.mock_arm names no mock controller's camera")
    served = cell_info(arm)["controller"]
    c = config.controller
    options = CONTROLLERS[c.protocol].link_options(c)
    if "url" in options:  # a line behind a URL: the URL is the address
        address, named = {"url": options["url"]}, options["url"]
    else:
        address = {"host": options.get("host"), "port": options.get("port")}
        named = f"{c.protocol} {address['host']}:{address['port']}"
    same = served["protocol"] == c.protocol and all(
        _same_host(str(served.get(key)), str(value)) if key == "host" else served.get(key) == value
        for key, value in address.items())
    if not same:
        where = served.get("url") or f"{served['host']}:{served['port']}"
        raise ConfigError(f"camera.mock_arm {config.camera.mock_arm} is the camera of the mock {served['protocol']} "
                          f"controller at {where}, but the controller section names {named}: a rehearsal drives the mock "
                          "controller whose arm the mock camera sees")
    return served


class _LoadsPrograms(Protocol):
    """A rehearsal's camera (``mocks.cell.CellCamera``): it loads a program into its mock controller's task."""

    def load_program(self, rapid_dir) -> int: ...


def _rehearsal_camera(camera: Camera) -> _LoadsPrograms:
    # a rehearsal config's camera back end is ``mock`` on camera.mock_arm: mocks.cell.CellCamera, which has load_program
    return cast(_LoadsPrograms, camera)


@contextmanager
def _mock_station(config: StationConfig, session_dir=None):
    from ..drivers import open_controller
    from ..mocks import MockStation

    with MockStation(mock_spec(config, mock_state_file(session_dir))) as station:
        options = {**station.controller_options(), "timeout": config.controller.timeout_s,
                   "motion_timeout": config.controller.motion_timeout_s, "robot": config.robot}
        with open_controller(station.spec.protocol, **options) as controller:
            yield station, controller


@contextmanager
def open_station(config: StationConfig, mock: bool = False, session_dir: str | Path | None = None) -> Iterator[StationLink]:
    """Yield a :class:`StationLink` with the controller and the camera of ``config`` (real, or the
    embedded mock when ``config.is_mock`` or ``mock``); everything is closed (and the mock stopped)
    on exit. The embedded mock keeps its controller's PERS tool data beside ``session_dir``
    (:func:`mock_state_file`), as a controller keeps it between runs.

    The controller is opened first, so a controller that is not there fails within its link timeout
    before the camera is touched.
    """
    if mock:
        config = config.as_mock()
    if config.is_mock:
        with _mock_station(config, session_dir) as (station, controller), station.camera as camera:
            yield StationLink(controller, camera, camera.model, lambda _postures, rapid_dir: station.load_program(rapid_dir),
                              station)
        return
    from ..drivers import open_camera
    from ..drivers import load_stereo_model, nominal_xb3_model
    from ..drivers import open_controller

    if config.is_rehearsal:
        check_rehearsal(config)
    model = load_stereo_model(config.camera.stereo_model) if config.camera.stereo_model else nominal_xb3_model()
    with open_controller(config.controller.protocol, **_controller_options(config)) as controller, \
            open_camera(config.camera.backend, **_camera_options(config)) as camera:
        loader = _program_loader(controller)  # over RWS the PC loads the program itself, rehearsal or not
        stop = getattr(controller, "stop_program", None) if loader is not None else None
        if config.is_rehearsal:  # else the mock plays the operator who loads SESSION/rapid into the task
            yield StationLink(controller, camera, model,
                              loader or (lambda _postures, rapid_dir: _rehearsal_camera(camera).load_program(rapid_dir)),
                              rehearsal=config.camera.mock_arm, stop_program=stop)
            return
        yield StationLink(controller, camera, model, loader, stop_program=stop)


def _program_loader(controller):
    """``load_program(postures, rapid_dir)`` for a controller the PC can load itself (Robot Web
    Services: upload, load into the task, reset the program pointer, start), else None (the
    operator loads the modules). HeTool is loaded only when the task has no camera tool data yet, so
    a calibrated tframe on the controller is never replaced by the session's placeholder."""
    load = getattr(controller, "load_program", None)
    if load is None:
        return None

    def put(_postures, rapid_dir) -> None:
        from ..drivers import StationError

        try:
            controller.read_tool()
            has_tool = True
        except StationError:
            has_tool = False
        files = sorted(p for p in Path(rapid_dir).iterdir() if p.suffix.lower() in (".mod", ".modx") and p.is_file())
        load([(p.name, p.read_text(encoding="latin-1")) for p in files if not (has_tool and p.stem.lower() == "hetool")])

    return put


@contextmanager
def open_controller_link(config: StationConfig, mock: bool = False,
                         session_dir: str | Path | None = None) -> Iterator[StationLink]:
    """Yield a :class:`StationLink` holding only the controller of ``config`` (real, or the embedded
    mock station's when ``config.is_mock`` or ``mock``, its PERS values kept beside ``session_dir``):
    what write-back needs, so it works without the camera."""
    if mock:
        config = config.as_mock()
    if config.is_mock:
        with _mock_station(config, session_dir) as (station, controller):
            yield StationLink(controller, mock=station)
        return
    from ..drivers import open_controller

    if config.is_rehearsal:
        check_rehearsal(config)
    with open_controller(config.controller.protocol, **_controller_options(config)) as controller:
        yield StationLink(controller, rehearsal=config.camera.mock_arm if config.is_rehearsal else None)
