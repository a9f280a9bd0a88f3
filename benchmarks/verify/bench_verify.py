"""``handeye verify`` on the embedded mock station: false alarms, detection, diagnosis, quick update.

Per trial (a fresh seed: new arm errors, sensor noise and plan), one baseline is captured (30
postures, ``station.capture.loop``), calibrated and written back to the mock controller (its PERS tool
data kept in the state file beside the session, as the CLI does); then every case disturbs the
station through ``mock.faults`` (or, for ``tooldata``, the controller's tool data) and runs
``station.verify.check.verify`` with K = 5 over the mock's socket link:

- ``none``: nothing changed (drift is a false alarm);
- ``camera_shift`` 0.5 mm (random direction), ``camera_turn`` 0.05 deg (random axis);
- ``board_shift`` 1 mm, ``board_turn`` 0.1 deg;
- ``joint1`` .. ``joint6``: a 0.05 deg zero shift of that axis;
- ``tooldata``: the controller holds another tool data (0.5 mm off);
- ``update``: the camera moved 2 mm / 0.2 deg: the quick update against the new truth, in its sigmas
  (the truth both as the physical mount on the true flange and as the arm's model sees it: the mount
  behind the true arm's last-link deviation, which no hand-eye data can tell from the mount;
  :func:`last_link_mount`).

Each verify's outcome is appended to ``--out`` (JSON lines) as it ends, so an interrupted run keeps
what it measured; ``--summary`` prints the figures of such a file. Runs in one process, one trial
after the other (no parallel workers: the machine is shared).

Usage:
    python benchmarks/verify/bench_verify.py [--trials 50] [--seed 100] [--out results.jsonl]
    python benchmarks/verify/bench_verify.py --summary results.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from handeye.robot.kinematics import load_robot
from handeye.geometry.transforms import rotation_error_deg
from handeye.mocks.station import DEFAULT_MOUNT, read_state, write_state
from handeye.station.capture.loop import capture
from handeye.station.config.station import FaultSettings, default_config
from handeye.station.runtime import mock_state_file, open_controller_link, open_station
from handeye.station.verify.check import session_baseline, verify
from handeye.station.verify.plan import capture_time
from handeye.station.verify.result import diagnosis
from handeye.station.writeback import writeback
from handeye.calibration.session import read_session

CASES = ("none", "camera_shift", "camera_turn", "board_shift", "board_turn", "joint1", "joint2", "joint3", "joint4",
         "joint5", "joint6", "tooldata", "update")


def _direction(rng) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def case_faults(case: str, rng) -> tuple[FaultSettings, dict]:
    """The faults of a case and its truth (cause, joint, size)."""
    z3 = (0.0, 0.0, 0.0)
    if case == "camera_shift":
        return FaultSettings(camera_shift_mm=tuple(0.5 * _direction(rng))), {"cause": "camera", "mm": 0.5}
    if case == "camera_turn":
        return FaultSettings(camera_turn_deg=tuple(0.05 * _direction(rng))), {"cause": "camera", "deg": 0.05}
    if case == "board_shift":
        return FaultSettings(board_shift_mm=tuple(1.0 * _direction(rng))), {"cause": "board", "mm": 1.0}
    if case == "board_turn":
        return FaultSettings(board_turn_deg=tuple(0.1 * _direction(rng))), {"cause": "board", "deg": 0.1}
    if case.startswith("joint"):
        k = int(case[5:])
        zero = [0.0] * 6
        zero[k - 1] = 0.05
        return FaultSettings(joint_zero_deg=tuple(zero)), {"cause": "joint", "joint": k, "deg": 0.05}
    if case == "update":
        return (FaultSettings(camera_shift_mm=tuple(2.0 * _direction(rng)), camera_turn_deg=tuple(0.2 * _direction(rng))),
                {"cause": "camera", "mm": 2.0, "deg": 0.2})
    if case == "tooldata":
        return FaultSettings(camera_shift_mm=z3), {"cause": "tooldata"}
    return FaultSettings(), {"cause": "none"}


def baseline(config, folder: Path) -> tuple[object, float]:
    """Capture, calibrate and write back the trial's baseline; its solved baseline and its robot time by the
    plan's motion model (``verify_plan.capture_time``: the model the check's ``motion_s`` is timed by)."""
    with open_station(config, session_dir=folder) as link:
        capture(config, folder, link)
    motion = capture_time(load_robot(config.robot), read_session(folder).extra["capture"])
    base = session_baseline(config, read_session(folder), folder)
    with open_controller_link(config, session_dir=folder) as link:
        writeback(folder, config, base.assessment.result, link.controller, origin="mock", mock_controller=True)
    return base, motion


def last_link_mount(config, mount: np.ndarray) -> np.ndarray:
    """The camera mount as the arm's model sees it: the true mount behind the true arm's last-link
    deviation (its DH row: ``d, a, alpha, theta``).

    A deviation of the last link is one rigid transform between the modelled flange and the camera,
    the same at every posture (``Rz``/``Tz`` of the row commute with the last axis, ``Tx``/``Rx``
    act in the flange frame): no hand-eye data can tell it from the mount, so a calibration (and the
    controller's tooldata, which the nominal last link carries) holds ``mount`` with it. The other
    rows' deviations stay where they are (the calibration models them).
    """
    from handeye.robot.kinematics import RobotModel, load_robot
    from handeye.mocks.station import perturbed_robot

    nominal = load_robot(config.robot)
    true = perturbed_robot(nominal, config.mock.kinematic_error_mm, config.mock.kinematic_error_deg, config.mock.seed)
    dh = true.dh.copy()
    dh[-1] = nominal.dh[-1]
    rows = [(i + 1, j + 1, nominal.coupling[i, j]) for i in range(nominal.dof) for j in range(nominal.dof)
            if i != j and nominal.coupling[i, j] != 0]
    modelled = RobotModel.from_dh("last link nominal", dh, rows, nominal.joint_limits_deg, nominal.max_speed_deg_s)
    q = np.zeros(nominal.dof)
    return np.linalg.inv(modelled.forward_transform(q)) @ true.forward_transform(q) @ mount


def _tamper_tool(folder: Path) -> object:
    """Put another tool data (0.5 mm off in x) into the mock controller's state; returns the original."""
    path = mock_state_file(folder)
    state = read_state(path)
    tool = state["tool"]
    moved = replace(tool, position_mm=(tool.position_mm[0] + 0.5,) + tuple(tool.position_mm[1:]))
    write_state(path, moved, state["runs"])
    return tool


def run_case(config, folder: Path, base, case: str, rng) -> dict:
    faults, truth = case_faults(case, rng)
    config = replace(config, mock=replace(config.mock, faults=faults))
    original = _tamper_tool(folder) if case == "tooldata" else None
    try:
        with open_station(config, session_dir=folder) as link:
            outcome = verify(config, folder, link, 5, base=base)
    finally:
        if original is not None:
            path = mock_state_file(folder)
            write_state(path, original, read_state(path)["runs"])
    diag = diagnosis(outcome)
    row = {"case": case, "truth": truth, "verdict": outcome.verdict, "cause": diag["cause"], "joint": diag["joint"],
           "translation_mm": diag["translation_mm"], "rotation_deg": diag["rotation_deg"],
           "named": [diag["cause"] + (f" {diag['joint']}" if diag["joint"] else "")] + diag["indistinguishable"],
           "p_value": None if outcome.test is None else outcome.test.p_value, "motion_s": outcome.motion_s}
    if case == "update" and outcome.update is not None:
        true_mount = faults.model().mount(DEFAULT_MOUNT)
        err_t = outcome.update.x[:3, 3] - true_mount[:3, 3]
        row["update_error_mm"] = [float(v) for v in err_t]
        row["update_sigma_mm"] = [float(v) for v in outcome.update.sigma_translation_mm]
        row["update_error_deg"] = float(rotation_error_deg(outcome.update.x, true_mount))
        row["update_sigma_deg"] = [float(v) for v in outcome.update.sigma_rotation_deg]
        row["update_reduced_chi2"] = float(outcome.update.reduced_chi2)
        seen = last_link_mount(config, true_mount)  # the same truth with the arm's last-link deviation in it
        row["update_error_model_mm"] = [float(v) for v in outcome.update.x[:3, 3] - seen[:3, 3]]
        row["update_error_model_deg"] = float(rotation_error_deg(outcome.update.x, seen))
    return row


def run(trials: int, seed: int, out: Path, cases) -> None:
    for t in range(trials):
        s = seed + t
        rng = np.random.default_rng(s)
        config = default_config().as_mock()
        config = replace(config, mock=replace(config.mock, seed=s), plan=replace(config.plan, seed=s))
        with tempfile.TemporaryDirectory(prefix="bench-verify-") as tmp:
            folder = Path(tmp) / "base"
            t0 = time.monotonic()
            base, full_motion = baseline(config, folder)
            for case in cases:
                row = run_case(config, folder, base, case, rng)
                row.update(trial=t, seed=s, capture_motion_s=full_motion)
                with out.open("a", encoding="utf-8") as fh:
                    fh.write(json.dumps(row) + "\n")
            print(f"trial {t + 1}/{trials} (seed {s}) done in {time.monotonic() - t0:.0f} s", flush=True)


def _rate(rows, test) -> str:
    return f"{sum(1 for r in rows if test(r))}/{len(rows)}" if rows else "-"


def _size_ok(r) -> bool:
    t = r["truth"]
    if "mm" in t and "deg" not in t:
        return abs(r["translation_mm"] - t["mm"]) <= 0.3 * t["mm"]
    if "deg" in t and "mm" not in t:
        return abs(r["rotation_deg"] - t["deg"]) <= 0.3 * t["deg"]
    return True


def _within(r, suffix: str = "") -> bool:
    """Every axis and the rotation of a quick update within 3 of its sigmas of a truth."""
    return (all(abs(e) <= 3 * s for e, s in zip(r[f"update_error{suffix}_mm"], r["update_sigma_mm"]))
            and r[f"update_error{suffix}_deg"] <= 3 * float(np.linalg.norm(r["update_sigma_deg"])))


def _update_line(rs) -> str:
    ok = [r for r in rs if "update_error_mm" in r]
    line = "  within 3 sigma " + _rate(ok, _within)
    model = [r for r in ok if "update_error_model_mm" in r]
    if model:
        line += f" (of the mount with the arm's last-link deviation: {_rate(model, lambda r: _within(r, '_model'))})"
    return line


def summary(path: Path) -> list[str]:
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    lines = [f"{len({r['trial'] for r in rows})} trials, {len(rows)} checks (K = 5)"]
    for case in CASES:
        rs = [r for r in rows if r["case"] == case]
        if not rs:
            continue
        drift = [r for r in rs if r["verdict"] == "drift"]
        t = rs[0]["truth"]
        line = f"  {case:13s} drift {_rate(rs, lambda r: r['verdict'] == 'drift'):7s}"
        if case.startswith("joint"):
            name = f"joint {t['joint']}"
            line += (f"  right joint named first {_rate(drift, lambda r: r['joint'] == t['joint'])}"
                     f"  among the named {_rate(drift, lambda r: name in r['named'])}")
        elif case != "none":
            line += f"  cause {t['cause']} {_rate(drift, lambda r: r['cause'] == t['cause'])}"
            if case != "update" and case != "tooldata":
                line += f"  size within 30 % {_rate([r for r in drift if r['cause'] == t['cause']], _size_ok)}"
        if case == "update":
            line += _update_line(rs)
        lines.append(line)
    ratio = [r["motion_s"] / r["capture_motion_s"] for r in rows if r.get("motion_s") and r.get("capture_motion_s")]
    if ratio:
        lines.append(f"  robot time of a check / the full capture's: median {np.median(ratio):.3f}, max {np.max(ratio):.3f}")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=50)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/verify/results.jsonl"))
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated subset of the cases")
    parser.add_argument("--summary", type=Path, help="print the figures of a results file and stop")
    args = parser.parse_args(argv)
    if args.summary:
        print("\n".join(summary(args.summary)))
        return 0
    run(args.trials, args.seed, args.out, [c for c in args.cases.split(",") if c])
    print("\n".join(summary(args.out)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
