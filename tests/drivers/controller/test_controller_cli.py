"""The commands: handeye robot joints/status, handeye mock controller, handeye rapid generate."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.station.cli import main


def _link_args(server):
    if server.protocol == "serial":
        return ["--protocol", "serial", "--url", server.url]
    if server.protocol == "rws":
        options = server.client_options()
        pin = ["--tls-fingerprint", options["tls_fingerprint"]] if "tls_fingerprint" in options else []
        return ["--protocol", "rws", "--host", server.host, "--port", str(server.port), "--user", options["username"],
                "--password", options["password"], *pin]
    return ["--protocol", server.protocol, "--host", server.host, "--port", str(server.port)]


def test_robot_joints_json(server, capsys):
    server.robot.start_posture(3)  # moved behind the program's back (jogged)
    server.robot.wait_until_stopped(timeout=5)
    if server.protocol == "modbus":  # HeIo publishes the joints every 0.1 s (its timer interrupt)
        time.sleep(0.25)
    assert main(["robot", "joints", *_link_args(server), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"joints_deg", "tool0_in_base"}
    assert set(data["tool0_in_base"]) == {"position_mm", "quaternion_wxyz"}
    truth = server.robot.postures[2]
    assert np.allclose(data["joints_deg"], truth, atol=1e-4)
    p, q = load_robot("IRB1400").forward(truth)
    assert np.allclose(data["tool0_in_base"]["position_mm"], p, atol=1e-3)
    assert np.allclose(data["tool0_in_base"]["quaternion_wxyz"], q, atol=2e-6)


def test_robot_status_text(server, capsys):
    assert main(["robot", "status", *_link_args(server)]) == 0
    out = capsys.readouterr().out
    assert "12 approved postures" in out
    if server.protocol == "rws":
        assert f"controller: motoron, mode AUTO, RAPID running, RobotWare {server.robotware}" in out


@pytest.mark.parametrize("link", ["socket", "modbus", "rws"])
def test_robot_unreachable_is_one_line_without_traceback(capsys, link):
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    assert main(["robot", "joints", "--protocol", link, "--port", str(port), "--timeout", "0.5"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and str(port) in err


def test_robot_serial_needs_a_url(capsys):
    assert main(["robot", "joints", "--protocol", "serial"]) == 1
    assert "--url" in capsys.readouterr().err


@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus", "rws"])
def test_mock_controller_in_process(protocol, capsys):
    assert main(["mock", "controller", "--protocol", protocol, "--port", "0", "--duration", "0.2"]) == 0
    out = capsys.readouterr().out
    assert f"mock {protocol} controller" in out and "stopped" in out
    assert ("socket://127.0.0.1:" in out) if protocol == "serial" else ("listening on 127.0.0.1:" in out)


def test_mock_controller_runs_until_ctrl_c():
    # A shell starts background jobs with SIGINT ignored, and a child inherits that: Python then
    # installs no KeyboardInterrupt handler and Ctrl-C never arrives. The child gets the default
    # disposition back, so the test behaves the same whether the suite runs in front or behind.
    proc = subprocess.Popen([sys.executable, "-c", "from handeye.station.cli import main; raise SystemExit(main())",
                             "mock", "controller", "--protocol", "socket", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        banner = proc.stdout.readline()
        assert "listening on 127.0.0.1:" in banner, banner + proc.stderr.read()
        port = int(banner.split("127.0.0.1:")[1].split(";")[0])
        from handeye.drivers.controller import open_controller

        with open_controller("socket", host="127.0.0.1", port=port, timeout=2) as c:
            assert c.info().postures == 12
        time.sleep(0.1)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)  # generous: a loaded 2-core machine starts and stops slowly
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "stopped" in out and "Traceback" not in err


def test_rapid_generate(tmp_path, capsys):
    assert main(["rapid", "generate", "-o", str(tmp_path / "out")]) == 0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    assert main(["rapid", "generate", "-o", str(tmp_path / "io"), "--protocol", "modbus"]) == 0
    assert (tmp_path / "io" / "HeIo.mod").is_file()
    capsys.readouterr()
    config = tmp_path / "station.yaml"
    config.write_text("postures: [[0, 0, 0, 0, 30, 0], [0, 90, 0, 0, 0, 0]]\n")
    assert main(["rapid", "generate", "--config", str(config), "-o", str(tmp_path / "bad")]) == 1
    err = capsys.readouterr().err
    assert "posture 2: axis 2 = 90.0000 deg outside [-70, 70]" in err and err.count("\n") == 1
    assert not (tmp_path / "bad").exists()  # nothing written
