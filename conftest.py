"""Stops a test run at once, with one line saying what to do, when ``handeye`` is not installed.

The rooms (``calibration/``, ``drivers/`` ...) import as ``handeye.<room>`` only once the package
is installed (``setup.py`` maps them); a plain checkout would otherwise fail in every test file.
"""

import os

# The suite's parallelism is pytest-xdist's: one worker process per core (and one more). Thread pools
# inside the libraries would only oversubscribe the cores, and OpenCV's spins: on a loaded 2-core machine
# cv2.stereoCalibrate took 4 s instead of 0.02 s with its default two threads. So every worker (and every
# command a test runs in a subprocess, which inherits the environment) uses one thread per library.
# Set before numpy or OpenCV is first imported; a value already in the environment is kept.
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OPENCV_FOR_THREADS_NUM"):
    os.environ.setdefault(_name, "1")

import pytest  # noqa: E402

try:
    import handeye.calibration  # noqa: F401,E402
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


def pytest_configure(config):
    """OpenCV's thread count, once more in the process itself (the environment is read at its import,
    which a plug-in may have done before this file)."""
    try:
        import cv2  # noqa: PLC0415
    except ImportError:
        return
    cv2.setNumThreads(int(os.environ["OPENCV_FOR_THREADS_NUM"]))
