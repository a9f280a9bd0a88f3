"""No session made against a mock is ever recorded or reported as real (issue 40.1): every capture path
(planned, guided by the pendant program, guided by the joints, verify and its quick update) against the
standalone `handeye mock controller` over every link (socket, serial, Modbus, Robot Web Services) and on
the embedded mock records ``capture.station: mock``; ``calibrate`` says MOCK SESSION (its JSON
``"station": "mock"``); and ``writeback`` with a real station's config refuses every one of them
before it opens a link."""

from __future__ import annotations

import json
import threading
import time

import numpy as np
import pytest
import yaml
from helpers import start_mock_station, stop_standalone_mock

from handeye.calibration.session import read_session
from handeye.station.cli import main
from handeye.station.config.station import load_config
from handeye.station.guided.capture import guided_capture
from handeye.station.origin import session_origin
from pendant_operator import PendantClient, PendantOperator
from handeye.station.runtime import open_station

KEY = "never-real_40"
PLANNED = 14
GUIDED = 3
#: A real station (nothing listens at port 1): writeback must refuse before it tries to connect.
REAL_STATION = {"controller": {"protocol": "socket", "host": "127.0.0.1", "port": 1, "timeout_s": 0.5, "write_key": KEY},
                "camera": {"backend": "xb3"}}
#: The camera moved on the flange (what verify's quick update answers).
CAMERA_MOVED = {"camera_shift_mm": [0.9, -0.8, 0.6], "camera_turn_deg": [0.05, -0.08, 0.1]}


def _start_mock(protocol: str, config):
    """`handeye mock controller` with its camera and pendant ports; (process, link section, mock_arm, pendant)."""
    return start_mock_station(protocol, KEY, "--config", str(config), duration_s=900, pendant=True)


def _rehearsal(folder, name: str, protocol: str, faults=None):
    """A standalone mock (with ``mock.faults``) and the rehearsal config that drives it."""
    base = {"controller": {"protocol": protocol, "write_key": KEY}, "camera": {"backend": "xb3"},
            "plan": {"postures": PLANNED}, "guided": {"operator_timeout_s": 120, "still_s": 0.3, "poll_s": 0.03},
            **({"mock": {"faults": faults}} if faults else {})}
    (folder / f"{name}-mock.yaml").write_text(yaml.safe_dump(base))
    proc, link, mock_arm, pendant = _start_mock(protocol, folder / f"{name}-mock.yaml")
    config = folder / f"{name}.yaml"
    config.write_text(yaml.safe_dump({**{k: v for k, v in base.items() if k != "mock"},
                                      "controller": {**base["controller"], **link},
                                      "camera": {"backend": "mock", "mock_arm": mock_arm}}))
    return proc, config, pendant


def _jog_through(pendant: str, poses, captured: list, stop: threading.Event) -> threading.Thread:
    """The operator of the joint-watching loop: jog with the pendant to each pose, wait for its capture."""
    def run():
        client = PendantClient(pendant)
        try:
            for target in poses:
                before = len(captured)
                assert client.jog(target).startswith("OK")
                deadline = time.monotonic() + 60
                while len(captured) == before and time.monotonic() < deadline:
                    time.sleep(0.02)
        finally:
            client.close()
            stop.set()
    thread = threading.Thread(target=run, name="jogging-operator")
    thread.start()
    return thread


def _guided(protocol: str, config, pendant: str, session, plan, capsys) -> str:
    """The guided capture the link runs: the pendant program over a line or Modbus, the joints over RWS."""
    if protocol == "rws":
        captured, stop = [], threading.Event()
        with open_station(load_config(config)) as link:
            operator = _jog_through(pendant, plan[:GUIDED], captured, stop)
            guided_capture(load_config(config), session, link, on_posture=captured.append, stop=stop)
            operator.join()
        assert len(captured) == GUIDED
        return "joints"
    operator = PendantOperator(pendant, plan[:GUIDED], lambda message: None)
    operator.start()
    rc = main(["capture", "--config", str(config), "--session", str(session), "--guided"])
    assert operator.join(120) and operator.error is None, operator.error
    out = capsys.readouterr().out
    assert rc == 0, out
    assert all(line.startswith("MOCK") for line in out.splitlines() if line.strip()), out
    return "pendant"


