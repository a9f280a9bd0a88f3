"""``handeye mock controller`` in a process of its own, for the link benchmarks (bench_joints.py, bench_rws.py).

A mock in its own process does not share the Python interpreter lock with the client, as a real
controller would not.
"""

from __future__ import annotations

import signal
import subprocess
import sys
from contextlib import contextmanager


@contextmanager
def mock_controller(*args: str, banner_lines: int = 1):
    """Start ``handeye mock controller ARGS --port 0``; yield the port it listens on and its banner lines.

    On exit it is stopped with Ctrl-C (SIGINT), killed if it has not stopped within 10 s. The child
    gets the default SIGINT disposition back: a shell starts background jobs with SIGINT ignored, and
    a child would inherit that and never stop on Ctrl-C.
    """
    cmd = [sys.executable, "-c", "from handeye.station.cli import main; raise SystemExit(main())",
           "mock", "controller", *args, "--port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        banner = [proc.stdout.readline() for _ in range(banner_lines)]
        if "127.0.0.1:" not in banner[0]:
            raise RuntimeError(f"mock did not start: {banner}{proc.stderr.read()}")
        yield int(banner[0].split("127.0.0.1:")[1].split(";")[0].split()[0]), banner
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
