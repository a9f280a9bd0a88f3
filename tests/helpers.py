"""Small builders shared by the tests."""

from __future__ import annotations

import ast
import sys
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from handeye.calibration.solve import problem_from_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session

from run_cache import shared_by_workers


REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
DATASETS = SHARED / "datasets"


def shared_dataset(name: str) -> Path:
    """Path of a data set in ../shared/datasets, or skip the test with the reason."""
    path = DATASETS / name
    if not path.is_dir():
        pytest.skip(f"data set {name} not available: ../shared/datasets is only beside a development checkout")
    return path


@contextmanager
def plugin_installed(monkeypatch, folder, modules=()):
    """A plug-in package installed for one test: ``folder`` (its ``.dist-info`` and modules) on
    ``sys.path`` and every registry reading its entry points again; afterwards the folder, its
    ``modules`` (imported names) and its entries are gone again."""
    from handeye.calibration.methods import METHODS
    from handeye.drivers.camera.backends import CAMERAS
    from handeye.drivers.controller.backends import CONTROLLERS

    registries = (METHODS, CONTROLLERS, CAMERAS)
    monkeypatch.syspath_prepend(str(folder))
    for registry in registries:
        registry.refresh()
    try:
        yield Path(folder)
    finally:
        monkeypatch.undo()
        for module in modules:
            sys.modules.pop(module, None)
        for registry in registries:
            registry.refresh()


@lru_cache(maxsize=None)
def scene(postures: int = 12, setup: str = "eye_in_hand", seed: int = 0):
    """A synthetic scene, built once per run: inverse kinematics makes one cost up to 0.2 s a posture,
    so the workers share it (:func:`shared_by_workers`) and each keeps it (the same object per process)."""
    config = SceneConfig(postures=postures, setup=setup, seed=seed)
    return shared_by_workers(f"scene-{postures}-{setup}-{seed}", lambda: make_scene(config))


def problem(postures=12, setup="eye_in_hand", sigma_cam=0.0, sigma_rob=0.0, seed=0, scene_seed=0):
    """(problem, truth dict, scene) drawn from a cached scene."""
    sc = scene(postures, setup, scene_seed)
    session = sample_session(sc, NoiseConfig(sigma_rob_deg=sigma_rob, sigma_cam_mm=sigma_cam, seed=seed))
    return problem_from_session(session), {"x": sc.x_true, "target2fixed": sc.target2fixed}, sc


class LinePeer:
    """A raw line-protocol peer of a mock controller (socket, or the serial mock's TCP stream), for
    what the client hides: ``ask("7 PING")`` sends one request line and returns the reply line."""

    def __init__(self, server):
        import socket

        self.sock = socket.create_connection((server.host, server.port), timeout=2)
        self.file = self.sock.makefile("rb")

    def ask(self, text: str) -> str:
        self.sock.sendall(text.encode("ascii") + b"\n")
        return self.file.readline().decode("ascii").rstrip("\n")

    def close(self) -> None:
        self.file.close()
        self.sock.close()


def flipped_board(prob, k: int):
    """``prob`` with posture ``k``'s board points turned 180 deg about the board's normal (in place):
    the points still fit a board, but the X-free angle invariant of AX = XB breaks at ``k``."""
    from scipy.spatial.transform import Rotation

    from handeye.calibration.compact_points import CompactPoints
    from handeye.calibration.problem import HandEyeProblem

    pts = prob.compact.points.copy()
    centre = pts[k].mean(axis=0)
    normal = np.cross(pts[k][1] - pts[k][0], pts[k][2] - pts[k][0])
    flip = Rotation.from_rotvec(np.pi * normal / np.linalg.norm(normal)).as_matrix()
    pts[k] = (pts[k] - centre) @ flip.T + centre
    c = prob.compact
    return HandEyeProblem(prob.setup, prob.hand, CompactPoints(pts, c.target_points, c.target2cam, c.plane_rms_mm),
                          pts, prob.posture_ids)


def assessed(problem, result, session_path="s", origin=None, **options):
    """``station.report.assessment.assess`` of a result solved in the test (no session folder needed; the
    origin is read from ``session_path`` when not given)."""
    from handeye.station.report.assessment import assess
    from handeye.station.calibrate import CalibrationOutcome

    return assess(CalibrationOutcome(session_path, result, problem=problem, origin=origin), **options)


def docstring_nodes(tree) -> set:
    """``id()`` of the string constants of ``tree`` that are docstrings (prose may name anything)."""
    nodes = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
                nodes.add(id(first.value))
    return nodes


