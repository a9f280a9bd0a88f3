"""Stops a test run at once, with one line saying what to do, when ``handeye`` is not installed.

The rooms (``calibration/``, ``drivers/`` ...) import as ``handeye.<room>`` only once the package
is installed (``setup.py`` maps them); a plain checkout would otherwise fail in every test file.
"""

import os

import pytest

try:
    import handeye.calibration  # noqa: F401
except ImportError as exc:
    pytest.exit(f"handeye is not importable ({exc}): install it first, from the repository folder: "
                'pip install -e ".[test]"', returncode=4)


def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker more than the cores (up to 4 cores; as many as the cores beyond). Many
    tests wait on a socket, a mock in another process or a timeout, and a worker that waits leaves its
    core idle; one more keeps both cores of a small machine busy. ``PYTEST_XDIST_AUTO_NUM_WORKERS`` or
    ``-n N`` set the number instead (fewer on a heavily loaded machine)."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return cores + 1 if cores <= 4 else cores
