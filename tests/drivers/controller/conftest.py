"""Fixtures of the controller-link tests: mock servers of every back end, leak checks."""

from __future__ import annotations

import os
import time

import pytest

from handeye.drivers.controller import open_controller
from handeye.mocks.backends import mock_variants
from handeye.mocks.controller import start_mock_controller

#: Every controller back end a mock serves (the registry's, so a new back end is tested here at once),
#: each variant of its mock included (RWS 1.0 and RWS 2.0 are both ``rws``).
PROTOCOLS = mock_variants()
#: Wall-clock seconds per simulated second of motion in tests (moves take a few ms).
TIME_SCALE = 0.002
#: The write key of the test servers (their client_options() carry it to the clients).
TEST_KEY = "test-key_0123"


def _open_sockets() -> set:
    """Inodes of the sockets this process holds open (Linux /proc)."""
    out = set()
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.startswith("socket:"):
            out.add(target)
    return out


@pytest.fixture
def no_leaked_sockets():
    """Fail the test if it leaves sockets open (waits up to 2 s for them to close)."""
    if not os.path.isdir("/proc/self/fd"):
        pytest.skip("socket leak check needs /proc (Linux)")
    before = _open_sockets()
    yield
    deadline = time.monotonic() + 2.0
    while True:
        extra = _open_sockets() - before
        if not extra or time.monotonic() > deadline:
            break
        time.sleep(0.02)
    if extra:
        pytest.fail(f"test leaked {len(extra)} socket(s): {sorted(extra)}")


@pytest.fixture(autouse=True)
def _no_leaks(no_leaked_threads, no_leaked_sockets):
    """Every test in this folder runs under both leak checks (set up before, torn down after the servers)."""
    yield


@pytest.fixture(params=PROTOCOLS, ids=[getattr(p, "label", p) for p in PROTOCOLS])
def protocol(request):
    return request.param


@pytest.fixture
def server(protocol):
    """A started mock controller of ``protocol`` (fast motion)."""
    with start_mock_controller(protocol, time_scale=TIME_SCALE, ack_timeout_s=None, write_key=TEST_KEY) as srv:
        yield srv


def connect(server, **options):
    """A connected client for ``server`` (same back end), with test-friendly defaults."""
    settings = {"timeout": 1.0, "motion_timeout": 10.0, "backoff_s": 0.02}
    settings = {**server.client_options(), **settings, **options}
    return open_controller(server.protocol, **settings)


@pytest.fixture
def connect_to():
    """``connect_to(server, **options)``: a connected client of the server's back end."""
    return connect


@pytest.fixture
def controller(server):
    with connect(server) as c:
        yield c