def start_standalone_mock(*args: str, until: str = "camera.mock_arm:"):
    """``handeye mock controller ARGS --camera-port ...`` in its own process, once its banner is out (its
    line holding ``until``); returns ``(process, banner text)``."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "handeye.station", "mock", "controller", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    banner = []
    while not any(until in line for line in banner):
        line = proc.stdout.readline()
        if not line:
            raise AssertionError("the mock did not start: " + "".join(banner) + proc.stderr.read())
        banner.append(line)
    return proc, "".join(banner)


def start_mock_station(protocol: str, key: str, *args: str, duration_s: float = 600, pendant: bool = False):
    """A standalone mock controller on ``protocol`` with its camera (and, with ``pendant``, its pendant
    port) on free ports, at ``--time-scale 0.01``; ``args`` are more of its flags (``--config FILE``).

    Returns
    -------
    tuple
        ``(process, link section of a station config, camera.mock_arm, pendant HOST:PORT or None)``.
    """
    import re

    extra = ("--pendant-port", "0") if pendant else ()
    proc, text = start_standalone_mock("--protocol", protocol, "--port", "0", "--camera-port", "0", *extra,
                                       "--write-key", key, "--time-scale", "0.01", "--duration", f"{duration_s:g}",
                                       *args, until="pendant:" if pendant else "camera.mock_arm:")
    mock_arm = re.search(r"camera\.mock_arm: ([\d.]+:\d+)", text).group(1)
    address = re.search(r"STATE on ([\d.]+:\d+)", text).group(1) if pendant else None
    if protocol == "serial":
        link = {"serial_url": re.search(r"(socket://[\d.]+:\d+)", text).group(1)}
    else:
        link = {"host": "127.0.0.1", "port": int(re.search(r"listening on 127\.0\.0\.1:(\d+)", text).group(1))}
    return proc, link, mock_arm, address


def stop_standalone_mock(proc) -> str:
    """Stop a mock of :func:`start_standalone_mock` (if it still runs); its stderr."""
    import subprocess

    if proc.poll() is None:
        proc.terminate()
    try:
        return proc.communicate(timeout=30)[1]
    except subprocess.TimeoutExpired:  # pragma: no cover - a wedged mock
        proc.kill()
        return proc.communicate()[1]


def joint_path(nodes: np.ndarray, step_deg: float) -> np.ndarray:
    """The joint-interpolated moves through ``nodes`` (n, k), deg, sampled so that no axis turns more
    than ``step_deg`` between samples (both ends of every move included): the tests' own sweep."""
    samples = []
    for a, b in zip(nodes[:-1], nodes[1:]):
        n = max(2, int(np.ceil(np.max(np.abs(b - a)) / step_deg)) + 1)
        samples.append(a + np.linspace(0, 1, n)[:, None] * (b - a))
    return np.concatenate(samples)


def mock_station_config(folder: Path, name: str, base_yaml: str, faults: str = "") -> str:
    """``folder/name.yaml``: ``base_yaml`` (an embedded mock station's config) with, given ``faults``
    (flow mapping text), ``mock.faults`` added inside the ``mock:`` section ``base_yaml`` ends with, or a new one."""
    text = base_yaml
    if faults:
        text += ("" if ("\n" + base_yaml).count("\nmock:\n") else "mock:\n") + f"  faults: {{{faults}}}\n"
    path = Path(folder) / f"{name}.yaml"
    path.write_text(text)
    return str(path)


def mock_baseline(root: Path, config: str, *calibrate: str) -> Path:
    """``root/base``: a capture on the embedded mock station of ``config``, calibrated again with the
    ``calibrate`` options when given (e.g. ``--kinematics``), its tool data written back."""
    from handeye.station.cli import main

    session = Path(root) / "base"
    assert main(["capture", "--config", config, "--session", str(session), "--yes"]) == 0
    if calibrate:
        assert main(["calibrate", str(session), *calibrate, "--quiet"]) == 0
    assert main(["writeback", str(session), "--config", config]) == 0
    return session


def verify_against(root: Path, session: Path, config: str, name: str) -> tuple[int, dict]:
    """``handeye verify --config CONFIG --against SESSION --json root/name.json``: its exit code and JSON."""
    import json

    from handeye.station.cli import main

    out = Path(root) / f"{name}.json"
    code = main(["verify", "--config", config, "--against", str(session), "--json", str(out)])
    return code, json.loads(out.read_text())
