"""A real RWS 1.0 client against the mock: PyPI's ``abb-robot-client`` (used in research labs) reads
joints and robtarget, reads and writes RAPID data (a num array that drives HeRws, the tooldata),
uploads a file and stops, resets and starts execution. What it reads is checked against the
simulated arm and the interpreted program's data, so a mock answering the wrong shape fails here."""

from __future__ import annotations

import time

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.mocks.controller import start_mock_controller
from handeye.mocks.controller.runner import tooldata_of

rws_module = pytest.importorskip("abb_robot_client.rws")


@pytest.fixture
def mock_and_client():
    with start_mock_controller("rws", generation=1, time_scale=0.002, ack_timeout_s=None) as server:
        client = rws_module.RWS(f"http://127.0.0.1:{server.port}")  # its defaults: Default User / robotics
        try:
            yield server, client
        finally:
            client._session.close()


def _wait(condition, seconds=5.0):
    end = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > end:
            return False
        time.sleep(0.01)
    return True


def test_joints_and_robtarget(mock_and_client):
    server, client = mock_and_client
    server.robot.start_posture(4)
    server.robot.wait_until_stopped(timeout=5)
    truth = server.robot.postures[3]
    joints = client.get_jointtarget()
    assert np.allclose(joints.robax, truth, atol=1e-5)
    target = client.get_robtarget()
    p, q = load_robot("IRB1400").forward(truth)
    assert np.allclose(target.trans, p, atol=1e-4)
    assert np.allclose(target.rot, q, atol=1e-7)
    assert client.get_controller_state() == "motoron"
    assert client.get_operation_mode() == "AUTO"


def test_rapid_variables_drive_the_program_and_write_the_tooldata(mock_and_client):
    server, client = mock_and_client
    # a num array of HeRws: the third-party client asks for posture 2 and the interpreted RAPID moves there
    assert client.get_rapid_variable("heRwsLink") == "[0,0,0,12,1]"
    client.set_rapid_variable("heRwsPc", "[2,0]")
    assert _wait(lambda: client.get_rapid_variable("heRwsLink").startswith("[2,2,"))  # AT posture 2
    assert np.allclose(server.robot.current_joints, server.robot.postures[1])
    assert client.get_rapid_variable("hePosture") == "2"  # a plain num (VAR of HeMain)
    # the camera's tooldata, by symbol
    literal = "[TRUE,[[12.5,-3.25,88],[0.5,0.5,-0.5,0.5]],[1.4,[0,10,70],[1,0,0,0],0,0,0]]"
    client.set_rapid_variable("tHeCamera", literal)
    stored = tooldata_of(server.symbol_value("tHeCamera"))
    assert stored.position_mm == (12.5, -3.25, 88.0) and stored.mass_kg == pytest.approx(1.4)
    assert client.get_rapid_variable("tHeCamera") == literal  # each num the shortest text of its float32


def test_upload_file_and_start_stop_execution(mock_and_client):
    server, client = mock_and_client
    text = b"MODULE HeNote\n  ! uploaded by abb-robot-client\nENDMODULE\n"
    client.upload_file("$HOME/HeNote.mod", text)
    assert server.files["$HOME/HeNote.mod"] == text
    assert client.read_file("$HOME/HeNote.mod") == text
    assert client.get_execution_state().ctrlexecstate == "running"
    client.stop()
    assert not server.running and client.get_execution_state().ctrlexecstate == "stopped"
    client.resetpp()
    client.start()
    assert server.running and client.get_execution_state().ctrlexecstate == "running"
    assert client.get_rapid_variable("heRwsLink") == "[0,0,0,12,1]"  # READY again, from main
