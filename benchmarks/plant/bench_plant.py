"""A plant of simulated cells publishing to a real mosquitto restarted mid-stream, and the time publishing
adds to a calibration command (issue 38).

Part 1 (``--cells`` 50 x ``--events`` 20): a broker on 127.0.0.1 with TLS, a password per cell and the
README's ACL (tests/plant_broker.py); the fleet's persistent subscriber (``station.plant.subscriber``)
keeps the history in SQLite. The cells run in a bounded thread pool (``--workers``), each publishing its
events one after the other as the commands do (``hooks.publish_event``: outbox, then delivery within
``publish_timeout_s``); the broker is stopped and started again twice while they publish (after a third
and two thirds of the events). Events made while it is down wait in their cell's outbox and leave with
the cell's next event; at the end each cell runs its next delivery once (the next command). Checked:
every event in the history exactly once, and in each cell's order of arrival seq 1..N.

Part 2 (``--rounds``): ``handeye calibrate`` of a mock session whose capture recorded a ``plant:``
section, each in a fresh process, timing the hook's call (``plant.hooks.after_calibrate``: importing
the plant modules and paho, the event, the outbox's atomic write, TLS connect, QoS 1 publish and the
retained state), in wall-clock and in CPU time of the process (all threads), beside the whole command.

Usage:
    python benchmarks/plant/bench_plant.py [--cells 50] [--events 20] [--workers 10] [--rounds 10] [--json OUT]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from plant_broker import MOSQUITTO_MISSING, Broker  # noqa: E402

import yaml  # noqa: E402

from handeye.station.plant.fleet_config import fleet_from_dict  # noqa: E402
from handeye.station.plant.hooks import publish_event  # noqa: E402
from handeye.station.plant.outbox import Outbox  # noqa: E402
from handeye.station.plant.publisher import deliver  # noqa: E402
from handeye.station.plant.settings import plant_rule  # noqa: E402
from handeye.station.plant.store import History  # noqa: E402
from handeye.station.plant.subscriber import FleetSubscriber  # noqa: E402


def _fleet_run(folder: Path, cells: int, events: int, workers: int) -> dict:
    names = [f"cell{i:02d}" for i in range(1, cells + 1)]
    broker = Broker(folder / "broker", cells=names).start()
    history = History(folder / "history.sqlite")
    subscriber = FleetSubscriber(fleet_from_dict({"mqtt": broker.fleet_mqtt()}), history).start()
    plants = {n: plant_rule(broker.cell_plant(n, folder / "outbox" / n, publish_timeout_s=1.0), "plant", {}) for n in names}
    total, made, lock = cells * events, [0], threading.Lock()
    restarts, warnings = [], io.StringIO()

    def cell(name):
        plant = plants[name]
        for n in range(1, events + 1):
            publish_event("calibrate", plant, lambda: {"topic_prefix": plant.mqtt.topic_prefix, "kind": "calibrate", "n": n})
            with lock:
                made[0] += 1
            time.sleep(0.01)

    def restarter():
        for fraction in (1 / 3, 2 / 3):
            while made[0] < fraction * total:
                time.sleep(0.01)
            broker.stop()
            time.sleep(0.5)  # events made meanwhile wait in the outboxes
            broker.start()
            restarts.append(made[0])

    started = time.monotonic()
    thread = threading.Thread(target=restarter)
    thread.start()
    with contextlib.redirect_stderr(warnings), ThreadPoolExecutor(max_workers=workers) as pool:
        list(pool.map(cell, names))
    thread.join()
    waiting_before = sum(len(Outbox(p.outbox_dir()).pending()) for p in plants.values())
    for plant in plants.values():  # each cell's next command
        deliver(plant, Outbox(plant.outbox_dir()))
    deadline = time.monotonic() + 60
    while history.count() < total and time.monotonic() < deadline:
        time.sleep(0.1)
    elapsed = time.monotonic() - started
    time.sleep(1.0)  # anything sent twice would arrive by now
    per_cell = {p.mqtt.topic_prefix: [e["seq"] for e in history.events(p.mqtt.topic_prefix, by_arrival=True)]
                for p in plants.values()}
    in_order = sum(seqs == list(range(1, events + 1)) for seqs in per_cell.values())
    subscriber.stop()
    broker.stop()
    return {"cells": cells, "events_per_cell": events, "workers": workers, "events_made": total,
            "events_in_history": history.count(), "cells_exactly_once_in_order": in_order,
            "duplicates_dropped_by_seq": subscriber.duplicates, "broker_restarts_after_events": restarts,
            "waiting_before_final_delivery": waiting_before, "warning_lines": len(warnings.getvalue().splitlines()),
            "seconds": round(elapsed, 1)}


_TIMED = """
import sys, time
import handeye.station.plant.hooks as hooks
original, took = hooks.after_calibrate, []
def timed(*a, **k):
    t, c = time.perf_counter(), time.process_time(); original(*a, **k)
    took.append((time.perf_counter() - t, time.process_time() - c))
