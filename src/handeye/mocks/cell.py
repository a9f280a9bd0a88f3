"""The mock cell around a standalone mock controller: its arm's camera, served to a rehearsal station.

``handeye mock controller --camera-port PORT`` runs a :class:`CellService` beside the controller: the
simulated Bumblebee XB3 on the arm's flange (frames rendered from where the arm really is: the true,
slightly wrong kinematics, the hidden camera mount, the printed board), served on a TCP side port.
A station config with ``camera.backend: mock`` and ``camera.mock_arm: HOST:PORT`` opens
:class:`CellCamera`, which fetches the packed XB3 frame and decodes it with the real driver code, so
capture, calibrate and writeback run against the mock exactly as on the station. The hidden truth
never leaves the mock's process.

The side port speaks JSON lines (one request, one reply)::

    {"cmd": "info"}                      -> {"ok": true, "mock": true, "controller": {...}, "camera": {...}}
    {"cmd": "frame"}                     -> {"ok": true, "width": w, "height": h, "bytes": n, ...} + n bytes
    {"cmd": "load", "modules": [{"source": "HeMain.mod", "text": "..."}, ...]}
                                         -> {"ok": true, "postures": n} | {"ok": false, "error": "..."}
    {"cmd": "signal", "name": "diCellDoor", "value": 0}
                                         -> {"ok": true, ...} (a cell input of the controller set)

``load`` plays the operator who loads a capture's ``SESSION/rapid`` into the controller's task (the
modules are linked and executed by the mock's interpreter; HeKey.sys stays loaded).
"""

from __future__ import annotations

import json
import logging
import os
import socket
import socketserver
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..drivers import decode_xb3_frame
from ..drivers import CameraError
from ..drivers import Camera, StereoFrame
from ..rapid import RapidError
from ..rapid import ModuleSource
from .controller.sources import MODULE_SUFFIXES, ControllerProgram
from .side_port import TOO_LONG, SidePort, _Server, read_line

if TYPE_CHECKING:
    from .controller import RapidControllerServer
    from .station import MockStationSpec

__all__ = ["CellService", "CellCamera", "mock_camera", "cell_info", "parse_address", "MAX_MESSAGE"]

log = logging.getLogger(__name__)

#: Longest JSON line either side accepts (a program's modules fit).
MAX_MESSAGE = 4 * 1024 * 1024


def parse_address(text: str, what: str = "camera.mock_arm") -> tuple[str, int]:
    """``HOST:PORT`` as ``(host, port)``; ValueError with a one-line message otherwise."""
    host, sep, port = str(text).rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"{what} must be HOST:PORT (where `handeye mock controller --camera-port PORT` serves its "
                         f"camera); got {text!r}")
    return host, int(port)


# ---------------------------------------------------------------------------------------- the mock's side
class _Handler(socketserver.StreamRequestHandler):
    server: _Server  # the side port's

    def handle(self) -> None:
        service = cast(CellService, self.server.service)  # the camera port's server serves its CellService
        while True:
            line = read_line(self.rfile, MAX_MESSAGE)
            if not line:
                return
            try:
                if line is TOO_LONG:
                    raise ValueError(f"a request line longer than {MAX_MESSAGE} bytes (refused whole)")
                request = json.loads(line)
                reply, payload = service.answer(request)
            except (ValueError, KeyError, TypeError) as exc:
                reply, payload = {"ok": False, "error": f"bad request: {exc}"}, b""
            self.wfile.write(json.dumps(reply).encode() + b"\n" + payload)
            self.wfile.flush()



