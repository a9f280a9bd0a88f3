"""Shared test fixtures, and how the property-based tests draw their cases.

The hypothesis tests (fuzzed readers, codecs) draw the same cases on every run by default, so the
suite that gates a change passes or fails on the code, not on the luck of a draw. To explore new
cases (and find what a fixed draw never reaches), run them with ``HANDEYE_FUZZ=explore``; a failure
prints its reproduction blob.
"""

from __future__ import annotations

import os
import threading

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
    import time

    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        extra = [t for t in threading.enumerate() if t not in before and t.is_alive()]
        if not extra:
            return
        time.sleep(0.02)
    pytest.fail(f"test leaked threads: {[t.name for t in extra]}")