def _reported_mock(session, capsys) -> None:
    """``calibrate`` says MOCK SESSION in its text and ``"station": "mock"`` in its JSON."""
    out = session.parent / f"{session.name}-calibration.json"
    main(["calibrate", str(session), "--json", str(out)])
    assert "MOCK SESSION" in capsys.readouterr().out
    assert json.loads(out.read_text())["station"] == "mock"


def _refused_by_a_real_controller(tmp_path, session, capsys) -> None:
    real = tmp_path / "real.yaml"
    real.write_text(yaml.safe_dump(REAL_STATION))
    capsys.readouterr()
    assert main(["writeback", str(session), "--config", str(real), "--force"]) == 1
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "not your robot's" in err[0] and "mock station" in err[0], captured.err
    assert "Traceback" not in captured.err and "read back" not in captured.out


@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus", "rws"])
def test_every_path_over_every_link_is_mock_and_never_written_to_a_real_robot(tmp_path, capsys, protocol):
    proc, config, pendant = _rehearsal(tmp_path, "rehearsal", protocol)
    try:
        planned = tmp_path / "planned"
        assert main(["capture", "--config", str(config), "--session", str(planned), "--yes"]) == 0
        plan = np.array(read_session(planned).extra["capture"]["plan_joints_deg"], float)
        guided = tmp_path / "guided"
        loop = _guided(protocol, config, pendant, guided, plan, capsys)
        assert read_session(guided).extra["capture"]["mode"] == "guided"
        assert (loop == "pendant") == (guided / "rapid" / "HeGuide.mod").is_file()
    finally:
        stop_standalone_mock(proc)
    proc, moved, _ = _rehearsal(tmp_path, "moved", protocol, CAMERA_MOVED)
    try:  # SESSION's tool data on the controller of the check, so that its finding is the camera alone
        assert main(["writeback", str(planned), "--config", str(moved), "--force"]) == 0
        capsys.readouterr()
        main(["verify", "--config", str(moved), "--against", str(planned), "--yes", "--postures", "5",
              "--json", str(tmp_path / "check.json")])
        out = capsys.readouterr().out
        assert all(line.startswith("MOCK") for line in out.splitlines() if line.strip()), out
    finally:
        stop_standalone_mock(proc)
    _all_mock_and_refused(tmp_path, planned, guided, capsys)


def test_every_path_on_the_embedded_mock_is_mock_and_never_written_to_a_real_robot(tmp_path, capsys):
    base = {"controller": {"protocol": "mock", "write_key": KEY}, "camera": {"backend": "mock"},
            "plan": {"postures": PLANNED}, "guided": {"still_s": 0.3, "poll_s": 0.03}, "mock": {"time_scale": 0.005}}
    config, moved = tmp_path / "mock.yaml", tmp_path / "moved.yaml"
    config.write_text(yaml.safe_dump(base))
    moved.write_text(yaml.safe_dump({**base, "mock": {**base["mock"], "faults": CAMERA_MOVED}}))
    planned, guided = tmp_path / "planned", tmp_path / "guided"
    assert main(["capture", "--config", str(config), "--session", str(planned), "--yes"]) == 0
    assert main(["capture", "--config", str(config), "--session", str(guided), "--guided", "--postures", str(GUIDED)]) == 0
    assert main(["writeback", str(planned), "--config", str(config), "--force"]) == 0
    capsys.readouterr()
    main(["verify", "--config", str(moved), "--against", str(planned), "--yes", "--json", str(tmp_path / "check.json")])
    out = capsys.readouterr().out
    assert all(line.startswith("MOCK") for line in out.splitlines() if line.strip()), out
    _all_mock_and_refused(tmp_path, planned, guided, capsys)


def _all_mock_and_refused(tmp_path, planned, guided, capsys) -> None:
    """The planned, the guided and the check's session (its quick update) are mock, said so, and refused."""
    check = json.loads((tmp_path / "check.json").read_text())
    folder = tmp_path / check["check_session"]
    assert check["quick_update"] is not None, check  # the camera moved: the check's folder is a quick update too
    for session in (planned, guided, folder):
        assert read_session(session).extra["capture"]["station"] == "mock", session
        assert session_origin(read_session(session)) == "mock"
        _refused_by_a_real_controller(tmp_path, session, capsys)
    for session in (planned, guided):
        _reported_mock(session, capsys)
