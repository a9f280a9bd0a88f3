"""Guided capture with the guided RAPID program (HeGuide) over socket, serial and Modbus, against the
standalone mock controller, the operator played from outside through its pendant port (issue 22's
Must-hold).

Per link: ``handeye mock controller --protocol P --camera-port 0 --pendant-port 0`` in its own process;
``capture --plan-only`` plans N postures around the board from where the arm stands (the postures an
operator who knows the cell would jog to); ``capture --guided`` with a scripted operator
(``tests/pendant_operator.py``: at each prompt Capture, JOG to the next posture, Start; Done at the end);
then the planned capture of the same plan on the same mock (``capture --yes``). Both sessions are
calibrated; each result is compared with the camera mount the mock hides (the default mock station's,
reproduced here: the mock never tells). Prints one line per link and appends them to results.jsonl.

Usage:
    python benchmarks/guided/bench_guided_pendant.py [--protocols socket,serial,modbus] [--postures 20]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "controller"))
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))  # the scripted operator (tests/pendant_operator.py)
from mock_process import mock_controller  # noqa: E402

from handeye.calibration.session import read_session  # noqa: E402
from handeye.geometry.transforms import rotation_error_deg, transform_from_pose, translation_error_mm  # noqa: E402
from handeye.mocks.station import MockStationSpec  # noqa: E402
from handeye.station.cli import main  # noqa: E402
from pendant_operator import PendantOperator  # noqa: E402

KEY = "bench-guided-key"


def _quiet(argv) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(argv)
    return rc, out.getvalue()


def _error(session: Path, truth) -> tuple[float, float]:
    """Rotation (deg) and translation (mm) of the default calibration of ``session`` from the hidden mount."""
    result = session.parent / f"{session.name}.json"
    rc, _ = _quiet(["calibrate", str(session), "--json", str(result)])
    if rc != 0:
        raise RuntimeError(f"calibrate {session} exited {rc}")
    pose = json.loads(result.read_text())["camera_pose"]
    x = transform_from_pose(pose["position_mm"], pose["quaternion_wxyz"])
    return float(rotation_error_deg(x, truth)), float(translation_error_mm(x, truth))


def run_link(protocol: str, postures: int, folder: Path) -> dict:
    base = {"controller": {"protocol": protocol, "write_key": KEY}, "camera": {"backend": "xb3"},
            "plan": {"postures": postures}, "guided": {"operator_timeout_s": 120}}
    (folder / "mock.yaml").write_text(yaml.safe_dump(base))
    args = ("--protocol", protocol, "--camera-port", "0", "--pendant-port", "0", "--write-key", KEY,
            "--time-scale", "0.01", "--config", str(folder / "mock.yaml"))
    with mock_controller(*args, banner_lines=5) as (port, banner):
        text = "".join(banner)
        arm = re.search(r"camera\.mock_arm: ([\d.]+:\d+)", text).group(1)
        pendant = re.search(r"STATE on ([\d.]+:\d+)", text).group(1)
        link = ({"serial_url": re.search(r"(socket://[\d.]+:\d+)", text).group(1)} if protocol == "serial"
                else {"host": "127.0.0.1", "port": port})
        config = folder / "rehearsal.yaml"
        config.write_text(yaml.safe_dump({**base, "controller": {**base["controller"], **link},
                                          "camera": {"backend": "mock", "mock_arm": arm}}))
        plan, guided = folder / "planned", folder / "guided"
        assert _quiet(["capture", "--config", str(config), "--session", str(plan), "--plan-only"])[0] == 0
        joints = np.array(read_session(plan).extra["capture"]["plan_joints_deg"], float)
        operator = PendantOperator(pendant, joints).start()
        started = time.monotonic()
        rc, out = _quiet(["capture", "--config", str(config), "--session", str(guided), "--guided"])
        guided_s = time.monotonic() - started
        operator.join(60)
        if rc != 0 or operator.error is not None:
            raise RuntimeError(f"{protocol}: guided capture exited {rc}, operator: {operator.error}\n{out[-2000:]}")
        good = "GOOD ENOUGH" in out
        rc, _ = _quiet(["capture", "--config", str(config), "--session", str(plan), "--yes"])
        if rc != 0:
            raise RuntimeError(f"{protocol}: planned capture exited {rc}")
    truth = MockStationSpec(protocol=protocol).cam2tool0
    g_rot, g_mm = _error(guided, truth)
    p_rot, p_mm = _error(plan, truth)
    return {"protocol": protocol, "postures": postures, "guided_postures": len(read_session(guided).postures),
            "good_enough": good, "guided_s": round(guided_s, 1), "guided_error_deg": round(g_rot, 4),
            "guided_error_mm": round(g_mm, 3), "planned_error_deg": round(p_rot, 4), "planned_error_mm": round(p_mm, 3),
            "ratio_deg": round(g_rot / p_rot, 2), "ratio_mm": round(g_mm / p_mm, 2)}


def main_(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--protocols", default="socket,serial,modbus")
    parser.add_argument("--postures", type=int, default=20)
    args = parser.parse_args(argv)
    results = Path(__file__).with_name("results.jsonl")
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        for protocol in args.protocols.split(","):
            folder = Path(tmp) / protocol
            folder.mkdir()
            row = run_link(protocol, args.postures, folder)
            ok = row["good_enough"] and row["ratio_deg"] <= 1.5 and row["ratio_mm"] <= 1.5 \
                and row["guided_postures"] == args.postures
            failed |= not ok
            row["holds"] = ok
            print(json.dumps(row), flush=True)
            with results.open("a") as handle:
                handle.write(json.dumps({**row, "when": time.strftime("%Y-%m-%d %H:%M")}) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main_())
