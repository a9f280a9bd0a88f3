"""A shared (serial) line quiet for the controller's idle timeout: the program clears its input buffer
each idle timeout while nothing arrives, and a clear that falls as a request arrives discards it. The
client wakes such a line with a PING, sent again until it is answered, before the request itself.

A scripted line stands in for the controller here, so the discarded line is certain, not a race."""

from __future__ import annotations

import time

import numpy as np
import pytest

from handeye.drivers.controller import ControllerTimeout
from handeye.drivers.controller import protocol as P
from handeye.drivers.controller.line_client import LineController, LineTransport

IDLE = 0.2
JOINTS = (1.5, -2.0, 3.0, 0.0, 45.0, 90.0)


class ScriptedLine(LineTransport):
    """The program's side of a serial line: answers PING, VERSION, COUNT and JOINTS; discards the
    ``discard`` next lines it receives (as its buffer clear does) once armed."""

    shared_line = True

    def __init__(self):
        self.open_ = False
        self.received: list[str] = []
        self.replies: list[bytes] = []
        self.discard = 0

    def open(self, deadline):
        self.open_ = True

    def close(self):
        self.open_ = False

    @property
    def is_open(self):
        return self.open_

    def write(self, data, deadline):
        for raw in data.split(b"\n"):
            if not raw.strip():
                continue
            request = P.parse_request(raw + b"\n")
            self.received.append(request.command)
            if self.discard:
                self.discard -= 1
                continue
            values = {"PING": (), "VERSION": (P.PROTOCOL_VERSION, "HANDEYE"), "COUNT": (3,), "JOINTS": JOINTS}
            self.replies.append(P.encode_ok(request, *values[request.command]))

    def read_line(self, deadline):
        while not self.replies:
            if deadline.remaining() <= 0:
                raise ControllerTimeout("timed out")
            time.sleep(min(0.005, deadline.remaining()))
        return self.replies.pop(0)


class ScriptedController(LineController):
    protocol = "serial"

    def __init__(self, line, **options):
        self.line = line
        super().__init__(**options)

    @property
    def address(self):
        return "scripted line"

    def _make_transport(self):
        return self.line


@pytest.fixture
def line():
    return ScriptedLine()


def test_a_request_after_the_idle_timeout_is_answered_though_its_first_line_was_discarded(line):
    with ScriptedController(line, timeout=2.0, idle_timeout=IDLE) as c:
        assert np.allclose(c.read_joints(), JOINTS)
        time.sleep(IDLE + 0.05)
        line.discard = 1  # the buffer clear takes the next line that arrives
        line.received.clear()
        assert np.allclose(c.read_joints(), JOINTS)
        assert line.received == ["PING", "PING", "JOINTS"]  # the wake PING lost, sent again, then the request


def test_a_request_within_the_idle_timeout_goes_out_alone(line):
    with ScriptedController(line, timeout=2.0, idle_timeout=5.0) as c:
        c.read_joints()
        line.received.clear()
        c.read_joints()
        assert line.received == ["JOINTS"]


def test_a_line_that_never_answers_still_times_out_within_the_budget(line):
    with ScriptedController(line, timeout=1.0, idle_timeout=IDLE) as c:
        c.read_joints()
        time.sleep(IDLE + 0.05)
        line.discard = 10**6
        start = time.monotonic()
        with pytest.raises(ControllerTimeout, match="no reply"):
            c.read_joints()
        assert time.monotonic() - start < 1.0 + 2.0  # the call's budget (a functional bound, not a speed)
        assert line.received.count("PING") >= 3  # sent again every idle timeout / 2
