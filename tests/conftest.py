"""Shared test fixtures, and how the property-based tests draw their cases.

The hypothesis tests (fuzzed readers, codecs) draw the same cases on every run by default, so the
suite that gates a change passes or fails on the code, not on the luck of a draw. To explore new
cases (and find what a fixed draw never reaches), run them with ``HANDEYE_FUZZ=explore``; a failure
prints its reproduction blob.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import threading
import time

import pytest
from hypothesis import settings

from run_cache import RUN_CACHE

FUZZ_PROFILE = "explore" if os.environ.get("HANDEYE_FUZZ") == "explore" else "gate"
settings.register_profile("gate", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(FUZZ_PROFILE)


def _pin_the_local_constants() -> None:
    """Keep hypothesis from drawing the literals of whatever local modules a worker has loaded.

    Besides its own seeded choices, hypothesis (6.131 and later) sometimes draws a literal taken from
    the source of the local modules in ``sys.modules`` at that moment. Which of the package's modules
    a worker has imported depends on the tests it ran before, so with a fixed seed a fuzz test still
    drew other cases in another order or selection. The gate profile draws from no local literals;
    the explore profile keeps hypothesis' own behaviour. (A private hook of hypothesis:
    ``tests/test_fuzz_profile.py`` fails if it stops working.)
    """
    try:
        from hypothesis.internal.conjecture import providers
        empty = providers.Constants()
    except (ImportError, AttributeError):
        return
    if hasattr(providers, "_get_local_constants"):
        providers._get_local_constants = lambda: empty


if FUZZ_PROFILE == "gate":
    _pin_the_local_constants()


#: The run's folder, in the stash of the process that made it.
_RUN_FOLDER = pytest.StashKey[str]()


def pytest_configure(config):
    """The folder the workers of this run share their deterministic builds in (``run_cache``): made by
    the controlling process (or the only one, without xdist) before the workers start, so they inherit
    it in their environment; removed when the run ends."""
    if hasattr(config, "workerinput") or os.environ.get(RUN_CACHE):
        return
    config.stash[_RUN_FOLDER] = os.environ[RUN_CACHE] = tempfile.mkdtemp(prefix="handeye-test-run-")


def pytest_unconfigure(config):
    folder = config.stash.get(_RUN_FOLDER, None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)
        os.environ.pop(RUN_CACHE, None)


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