class CellService(SidePort):
    """The camera side port of a standalone mock controller (see the module docstring).

    Parameters
    ----------
    controller : RapidControllerServer
        The running mock controller; its ``robot`` carries the camera.
    host, port : str, int
        Where the side port listens (0: a free port).
    spec : MockStationSpec, optional
        The cell: hidden mount, board, kinematic errors, seed (default: the demo's).
    """

    def __init__(self, controller: RapidControllerServer, host: str = "127.0.0.1", port: int = 0,
                 spec: MockStationSpec | None = None):
        from .station import MockStationSpec, flange_camera

        self.controller = controller
        self.spec = spec or MockStationSpec(protocol=controller.protocol)
        self.camera, self._truth = flange_camera(self.spec, controller.robot)
        self.camera.connect()
        self._lock = threading.Lock()
        super().__init__(_Handler, host, port, "mock-cell")

    def stop(self) -> None:
        super().stop()
        self.camera.close()

    def banner(self) -> str:
        return (f"  rehearsal camera: the simulated XB3 on its flange at {self.host}:{self.port} "
                f"(station config: camera.backend: mock, camera.mock_arm: {self.host}:{self.port})")

    # ------------------------------------------------------------------ requests
    def answer(self, request: dict) -> tuple[dict, bytes]:
        command = request.get("cmd")
        if command == "info":
            return self.info(), b""
        if command == "frame":
            return self.frame()
        if command == "load":
            return self.load(request["modules"]), b""
        if command == "signal":
            return self.signal(str(request["name"]), float(request["value"])), b""
        return {"ok": False, "error": f"unknown command {command!r}"}, b""

    def info(self) -> dict:
        c = self.controller
        where = {"protocol": c.protocol, "host": c.host, "port": c.port}
        url = getattr(c, "url", None)
        if url is not None:  # a line behind a URL (pyserial's socket://HOST:PORT)
            where["url"] = url
        w, h = self.camera.model.image_size
        return {"ok": True, "mock": True, "what": "handeye mock controller", "controller": where,
                "camera": {"model": "Bumblebee XB3 (mock)", "serial": self.camera.serial, "width": w, "height": h,
                           "colour": self.camera.renderer.options.colour}}

    def frame(self) -> tuple[dict, bytes]:
        with self._lock:
            packed = self.camera.renderer.xb3_frame(self.camera.target2cam())
        h, w = packed.shape[:2]
        data = np.ascontiguousarray(packed, np.uint8).tobytes()
        return {"ok": True, "width": w, "height": h, "colour": self.camera.renderer.options.colour,
                "serial": self.camera.serial, "timestamp": time.time(), "bytes": len(data)}, data

    def signal(self, name: str, value: float) -> dict:
        """Set a cell input of the controller (the door switch ...), as a test or the pendant does."""
        try:
            self.controller.cell_signals.set(name, value)
        except ValueError as exc:
            return {"ok": False, "error": str(exc)}
        return {"ok": True, "name": name, "value": value}

    def load(self, modules: list) -> dict:
        program = ControllerProgram(tuple(ModuleSource(str(m["text"]), str(m["source"])) for m in modules),
                                    "modules loaded through the cell port")
        try:
            self.controller.load_program(program)
        except RapidError as exc:
            return {"ok": False, "error": str(exc)}
        log.info("mock controller: loaded %d module(s) through the cell port", len(modules))
        return {"ok": True, "postures": len(self.controller.robot.postures)}


# ---------------------------------------------------------------------------------------- the PC's side
class _Link:
    """One JSON-lines connection to a cell service."""

    def __init__(self, address: str, timeout_s: float):
        self.address = address
        host, port = parse_address(address)
        try:
            self.sock = socket.create_connection((host, port), timeout=timeout_s)
        except OSError as exc:
            raise CameraError(f"mock: no rehearsal camera at {address} ({exc.strerror or exc}): start `handeye mock "
                              f"controller --camera-port {port}` or fix camera.mock_arm") from None
        self.file = self.sock.makefile("rb")

    def ask(self, request: dict, timeout_s: float) -> tuple[dict, bytes]:
        self.sock.settimeout(timeout_s)
        try:
            self.sock.sendall(json.dumps(request).encode() + b"\n")
            reply = json.loads(self.file.readline(MAX_MESSAGE) or b"null")
            if not isinstance(reply, dict):
                raise CameraError(f"mock: the rehearsal camera at {self.address} closed the connection")
            payload = self.file.read(int(reply.get("bytes", 0))) if reply.get("bytes") else b""
        except (OSError, ValueError) as exc:
            raise CameraError(f"mock: the rehearsal camera at {self.address} did not answer ({exc})") from None
        if not reply.get("ok"):
            raise CameraError(f"mock: the rehearsal camera at {self.address}: {reply.get('error', 'refused')}")
        return reply, payload

    def close(self) -> None:
        self.file.close()
        self.sock.close()


