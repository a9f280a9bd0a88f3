"""Shared test fixtures."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
DATASETS = SHARED / "datasets"


def shared_dataset(name: str) -> Path:
    """Path of a data set in ../shared/datasets, or skip the test with the reason."""
    path = DATASETS / name
    if not path.is_dir():
        pytest.skip(f"data set {name} not available: ../shared/datasets is only beside a development checkout")
    return path


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
