"""The mock's pendant port as a careless or hostile client meets it: an over-long line is one request,
refused whole (its tail never runs), and a client that hangs up early leaves no traceback behind."""

from __future__ import annotations

import socket
import struct
import time
from types import SimpleNamespace

import numpy as np
import pytest

from handeye.mocks.controller.pendant import MAX_LINE, PendantService
from handeye.mocks.robot import SimulatedRobot


@pytest.fixture
def port():
    robot = SimulatedRobot(np.zeros((1, 6)), time_scale=0.01)
    service = PendantService(SimpleNamespace(robot=robot, program=None, flexpendant=SimpleNamespace(prompt=None, stopped=False, last_line="-"))).start()
    try:
        yield service, robot
    finally:
        service.stop()


def _ask(service, data: bytes, replies: int = 1) -> list[str]:
    with socket.create_connection((service.host, service.port), timeout=10) as sock:
        sock.sendall(data)
        stream = sock.makefile("rb")
        return [stream.readline().decode().strip() for _ in range(replies)]


@pytest.mark.parametrize("pad", [MAX_LINE - len("JOG 10 0 0 0 0 0") + 1, MAX_LINE, 5 * MAX_LINE + 7])
def test_an_over_long_line_is_refused_whole_and_its_tail_never_moves_the_arm(port, pad):
    service, robot = port
    before = robot.current_joints.copy()
    replies = _ask(service, b"X" * pad + b"JOG 10 0 0 0 0 0\nSTATE\n", replies=2)
    assert replies[0].startswith("ERR request line longer than"), replies
    assert replies[1].startswith("OK none"), replies  # the next line is the next request
    assert np.array_equal(robot.current_joints, before)


def test_a_line_of_the_longest_length_taken_is_served(port):
    service, robot = port
    request = b"JOG 10 0 0 0 0 0"
    line = request + b" " * (MAX_LINE - len(request))  # exactly MAX_LINE bytes before the newline
    assert _ask(service, line + b"\n")[0].startswith("OK 10.0000")
    assert robot.current_joints[0] == pytest.approx(10.0)


def test_a_client_that_hangs_up_early_leaves_no_traceback(port, capfd):
    service, _ = port
    for _ in range(3):
        sock = socket.create_connection((service.host, service.port), timeout=10)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # reset, not a clean close
        sock.sendall(b"JOG 40 0 0 0 0 0\n")  # the reply comes once the arm stands still: after the hang-up
        sock.close()
    time.sleep(1.0)
    assert _ask(service, b"STATE\n")[0].startswith("OK ")  # the port still serves
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Exception occurred" not in err, err


def test_the_pendant_command_plays_the_operator_without_nc(port, capsys):
    """``handeye mock pendant``: each request a line, each reply printed; ERR gives exit 1."""
    from handeye.station.cli import main

    service, robot = port
    assert main(["mock", "pendant", "--port", str(service.port), "STATE", "JOG 12 0 0 0 0 0"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("OK none") and out[1].startswith("OK 12.0000"), out
    assert robot.current_joints[0] == pytest.approx(12.0)
    assert main(["mock", "pendant", "--port", str(service.port), "JOG 1 2"]) == 1
    assert capsys.readouterr().out.startswith("ERR JOG takes 6 axis angles")


def test_the_pendant_command_reads_requests_from_stdin(port, capsys, monkeypatch):
    import io

    from handeye.station.cli import main

    service, robot = port
    monkeypatch.setattr("sys.stdin", io.StringIO("JOG 0 5 0 0 0 0\n\nSTATE\n"))
    assert main(["mock", "pendant", "--port", str(service.port), "-"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and out[1].startswith("OK none"), out
    assert robot.current_joints[1] == pytest.approx(5.0)


def test_the_pendant_command_says_what_to_do_when_nothing_listens(capsys):
    from handeye.station.cli import main

    with socket.socket() as sock:  # a port that was free a moment ago: nothing listens there
        sock.bind(("127.0.0.1", 0))
        free = sock.getsockname()[1]
    assert main(["mock", "pendant", "--port", str(free), "STATE"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--pendant-port" in err[0] and "Traceback" not in err[0], err


def test_the_mock_controller_help_prints_its_examples_on_one_line_each(capsys):
    """The epilog's example request is one command line (it printed a literal line break inside
    ``printf 'STATE``), needs no ``nc`` and says what a restart loses."""
    from handeye.station.cli import main

    with pytest.raises(SystemExit):
        main(["mock", "controller", "--help"])
    text = capsys.readouterr().out
    assert "handeye mock pendant --port 5022 STATE" in text
    assert "nc " not in text and not any(line.strip().startswith("' |") for line in text.splitlines())
    assert "restart resets" in text and "faults" in text


def test_the_pendant_command_says_so_when_the_port_never_replies(capsys, monkeypatch):
    """A listener that accepts and says nothing: one line, exit 1, after the reply bound."""
    import handeye.station.commands.mock as mock_command
    from handeye.station.cli import main

    monkeypatch.setattr(mock_command, "PENDANT_REPLY_S", 0.3)
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(1)
        assert main(["mock", "pendant", "--port", str(silent.getsockname()[1]), "STATE"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did not reply within 0.3 s" in err[0], err
