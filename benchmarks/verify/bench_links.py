"""``handeye verify`` over every controller link against the standalone mock (a rehearsal station).

Per link (socket, serial, Modbus, RWS): ``handeye mock controller --protocol P --camera-port 0`` in
its own process; a baseline captured over that link (``capture``), calibrated and written back
(``writeback``); a check with nothing changed (expected exit 0); then the mock is started again with
a station config whose ``mock.faults`` moves the camera 0.5 mm, the baseline's tool data written to
it again (a restarted standalone mock forgets it), and a second check (expected exit 3, cause
camera). Prints one line per link.

Usage:
    python benchmarks/verify/bench_links.py [--protocols socket,serial,modbus,rws] [--postures 14]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "controller"))
from mock_process import mock_controller  # noqa: E402

from handeye.station.cli import main  # noqa: E402

KEY = "bench-verify-key"
FAULTS = {"camera_shift_mm": [0.3, -0.3, 0.25]}


def _link(protocol: str, port: int, banner: str) -> dict:
    if protocol == "serial":
        return {"serial_url": re.search(r"(socket://[\d.]+:\d+)", banner).group(1)}
    return {"host": "127.0.0.1", "port": port}


def _config(folder: Path, name: str, protocol: str, link: dict, arm: str, postures: int, faults=None) -> str:
    data = {"controller": {"protocol": protocol, "write_key": KEY, **link}, "camera": {"backend": "mock", "mock_arm": arm},
            "plan": {"postures": postures}}
    if faults:
        data["mock"] = {"faults": faults}
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def _mock(protocol: str, *extra):
    return mock_controller("--protocol", protocol, "--camera-port", "0", "--write-key", KEY, "--time-scale", "0.01",
                           "--duration", "1200", *extra, banner_lines=4)


def _arm(banner: list) -> str:
    return re.search(r"camera\.mock_arm: ([\d.]+:\d+)", "".join(banner)).group(1)


def _check(folder: Path, config: str, session: Path, name: str) -> tuple[int, dict]:
    out = folder / f"{name}.json"
    code = main(["verify", "--config", config, "--against", str(session), "--json", str(out), "--yes"])
    return code, json.loads(out.read_text()) if out.is_file() else {}


def run_link(protocol: str, postures: int) -> str:
    with tempfile.TemporaryDirectory(prefix=f"bench-verify-{protocol}-") as tmp:
        folder = Path(tmp)
        session = folder / "base"
        with _mock(protocol) as (port, banner):
            config = _config(folder, "clean", protocol, _link(protocol, port, "".join(banner)), _arm(banner), postures)
            assert main(["capture", "--config", config, "--session", str(session), "--yes"]) == 0
            assert main(["writeback", str(session), "--config", config]) == 0
            clean = _check(folder, config, session, "clean")
        faults = folder / "faults.yaml"
        faults.write_text(yaml.safe_dump({"controller": {"protocol": protocol, "write_key": KEY}, "camera": {"backend": "xb3"},
                                          "mock": {"faults": FAULTS}}))
        with _mock(protocol, "--config", str(faults)) as (port, banner):
            config = _config(folder, "moved", protocol, _link(protocol, port, "".join(banner)), _arm(banner), postures)
            assert main(["writeback", str(session), "--config", config]) == 0
            moved = _check(folder, config, session, "moved")
    d = moved[1].get("diagnosis", {})
    return (f"{protocol:7s} nothing changed: exit {clean[0]} ({clean[1].get('verdict')}); camera moved 0.49 mm: "
            f"exit {moved[0]} ({moved[1].get('verdict')}, cause {d.get('cause')}, {d.get('translation_mm', 0):.3f} mm)")


def main_(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--protocols", default="socket,serial,modbus,rws")
    parser.add_argument("--postures", type=int, default=14)
    args = parser.parse_args(argv)
    lines = [run_link(p, args.postures) for p in args.protocols.split(",")]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main_())
