"""``handeye plant``: the fleet view of a plant's cells (their calibration health, from the plant's broker)."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "the fleet view: subscribe to the plant's broker, keep the history, show one row per cell"

EPILOG = """\
Every cell whose station file has a plant: section publishes each calibrate, writeback, verify and
quick update to the plant's MQTT broker (docs/plant.md, A plant of cells). This command subscribes to
them (plant.yaml: the broker, its TLS and credentials, which cells, the verify interval), keeps every
event once and in each cell's order in a SQLite history beside plant.yaml, and serves a page (the
live view's: offline, behind a token printed here) with one row per cell: last calibration, last
verify and its verdict, the drift trend, the predicted error at the stand-off, what is due, and
the alarms (drift, camera serial changed, tooldata mismatch, verify overdue, stopped reporting).
It runs until Ctrl-C; the broker keeps the events for it meanwhile (a persistent session).

--json [FILE] prints the same table as JSON and stops: the history (kept by the running fleet view)
and what arrives meanwhile; it does not take the running view's place at the broker.

Examples:
  handeye plant --config plant.yaml
  handeye plant --config plant.yaml --json fleet.json
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("plant", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", metavar="PLANT.yaml", required=True, help="the fleet's configuration (broker, cells)")
    p.add_argument("--json", metavar="FILE", nargs="?", const="-", help="print the table as JSON and stop ('-' = stdout)")
    p.add_argument("--settle-s", type=float, default=1.0, help="--json: stop once nothing came for this long (s)")
    return p


def run(args: argparse.Namespace) -> int:
    import json
    import time

    from ..plant.fleet import fleet_table
    from ..plant.fleet_config import load_fleet_config
    from ..plant.store import History
    from ..plant.subscriber import FleetSubscriber

    fleet = load_fleet_config(args.config)
    history = History(fleet.history_path())
    if args.json is not None:
        subscriber = FleetSubscriber(fleet, history, persistent=False).start()
        try:
            seen, quiet_since, deadline = -1, time.monotonic(), time.monotonic() + max(30.0, args.settle_s * 10)
            while time.monotonic() < deadline and time.monotonic() - quiet_since < args.settle_s:
                if history.version != seen:
                    seen, quiet_since = history.version, time.monotonic()
                time.sleep(0.05)
        finally:
            subscriber.stop()
        from ..output import write_json

        write_json(args.json, fleet_table(history, fleet))
        return 0
    return _serve(fleet, history)


def _serve(fleet, history) -> int:
    import time

    from ..plant.subscriber import FleetSubscriber
    from ..plant.view import FleetHub, FleetServer
    from ..view import loopback

    hub = FleetHub(history, fleet).start()
    subscriber = FleetSubscriber(fleet, history, on_change=hub.poke).start()
    server = FleetServer(hub, fleet.view.host, fleet.view.port).start()
    if not loopback(fleet.view.host):
        print(f"handeye plant: warning: the page listens on {fleet.view.host}: anyone with its URL (its token) sees the "
              "fleet", flush=True)
    print(f"fleet view: {server.url}", flush=True)
    print(f"history: {fleet.history_path()} (Ctrl-C stops)", flush=True)
    try:
        while True:
            time.sleep(1.0)
    finally:
        subscriber.stop()
        hub.close()
        server.close(linger_s=0.1)
        history.close()