def cell_info(address: str, timeout_s: float = 5.0) -> dict:
    """What the cell service at ``address`` serves (its ``info`` reply)."""
    link = _Link(address, timeout_s)
    try:
        return link.ask({"cmd": "info"}, timeout_s)[0]
    finally:
        link.close()


class CellCamera(Camera):
    """The ``mock`` camera of a rehearsal station: frames of the standalone mock controller's XB3.

    Parameters
    ----------
    mock_arm : str
        ``HOST:PORT`` of the mock controller's cell service (``--camera-port``).
    output : {"bgr", "gray"}
    timeout_s : float
        Budget of connecting.
    """

    name = "mock"
    simulated = True

    def __init__(self, mock_arm: str, output: str = "bgr", timeout_s: float = 5.0):
        parse_address(mock_arm)
        self.mock_arm, self.output, self.timeout_s = mock_arm, output, float(timeout_s)
        self._link: _Link | None = None
        self._info: dict = {}

    def connect(self) -> None:
        if self._link is None:
            self._link = _Link(self.mock_arm, self.timeout_s)
            self._info = self._link.ask({"cmd": "info"}, self.timeout_s)[0]

    def close(self) -> None:
        if self._link is not None:
            self._link.close()
            self._link = None

    @property
    def is_connected(self) -> bool:
        return self._link is not None

    @property
    def serial(self) -> int | None:
        return self._info.get("camera", {}).get("serial")

    @property
    def controller(self) -> dict:
        """The mock controller this camera's arm belongs to (protocol, host, port[, url])."""
        return dict(self._info.get("controller", {}))

    def grab(self, timeout_s: float = 2.0) -> StereoFrame:
        """Fetch the frame the mock renders now and decode it with the driver's decoder."""
        if self._link is None:
            raise CameraError("mock: the rehearsal camera is not connected: call connect() or use it in a with-block")
        reply, payload = self._link.ask({"cmd": "frame"}, max(timeout_s, 5.0))
        w, h = int(reply["width"]), int(reply["height"])
        packed = np.frombuffer(payload, np.uint8).reshape(h, w, 3)
        frame = decode_xb3_frame(packed, "rgb8", w, h, colour=bool(reply["colour"]), output=self.output, centre=True,
                                 serial=reply.get("serial"), timestamp=reply.get("timestamp"))
        frame.raw = packed
        frame.info = {"model": f"Bumblebee XB3 (mock, rendered by handeye mock controller at {self.mock_arm})"}
        return frame

    def load_program(self, rapid_dir: str | os.PathLike[str]) -> int:
        """Load the modules of ``rapid_dir`` into the mock controller's task (what the operator does on a
        real controller); returns its posture count. Raises CameraError naming a module the mock refused."""
        files = sorted(p for p in Path(rapid_dir).iterdir() if p.suffix.lower() in MODULE_SUFFIXES)
        modules = [{"source": p.name, "text": p.read_text(encoding="latin-1")} for p in files]
        if self._link is None:
            raise CameraError("mock: the rehearsal camera is not connected: call connect() or use it in a with-block")
        reply, _ = self._link.ask({"cmd": "load", "modules": modules}, 30.0)
        return int(reply["postures"])


def mock_camera(mock_arm: str | None = None, **options: Any) -> Camera:  # options: the camera's own
    """The ``mock`` camera back end: the rehearsal camera of a standalone mock controller when
    ``mock_arm`` is given, else the embedded station's simulated XB3 (:class:`~handeye.mocks.camera.MockCamera`)."""
    if mock_arm:
        return CellCamera(mock_arm, **options)
    from .camera import MockCamera

    return MockCamera(**options)