hooks.after_calibrate = timed
from handeye.station.cli import main
start = time.perf_counter()
code = main(["calibrate", sys.argv[1], "--quiet", "--json", sys.argv[2]])
print("HOOK_MS", code, took[0][0] * 1000, "paho" in "".join(sys.modules), took[0][1] * 1000, (time.perf_counter() - start) * 1000)
"""


def _publish_cost(folder: Path, rounds: int) -> dict:
    from handeye.station.cli import main

    broker = Broker(folder / "broker2", cells=("cell01",)).start()
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["demo", "--session", str(folder / "demo"), "--postures", "14", "--no-report"]) == 0
    session = folder / "demo" / "session"
    head = yaml.safe_load((session / "session.yaml").read_text())
    head["capture"]["config"]["plant"] = broker.cell_plant("cell01", folder / "outbox-cost")
    (session / "session.yaml").write_text(yaml.safe_dump(head))
    costs, cpu, command = [], [], []
    for _ in range(rounds):
        out = subprocess.run([sys.executable, "-c", _TIMED, str(session), str(folder / "r.json")], capture_output=True,
                             text=True, timeout=300)
        words = [line for line in out.stdout.splitlines() if line.startswith("HOOK_MS")][0].split()
        assert words[1] == "0" and words[3] == "True" and "warning" not in out.stderr, out.stderr
        costs.append(float(words[2]))
        cpu.append(float(words[4]))
        command.append(float(words[5]))
    sent = len(Outbox(folder / "outbox-cost").pending())
    broker.stop()
    return {"rounds": rounds, "hook_ms_median": round(statistics.median(costs), 1), "hook_ms_max": round(max(costs), 1),
            "hook_ms": [round(c, 1) for c in costs], "hook_cpu_ms_median": round(statistics.median(cpu), 1),
            "calibrate_command_ms_median": round(statistics.median(command), 1), "left_in_outbox": sent}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=50)
    parser.add_argument("--events", type=int, default=20)
    parser.add_argument("--workers", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=10)
    parser.add_argument("--json", metavar="OUT")
    args = parser.parse_args(argv)
    if MOSQUITTO_MISSING:
        print(MOSQUITTO_MISSING, file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        fleet = _fleet_run(Path(tmp), args.cells, args.events, args.workers)
        print(json.dumps(fleet), flush=True)
        cost = _publish_cost(Path(tmp), args.rounds)
        print(json.dumps(cost), flush=True)
    import os

    result = {"fleet": fleet, "publish_cost": cost, "load_average_1min": round(os.getloadavg()[0], 1),
              "date": time.strftime("%Y-%m-%d")}
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n")
    ok = fleet["cells_exactly_once_in_order"] == fleet["cells"] and fleet["events_in_history"] == fleet["events_made"]
    print(f"fleet: {'PASS' if ok else 'FAIL'} (every event once, in order per cell); publish cost: median "
          f"{cost['hook_ms_median']} ms wall, {cost['hook_cpu_ms_median']} ms CPU (target < 50 ms: "
          f"{'PASS' if cost['hook_ms_median'] < 50 else 'FAIL'}) at load average {result['load_average_1min']}", flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
