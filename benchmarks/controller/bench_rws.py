"""Robot Web Services on loopback: one joints read, and a full tool-data write-back with read-back.

The mock RWS controller runs in its own process (``handeye mock controller --protocol rws
--rws-generation G --port 0``), RWS 1.0 (HTTP, Digest) and RWS 2.0 (HTTPS pinned, Basic). The
client keeps ABB's documented ceiling of about 20 requests/s (its rate limiter): reads are paced at
``--rate`` per second, below it, so each timed call is the latency of one request, not a wait for
the limiter. A write-back is ``Controller.set_tool``: mastership request, symbol write, release,
symbol read-back and compare (4 requests), timed whole, paced ``--pause`` apart.

Targets (issue 14): joints median <= 10 ms; a write-back with read-back <= 1 s.

Usage:
    python benchmarks/controller/bench_rws.py [--reads 300] [--writes 20] [--json results.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from contextlib import contextmanager

import numpy as np

from handeye.drivers.controller import ToolData, open_controller
from mock_process import mock_controller

JOINTS_TARGET_MS = 10.0
WRITEBACK_TARGET_MS = 1000.0


@contextmanager
def mock_process(generation: int):
    """The mock RWS controller of one generation in its own process; yields the client's options."""
    with mock_controller("--protocol", "rws", "--rws-generation", str(generation), banner_lines=3) as (port, banner):
        options = {"host": "127.0.0.1", "port": port}
        if generation == 2:
            options["tls_fingerprint"] = banner[2].split("--tls-fingerprint ")[1].split()[0]
        yield options


def summary(times: list) -> dict:
    times = sorted(times)
    return {"n": len(times), "median_ms": statistics.median(times), "p95_ms": times[int(0.95 * (len(times) - 1))],
            "max_ms": times[-1]}


def measure(generation: int, reads: int, writes: int, rate: float, pause: float) -> dict:
    rng = np.random.default_rng(generation)
    with mock_process(generation) as options, open_controller("rws", timeout=2.0, **options) as c:
        for _ in range(10):
            c.read_joints()
        time.sleep(1.0)  # the limiter's burst refills
        joints = []
        for _ in range(reads):
            start = time.perf_counter()
            c.read_joints()
            joints.append((time.perf_counter() - start) * 1000.0)
            time.sleep(max(0.0, 1.0 / rate - (time.perf_counter() - start)))
        writebacks = []
        for _ in range(writes):
            time.sleep(pause)
            q = rng.normal(size=4)
            q = q / np.linalg.norm(q) * np.sign(q[0])
            tool = ToolData(tuple(np.round(rng.uniform(-200, 200, 3), 3)), tuple(q), 1.5, (0.0, 0.0, 40.0))
            start = time.perf_counter()
            back = c.set_tool(tool)
            writebacks.append((time.perf_counter() - start) * 1000.0)
            assert back.close_to(tool)
    return {"generation": generation, "joints": summary(joints), "writeback": summary(writebacks)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reads", type=int, default=300)
    parser.add_argument("--writes", type=int, default=20)
    parser.add_argument("--rate", type=float, default=15.0, help="joints reads per second (below the 20/s ceiling)")
    parser.add_argument("--pause", type=float, default=0.5, help="seconds between write-backs")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    results = [measure(g, args.reads, args.writes, args.rate, args.pause) for g in (1, 2)]
    print(f"Python {platform.python_version()}, {platform.machine()}")
    print(f"{'RWS':<5} {'joints median/p95/max ms':>28} {'write-back median/p95/max ms':>32}")
    ok = True
    for r in results:
        j, w = r["joints"], r["writeback"]
        print(f"{r['generation']}.0   {j['median_ms']:8.2f} {j['p95_ms']:8.2f} {j['max_ms']:8.2f}"
              f"       {w['median_ms']:8.1f} {w['p95_ms']:8.1f} {w['max_ms']:8.1f}")
        ok &= j["median_ms"] <= JOINTS_TARGET_MS and w["max_ms"] <= WRITEBACK_TARGET_MS
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
