"""Latency of one joints read over loopback, per back end (socket, serial via socket://, Modbus TCP).

Each back end's mock controller runs in its own process (``handeye mock controller --port 0``), as
a controller would, so client and server do not share the Python interpreter lock; ``--in-process``
runs the mock in a thread of this process instead. The figure is the median of ``--reads`` calls of
``Controller.read_joints()`` after ``--warmup`` calls, each timed with ``time.perf_counter``.

Usage:
    python benchmarks/controller/bench_joints.py [--reads 2000] [--in-process] [--json results.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from contextlib import contextmanager

from handeye.drivers.controller import open_controller
from mock_process import mock_controller
from handeye.mocks.backends import mock_protocols

PROTOCOLS = tuple(p for p in mock_protocols() if p != "rws")  # rws: bench_rws.py (paced below its rate limit)
TARGET_MS = 5.0


@contextmanager
def mock_process(protocol: str):
    """The mock controller of one back end in its own process; yields the client's options."""
    with mock_controller("--protocol", protocol) as (port, _):
        yield ({"url": f"socket://127.0.0.1:{port}"} if protocol == "serial" else {"host": "127.0.0.1", "port": port})


@contextmanager
def mock_thread(protocol: str):
    from handeye.mocks.controller import start_mock_controller

    with start_mock_controller(protocol) as server:
        yield server.client_options()


def measure(protocol: str, options: dict, reads: int, warmup: int) -> dict:
    with open_controller(protocol, timeout=2.0, **options) as controller:
        for _ in range(warmup):
            controller.read_joints()
        times = []
        for _ in range(reads):
            start = time.perf_counter()
            controller.read_joints()
            times.append((time.perf_counter() - start) * 1000.0)
    times.sort()
    return {
        "protocol": protocol,
        "reads": reads,
        "median_ms": statistics.median(times),
        "p95_ms": times[int(0.95 * (len(times) - 1))],
        "max_ms": times[-1],
        "mean_ms": statistics.fmean(times),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reads", type=int, default=2000)
    parser.add_argument("--warmup", type=int, default=100)
    parser.add_argument("--in-process", action="store_true", help="run the mock in a thread of this process")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    args = parser.parse_args(argv)
    runner = mock_thread if args.in_process else mock_process
    rows = []
    for protocol in PROTOCOLS:
        with runner(protocol) as options:
            rows.append(measure(protocol, options, args.reads, args.warmup))
    mode = "mock in a thread of the client process" if args.in_process else "mock in its own process"
    print(f"joints read on loopback ({mode}), {args.reads} reads after {args.warmup} warm-up; "
          f"Python {platform.python_version()}, {platform.machine()}")
    print(f"{'back end':<8} {'median ms':>10} {'p95 ms':>8} {'max ms':>8}  target median <= {TARGET_MS:g} ms")
    for r in rows:
        verdict = "ok" if r["median_ms"] <= TARGET_MS else "TOO SLOW"
        print(f"{r['protocol']:<8} {r['median_ms']:>10.3f} {r['p95_ms']:>8.3f} {r['max_ms']:>8.2f}  {verdict}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"mode": mode, "results": rows}, handle, indent=2)
    return 0 if all(r["median_ms"] <= TARGET_MS for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
