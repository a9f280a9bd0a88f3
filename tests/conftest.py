"""Shared test fixtures, and how the property-based tests draw their cases.

The hypothesis tests (fuzzed readers, codecs) draw the same cases on every run by default, so the
suite that gates a change passes or fails on the code, not on the luck of a draw. To explore new
cases (and find what a fixed draw never reaches), run them with ``HANDEYE_FUZZ=explore``; a failure
prints its reproduction blob.
"""

from __future__ import annotations

import os
import threading
import time

import pytest
from hypothesis import settings

settings.register_profile("gate", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("explore" if os.environ.get("HANDEYE_FUZZ") == "explore" else "gate")


@pytest.fixture
def no_leaked_threads():
    """Fail the test if it leaves threads running."""
    before = set(threading.enumerate())
    yield
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        extra = [t for t in threading.enumerate() if t not in before and t.is_alive()]
        if not extra:
            return
        time.sleep(0.02)
    pytest.fail(f"test leaked threads: {[t.name for t in extra]}")


class _NoPause:
    """The ``time`` module with a ``sleep`` that returns at once."""

    def __getattr__(self, name):
        return getattr(time, name)

    @staticmethod
    def sleep(seconds):
        return None


@pytest.fixture(autouse=True, scope="session")
def _no_pause_when_a_serial_socket_closes():
    """pyserial's ``socket://`` port sleeps 0.3 s in ``close()`` ("in case of quick reconnects, give the
    server some time"). The mock serial line needs no such pause (a new connection takes the line over
    at once) and the suite closes hundreds of serial links: without it they reconnect as fast as they can.
    """
    try:
        from serial.urlhandler import protocol_socket
    except ImportError:
        yield
        return
    real, protocol_socket.time = protocol_socket.time, _NoPause()
    yield
    protocol_socket.time = real
