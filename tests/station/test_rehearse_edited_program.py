"""Rehearsing a program a station engineer edited: the generated HeMain with a MoveJ via point before the
first posture, a MoveL retreat (Offs) after each posture, a WaitDI on the cell door and an UNDO handler,
run by `handeye mock controller --program` in another process and driven by `capture` over real
sockets; the same program with a MoveL across a keep-out box stops at that line, naming the box."""

from __future__ import annotations

import json
import re
import shutil
import socket
import threading

import pytest
import yaml
from helpers import start_standalone_mock, stop_standalone_mock

from handeye.robot.kinematics import load_robot
from handeye.geometry.rotations import quaternion_from_matrix
from handeye.mocks.station import DEFAULT_START
from handeye.rapid.interpreter.configuration import confdata
from handeye.station.cli import main

BOX = {"type": "box", "name": "tool rack", "min_mm": [300, -600, 800], "max_mm": [460, -450, 1150]}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _via_point() -> str:
    """A taught robtarget 60 mm above where the arm stands at power-up (tool0, wobj0), with its confdata."""
    robot = load_robot("IRB1400")
    flange = robot.forward_transform(DEFAULT_START)
    p, q = flange[:3, 3] + [0.0, 0.0, 60.0], quaternion_from_matrix(flange[:3, :3])
    conf = confdata(robot, DEFAULT_START)
    return (f"[[{p[0]:.3f},{p[1]:.3f},{p[2]:.3f}],[{q[0]:.6f},{q[1]:.6f},{q[2]:.6f},{q[3]:.6f}],"
            f"[{conf[0]},{conf[1]},{conf[2]},{conf[3]}],[9E9,9E9,9E9,9E9,9E9,9E9]]")


def _edit(text: str, crossing: bool) -> str:
    """The engineer's edits of HeMain (each anchored on a line the generator writes)."""
    data = (f"  CONST robtarget pHeVia := {_via_point()};\n  VAR robtarget pHeHere;\n  VAR bool heBeenAt := FALSE;\n")
    # the crossing line turns axis 4 into another quadrant: the engineer switches the configuration check off
    cross = "      ConfL \\Off;\n      MoveL Offs(pHeVia, -300, -600, 0), v200, fine, tool0;\n" if crossing else ""
    head = ("  PROC HeGoPosture(num k)\n"
            "    SetDO doCellBusy, 1;\n"
            "    IF heBeenAt THEN\n"
            "      pHeHere := CRobT(\\Tool:=tool0 \\WObj:=wobj0);\n"
            "      MoveL Offs(pHeHere, 0, 0, 40), v200, fine, tool0;\n"
            "    ELSE\n"
            "      WaitDI diCellDoor, 1 \\MaxTime:=60;\n"
            "      MoveJ pHeVia, v500, z50, tool0;\n"
            f"{cross}"
            "    ENDIF\n"
            "    heBeenAt := TRUE;\n"
            "    TEST k\n")
    tail = "    ENDTEST\n    SetDO doCellBusy, 0;\n  UNDO\n    SetDO doCellBusy, 0;\n  ENDPROC\nENDMODULE"
    for old, new in (("  VAR num heTarget := 0;\n", "  VAR num heTarget := 0;\n" + data),
                     ("  PROC HeGoPosture(num k)\n    TEST k\n", head),
                     ("    ENDTEST\n  ENDPROC\nENDMODULE", tail)):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def _mock(program, config, port: int, camera_port: int):
    return start_standalone_mock("--protocol", "socket", "--port", str(port), "--camera-port", str(camera_port),
                                 "--time-scale", "0.01", "--duration", "600", "--config", str(config),
                                 *(["--program", str(program)] if program else []))[0]


_stop = stop_standalone_mock


def _cell(camera_port: int, request: dict) -> dict:
    with socket.create_connection(("127.0.0.1", camera_port), timeout=10) as sock:
        sock.sendall(json.dumps(request).encode() + b"\n")
        return json.loads(sock.makefile("rb").readline())


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """A rehearsal config with a keep-out box, and a session planned on it (`capture --plan-only`: the
    project's generator wrote SESSION/rapid)."""
    tmp = tmp_path_factory.mktemp("edited")
    port, camera_port = _free_port(), _free_port()
    config = tmp / "station.yaml"
    config.write_text(yaml.safe_dump({
        "controller": {"protocol": "socket", "host": "127.0.0.1", "port": port},
        "camera": {"backend": "mock", "mock_arm": f"127.0.0.1:{camera_port}"},
        "plan": {"postures": 8},
        "cell": {"keep_out": [{"type": "floor", "z_mm": 0}, BOX]},
    }))
    proc = _mock(None, config, port, camera_port)
    try:
        session = tmp / "plan"
        assert main(["capture", "--config", str(config), "--session", str(session), "--plan-only"]) == 0
    finally:
        _stop(proc)
    return config, session, port, camera_port


def _edited_session(tmp_path, planned, crossing: bool):
    config, plan, port, camera_port = planned
    session = tmp_path / "s"
    shutil.copytree(plan, session)
    main_mod = session / "rapid" / "HeMain.mod"
    main_mod.write_text(_edit(main_mod.read_text(), crossing))
    return config, session, port, camera_port


def test_an_edited_program_runs_in_the_mock_and_capture_passes(tmp_path, planned, capsys):
    config, session, port, camera_port = _edited_session(tmp_path, planned, crossing=False)
    capsys.readouterr()
    proc = _mock(session / "rapid", config, port, camera_port)
    try:
        # the door is open: the program's WaitDI holds the first move until the cell port closes it
        assert _cell(camera_port, {"cmd": "signal", "name": "diCellDoor", "value": 0})["ok"]
        closer = threading.Timer(1.0, _cell, (camera_port, {"cmd": "signal", "name": "diCellDoor", "value": 1}))
        closer.start()
        assert main(["capture", "--config", str(config), "--session", str(session), "--yes"]) == 0
        closer.join()
        out = capsys.readouterr().out
        assert "8 of 8 postures" in out, out
        assert main(["calibrate", str(session)]) == 0
    finally:
        err = _stop(proc)
    assert "stopped on an error" not in err, err


def test_the_same_program_with_a_movel_across_the_box_stops_at_that_line(tmp_path, planned, capsys):
    config, session, port, camera_port = _edited_session(tmp_path, planned, crossing=True)
    line = 1 + (session / "rapid" / "HeMain.mod").read_text().split("\n").index(
        "      MoveL Offs(pHeVia, -300, -600, 0), v200, fine, tool0;")
    proc = _mock(session / "rapid", config, port, camera_port)
    try:
        assert main(["capture", "--config", str(config), "--session", str(session), "--yes"]) == 1
        proc.wait(timeout=120)  # the mock ends by itself on the program's error
    finally:
        err = _stop(proc)
    message = re.search(r"RAPID program stopped on an error: (.*)", err)
    assert message, err
    assert message.group(1).startswith(f"HeMain.mod:{line}: MoveL: world zone: ") and "'tool rack'" in message.group(1)
    assert proc.returncode == 1
