"""Shared test fixtures."""

from __future__ import annotations

import threading

import pytest


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
