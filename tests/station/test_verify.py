"""``handeye verify`` on the embedded mock station (a real TCP controller server and rendered XB3
frames), with faults of known size injected through ``mock.faults``: each cause must be named with
its size; exit codes, JSON keys, refusals, the history and the write-back of a quick update.

One baseline session (captured, calibrated, written back) is shared by the module; each check is a
few postures. The rates over many seeds are the benchmark's (benchmarks/verify)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from handeye.geometry.transforms import rotation_error_deg
from handeye.mocks.station import DEFAULT_MOUNT, read_state, write_state
from handeye.station.cli import main
from handeye.station.config.station import FaultSettings
from handeye.station.runtime import mock_state_file

BASE_YAML = "controller: {protocol: mock}\ncamera: {backend: mock}\nplan: {postures: 14}\n"

def _config(folder, name: str, faults: str = "", extra: str = "") -> str:
    path = folder / f"{name}.yaml"
    path.write_text(BASE_YAML + extra + (f"mock:\n  faults: {{{faults}}}\n" if faults else ""))
    return str(path)

@pytest.fixture(scope="module")
def station(tmp_path_factory):
    """A calibrated baseline on the mock station, its tool data written back (kept in the state file)."""
    root = tmp_path_factory.mktemp("verify")
    config = _config(root, "mock")
    session = root / "base"
    assert main(["capture", "--config", config, "--session", str(session), "--yes"]) == 0
    assert main(["writeback", str(session), "--config", config]) == 0
    return root, session, config

def _verify(station, name: str, faults: str, *extra, config_extra: str = ""):
    root, session, _ = station
    out = root / f"{name}.json"
    code = main(["verify", "--config", _config(root, name, faults, config_extra), "--against", str(session), "--json", str(out),
                 *extra])
    return code, json.loads(out.read_text()) if out.is_file() else None

def test_nothing_changed_is_ok_with_the_json_keys(station, capsys):
    code, data = _verify(station, "none", "")
    assert code == 0
    assert data["verdict"] == "ok" and data["postures"] == 5 and data["measured"] == 5
    out = capsys.readouterr().out
    # issue 42.10: the per-posture lines name SESSION's postures, as "revisiting postures ..." does
    revisited = data["revisited"]
    assert f"revisiting postures {', '.join(map(str, revisited))} of base" in out
    named = [int(line.split("ok    posture ")[1].split(":")[0]) for line in out.splitlines() if "ok    posture " in line]
    assert named == revisited and revisited != list(range(5)), out
    diag = data["diagnosis"]
    assert diag["cause"] == "none" and diag["joint"] is None
    assert {"alternatives", "translation_mm", "rotation_deg"} <= set(diag)
    assert 0.01 < data["test"]["p_value"] <= 1.0 and data["test"]["degrees_of_freedom"] == 30
    assert "nothing to do" in out

def test_camera_move_is_named_with_its_size_and_the_quick_update_is_written(station, capsys):
    root, session, config = station
    shift = np.array([0.9, -0.8, 0.6])  # 1.34 mm
    code, data = _verify(station, "camera", f"camera_shift_mm: {shift.tolist()}, camera_turn_deg: [0.05, -0.08, 0.1]")
    assert code == 3 and data["verdict"] == "drift"
    diag = data["diagnosis"]
    assert diag["cause"] == "camera"
    assert diag["translation_mm"] == pytest.approx(np.linalg.norm(shift), rel=0.3)
    assert diag["rotation_deg"] == pytest.approx(np.linalg.norm([0.05, -0.08, 0.1]), rel=0.3)
    assert diag["likelihood_ratio"] > 100
    update = data["quick_update"]
    truth = FaultSettings(camera_shift_mm=tuple(shift), camera_turn_deg=(0.05, -0.08, 0.1)).model().mount(DEFAULT_MOUNT)
    new = np.array(update["camera_pose"]["position_mm"])
    sigma = np.array(update["uncertainty"]["translation_mm"])
    assert np.all(np.abs(new - truth[:3, 3]) <= 3 * sigma + 1e-3)
    folder = data["check_session"]
    assert "quick update" in capsys.readouterr().out
    assert main(["writeback", folder, "--config", config]) == 0
    assert "read back: identical" in capsys.readouterr().out
    held = read_state(mock_state_file(session))["tool"]
    assert np.allclose(held.position_mm, new, atol=2e-3)
    history = [json.loads(line) for line in (root / "history.jsonl").read_text().splitlines()]
    assert history[-1]["kind"] == "writeback" and history[-1]["session"] == folder
    assert main(["writeback", str(session), "--config", config]) == 0  # SESSION's tool data back for the next tests

@pytest.mark.parametrize("name, faults, cause, joint", [
    ("board", "board_turn_deg: [0.1, -0.1, 0.05], board_shift_mm: [0.5, 0.0, 0.5]", "board", None),
    ("joint3", "joint_zero_deg: [0, 0, 0.08, 0, 0, 0]", "joint", 3),
])
def test_each_cause_is_named(station, name, faults, cause, joint):
    code, data = _verify(station, name, faults)
    assert code == 3
    assert data["diagnosis"]["cause"] == cause and data["diagnosis"]["joint"] == joint
    if joint is not None:
        assert data["diagnosis"]["rotation_deg"] == pytest.approx(0.08, rel=0.3)

def test_joint6_is_named_with_the_camera_turn_it_cannot_be_told_from(station, capsys):
    code, data = _verify(station, "joint6", "joint_zero_deg: [0, 0, 0, 0, 0, 0.08]")
    assert code == 3
    diag = data["diagnosis"]
    named = [diag["cause"] + (f" {diag['joint']}" if diag["joint"] else "")] + diag["indistinguishable"]
    assert "joint 6" in named and "camera" in named
    assert "cannot tell it from" in capsys.readouterr().out

def _verify_with_tool_shifted(station, name: str, shift_mm: float, config_extra: str = ""):
    """A check while the controller holds SESSION's tooldata moved by ``shift_mm`` along x (put back after)."""
    root, session, _ = station
    path = mock_state_file(session)
    state = read_state(path)
    tool = state["tool"]
    write_state(path, type(tool)((tool.position_mm[0] + shift_mm,) + tuple(tool.position_mm[1:]), tool.quaternion_wxyz,
                                 tool.mass_kg, tool.cog_mm), state["runs"])
    try:
        return _verify(station, name, "", config_extra=config_extra)
    finally:
        write_state(path, tool, read_state(path)["runs"])


def test_another_tooldata_on_the_controller_is_found(station, capsys):
    code, data = _verify_with_tool_shifted(station, "tool", 0.3)
    assert code == 3 and data["diagnosis"]["cause"] == "tooldata"
    assert data["diagnosis"]["board_check"]["cause"] == "none"
    out = capsys.readouterr().out
    assert "holds a different tHeCamera" in out and "restore it" in out
    # issue 42.10: the finding's size is the tooldata's difference, not the board check's camera drift (0.000 mm)
    diag = data["diagnosis"]
    assert diag["translation_mm"] == pytest.approx(0.3, abs=1e-3) and diag["rotation_deg"] == pytest.approx(0, abs=1e-4)
    assert diag["tooldata"]["beyond_tolerance"] is True
    assert "most likely: tooldata, 0.300 mm / 0.0000 deg" in out, out
    assert "(0.300 mm / 0.0000 deg apart; the tolerance 0.2 mm / 0.02 deg)" in out
    assert "differs from base's by 0.300 mm / 0.0000 deg, beyond the tolerance 0.2 mm / 0.02 deg" in data["reason"]


@pytest.mark.parametrize("shift_mm, config_extra, verdict", [
    (0.05, "", "ok"),                                   # below the default tolerance (0.2 mm)
    (0.05, "verify: {tolerance_mm: 0.03}\n", "drift"),  # the station's own tolerance
], ids=["below-default", "above-station-tolerance"])
def test_a_tooldata_difference_is_held_to_the_tolerance(station, capsys, shift_mm, config_extra, verdict):
    # issue 42 (tooldata): a mismatch was DRIFT whatever its size; now as the camera drift, with size and tolerance
    code, data = _verify_with_tool_shifted(station, f"tool{shift_mm}{bool(config_extra)}", shift_mm, config_extra)
    out = capsys.readouterr().out
    assert data["verdict"] == verdict and code == {"ok": 0, "drift": 3}[verdict], out
    tool = data["diagnosis"]["tooldata"]
    assert tool["translation_mm"] == pytest.approx(shift_mm, abs=1e-3) and tool["beyond_tolerance"] is (verdict == "drift")
    tolerance = "0.03 mm / 0.02 deg" if config_extra else "0.2 mm / 0.02 deg"
    assert f"({shift_mm:.3f} mm / 0.0000 deg apart; the tolerance {tolerance})" in out, out
    if verdict == "ok":
        assert data["diagnosis"]["cause"] == "none" and "restore it" not in out
        assert "within the tolerance, nothing to write" in out and "ok: the calibration still predicts" in out
    else:
        assert data["diagnosis"]["cause"] == "tooldata" and "restore it" in out

def test_board_out_of_view_is_inconclusive(station):
    # The camera turned and the board moved away so far that no corner is in view, no retries: an OpenCV
    # search on a partly seen board costs seconds per attempt, and it is the verdict that is tested here.
    code, data = _verify(station, "blind", "camera_turn_deg: [-30, 30, 0], board_shift_mm: [100, 100, 100]",
                         "--postures", "3", config_extra="capture: {retries: 0}\n")
    assert code == 4 and data["verdict"] == "inconclusive"
    assert data["measured"] < 3

def test_board_out_of_view_stops_the_check_at_its_first_posture(station, capsys, monkeypatch):
    # With the retries a capture uses (2), a check of 5 postures whose board is out of view would run
    # 15 full chessboard searches; it stops after the first grab that sees no checkerboard at all.
    from handeye.mocks.camera import MockCamera

    grabs = []
    grab = MockCamera.grab
    monkeypatch.setattr(MockCamera, "grab", lambda self, *a, **k: grabs.append(1) or grab(self, *a, **k))
    code, data = _verify(station, "blind5", "camera_turn_deg: [-30, 30, 0], board_shift_mm: [100, 100, 100]",
                         config_extra="capture: {retries: 2}\n")
    assert code == 4 and data["verdict"] == "inconclusive"
    assert data["measured"] == 0 and len(grabs) == 1
    out = capsys.readouterr().out
    assert f"board not seen at posture {data['revisited'][0]} " in out and "run verify again" in out
    assert data["reason"].startswith("board not seen at posture")

def test_history_lists_every_check(station, capsys):
    root, session, config = station
    before = (root / "history.jsonl").read_text().splitlines()
    assert main(["verify", "--config", config, "--against", str(session), "--history", "--report",
                 str(root / "trend.html")]) == 0
    out = capsys.readouterr().out
    assert len([line for line in out.splitlines() if line.startswith("  20")]) == len(before)
    assert (root / "trend.html").read_text().count("data:image/png;base64,") == 1
    assert (root / "history.jsonl").read_text().splitlines() == before  # printing never rewrites it

@pytest.mark.parametrize("argv, says, code", [
    (["--postures", "2"], "at least 3", 2),  # a usage error (issue 42.10: it exited 1)
    (["--postures", "99"], "asks for more", 1),  # what SESSION holds
])
def test_bad_requests_are_one_line_and_write_nothing(station, capsys, argv, says, code):
    root, session, config = station
    listing = sorted(p.name for p in root.iterdir())
    assert main(["verify", "--config", config, "--against", str(session), *argv]) == code
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and "Traceback" not in err
    assert sorted(p.name for p in root.iterdir()) == listing

def test_sessions_verify_cannot_check_are_refused(tmp_path, station, capsys):
    root, session, config = station
    simulated = tmp_path / "sim"
    assert main(["simulate", "-o", str(simulated), "--postures", "6"]) == 0
    other = tmp_path / "other.yaml"
    other.write_text(BASE_YAML + "target: {corners: [9, 6], square_mm: 25}\n")
    capsys.readouterr()
    assert main(["verify", "--config", config, "--against", str(simulated)]) == 1
    assert "simulated or imported" in capsys.readouterr().err
    assert main(["verify", "--config", str(other), "--against", str(session)]) == 1
    assert "another board" in capsys.readouterr().err

def test_exit_codes_are_in_the_help(capsys):
    with pytest.raises(SystemExit):
        main(["verify", "--help"])
    out = capsys.readouterr().out
    assert "0 ok, 3 drift, 4 inconclusive" in out and "1 errors" in out


class _RealLink:
    """A link as a real station's holds it: the controller, the camera, the stereo model, the program's loader
    and stop; no mock, no truth (no ``.mock`` at all)."""

    is_mock = False
    rehearsal = None

    def __init__(self, link):
        self.controller, self.camera, self.stereo_model = link.controller, link.camera, link.stereo_model
        self.load_program, self.stop_program = link.load_program, link.stop_program


def test_verify_over_a_link_without_a_mock_reports_the_robot_time(station):
    """The robot time comes from the plan's motion model from where the controller reports the arm, never from
    a mock: over a link without one the check works and says it, and it is the time the simulated arm took."""
    from handeye.station.config.station import load_config
    from handeye.station.runtime import open_station
    from handeye.station.verify.check import verify
    from handeye.station.verify.result import outcome_json

    root, session, config = station
    config = load_config(config)
    with open_station(config, session_dir=session) as link:
        real = _RealLink(link)
        assert not hasattr(real, "mock")
        arm, started = link.mock.arm, link.mock.arm.motion_s
        outcome = verify(config, session, real, 3, confirm=lambda question: True)
        took = (arm.motion_s - started) * arm.speed_fraction  # the simulated arm's own clock, at full axis speed
    assert outcome.measured == 3
    assert outcome.motion_s > 0 and outcome.motion_s == pytest.approx(took, rel=0.02)
    assert 0 < outcome.motion_s < outcome.capture_motion_s
    data = outcome_json(outcome, str(session), None)
    assert data["simulated_robot_time_s"] == outcome.motion_s and data["capture_robot_time_s"] == outcome.capture_motion_s


def _session_copy(session, folder, **recorded):
    """SESSION copied with its recorded station config changed (``section={key: value}``)."""
    import shutil

    import yaml

    copy = folder / session.name
    shutil.copytree(session, copy)
    header = yaml.safe_load((copy / "session.yaml").read_text())
    for section, values in recorded.items():
        header["capture"]["config"][section].update(values)
    (copy / "session.yaml").write_text(yaml.safe_dump(header, sort_keys=False))
    return copy

@pytest.mark.parametrize("recorded, config_text, says", [
    ({}, "controller: {protocol: socket, host: 127.0.0.1, port: 9}\ncamera: {backend: xb3}\n",
     ["another controller: mock (the embedded mock station) there, socket at 127.0.0.1 here",
      "another camera: mock there, xb3 here"]),
    ({"controller": {"protocol": "socket", "host": "10.0.0.5"}, "camera": {"backend": "xb3"}},
     "controller: {protocol: socket, host: 10.0.0.6, port: 9}\ncamera: {backend: xb3}\n",
     ["another controller: socket at 10.0.0.5 there, socket at 10.0.0.6 here"]),
    ({"controller": {"protocol": "socket", "host": "10.0.0.5"}, "camera": {"backend": "xb3", "guid": "00b09d0100a1b2c3"}},
     "controller: {protocol: socket, host: 10.0.0.5, port: 9}\ncamera: {backend: xb3, guid: '00b09d0100a1b2c4'}\n",
     ["another camera: xb3 (guid 00b09d0100a1b2c3) there, xb3 (guid 00b09d0100a1b2c4) here"]),
    ({"controller": {"protocol": "socket", "host": "10.0.0.5"}}, BASE_YAML,
     ["another controller: socket at 10.0.0.5 there, mock (the embedded mock station) here"]),
    ({}, BASE_YAML + "robot: IRB1410\ntarget: {corners: [9, 6], square_mm: 25}\n",
     ["another robot: IRB1400 there, IRB1410 here", "another board: 13x8, 30 mm there, 9x6, 25 mm here"]),
], ids=["mock-session-socket-station", "another-controller-address", "another-xb3", "socket-session-mock-station",
        "robot-and-board"])
def test_a_session_of_another_station_is_refused_before_anything_opens(station, tmp_path, capsys, recorded,
                                                                      config_text, says):
    # issue 42.4: a mock session against a socket station moved the robot and advised writing the other
    # cell's camera; refused in one line saying what differs, with --yes too, before any link opens
    root, session, _ = station
    against = _session_copy(session, tmp_path, **recorded) if recorded else session
    config = tmp_path / "station.yaml"
    config.write_text(config_text)
    listing = sorted(p.name for p in root.iterdir())
    capsys.readouterr()
    assert main(["verify", "--config", str(config), "--against", str(against), "--yes"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "captured on another station" in err and "nothing moved" in err
    assert all(part in err for part in says), err
    assert sorted(p.name for p in root.iterdir()) == listing and sorted(p.name for p in tmp_path.iterdir()) == \
        sorted(["station.yaml"] + ([against.name] if recorded else []))

def _edit_postures(session, folder, numbers, edit):
    """SESSION copied with ``edit(posture mapping)`` applied to the posture files ``numbers``."""
    import yaml

    copy = _session_copy(session, folder)
    for number in numbers:
        path = copy / "postures" / f"{number:03d}.yaml"
        posture = yaml.safe_load(path.read_text())
        edit(posture)
        path.write_text(yaml.safe_dump(posture, sort_keys=False))
    return copy

def _turn_axis_1(posture):
    posture["joints_deg"][0] += 1.0

@pytest.mark.parametrize("edit, says", [
    (_turn_axis_1, "the joint angles of postures 3, 7 (2 of 14) do not reproduce their flange poses"),
    (lambda posture: posture.pop("joints_deg"), "postures 3, 7 hold no joint angles"),
], ids=["joints-disagree", "joints-missing"])
def test_joints_that_disagree_with_the_flange_poses_are_refused_before_anything_moves(station, tmp_path, capsys,
                                                                                        edit, says):
    # issue 42.5: 1 deg added to axis 1 in two posture files moved the robot, then "unexpected ValueError"
    root, session, config = station
    against = _edit_postures(session, tmp_path, (3, 7), edit)
    capsys.readouterr()
    assert main(["verify", "--config", config, "--against", str(against)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and "nothing moved" in err and "unexpected" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [against.name]  # no check session, no history beside it

def test_calibrate_warns_naming_the_postures_whose_joints_disagree(station, tmp_path, capsys):
    root, session, _ = station
    against = _edit_postures(session, tmp_path, (3, 7), _turn_axis_1)
    out = tmp_path / "result.json"
    capsys.readouterr()
    assert main(["calibrate", str(against), "--json", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("handeye calibrate: warning: the joint angles of postures 3, 7 ")
    reason = json.loads(out.read_text())["details"]["kinematics"]["reason"]
    assert "postures 3, 7" in reason and "flange poses instead of the joints" in reason

@pytest.mark.parametrize("shift_mm, config_extra, verdict", [
    (0.05, "", "ok"),                                   # detectable, below the default 0.2 mm
    (0.05, "verify: {tolerance_mm: 0.03}\n", "drift"),  # the station's own tolerance
    (0.3, "", "drift"),                                 # above the default
], ids=["below-default", "above-station-tolerance", "above-default"])
def test_drift_means_beyond_the_noise_and_beyond_the_tolerance(station, capsys, shift_mm, config_extra, verdict):
    # issue 42.7: a 0.05 mm camera shift was DRIFT (chi2 in the thousands) against a calibration whose
    # one-sigma is 0.03 mm: the output states the statistic and the size against the tolerance
    code, data = _verify(station, f"small{shift_mm}{bool(config_extra)}", f"camera_shift_mm: [{shift_mm}, 0, 0]",
                         config_extra=config_extra)
    out = capsys.readouterr().out
    assert data["verdict"] == verdict and code == {"ok": 0, "drift": 3}[verdict]
    assert data["test"]["statistically_detectable"] is True and data["test"]["p_value"] < 0.01
    size, tolerance = data["size"], data["tolerance"]
    assert size["cause"] == "camera" and size["translation_mm"] == pytest.approx(shift_mm, rel=0.3)
    assert tolerance["translation_mm"] == (0.03 if config_extra else 0.2) and tolerance["rotation_deg"] == 0.02
    assert ("verify.tolerance_mm" in tolerance["source"]) == bool(config_extra)
    assert data["beyond_tolerance"] is (verdict == "drift") and size["beyond_tolerance"] is (verdict == "drift")
    assert f"chi2 {data['test']['statistic']:.1f} on 30 degrees of freedom" in data["reason"]
    if verdict == "ok":
        assert data["diagnosis"]["cause"] == "none" and data["quick_update"] is None
        assert "statistically detectable" in out and "within the tolerance 0.2 mm / 0.02 deg" in out
        assert "nothing to do" in out and "writeback" not in out
    else:
        assert data["diagnosis"]["cause"] == "camera" and "beyond the tolerance" in out

@pytest.mark.parametrize("level", ["1e-300", "0", "0.5", "nan", "1e-7"])
def test_a_level_outside_its_range_is_a_usage_error(station, capsys, level):
    root, session, config = station
    assert main(["verify", "--config", config, "--against", str(session), "--level", level]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--level must be between 1e-06 and 0.2" in err


def test_a_link_failure_after_three_postures_counts_them(station, capsys, monkeypatch):
    # issue 42.10: the JSON said "measured": 0 after 3 postures were measured and written
    from handeye.drivers.errors import StationError
    from handeye.station.capture import loop as capture

    real, calls = capture._capture_posture, []

    def fourth_fails(*args, **kwargs):
        calls.append(1)
        if len(calls) == 4:
            raise StationError("the link dropped (test)")
        return real(*args, **kwargs)

    monkeypatch.setattr(capture, "_capture_posture", fourth_fails)
    code, data = _verify(station, "dropped", "")
    assert code == 4 and data["verdict"] == "inconclusive" and "the link failed" in data["reason"]
    assert data["measured"] == 3
    assert len(list((Path(data["check_session"]) / "postures").glob("*.yaml"))) == 3


def test_after_a_quick_update_is_written_verify_follows_it_and_never_advises_undoing_it(station, capsys):
    # issue 42.2: verify -> DRIFT camera -> writeback of the quick update -> verify against the same session said
    # DRIFT/tooldata and "restore it (handeye writeback SESSION ...)", putting back a tool 1 mm off
    root, session, config = station
    faults = "camera_shift_mm: [0.8, -0.6, 0.4]"
    code, data = _verify(station, "moved", faults)
    assert code == 3 and data["diagnosis"]["cause"] == "camera" and data["quick_update"]["within_thresholds"]
    folder = data["check_session"]
    assert main(["writeback", folder, "--config", config]) == 0
    capsys.readouterr()
    try:
        code, data = _verify(station, "moved-again", faults)  # the camera stays where the update put it
        out = capsys.readouterr().out
        assert data["diagnosis"]["cause"] != "tooldata" and f"handeye writeback {session} " not in out
        assert "restore it" not in out and "checking against the quick update written from" in out
        assert code == 0 and data["verdict"] == "ok", out
        assert data["reference"]["kind"] == "update" and data["reference"]["written_from"].endswith(
            str(folder).split("/")[-1])
        assert main(["verify", "--config", config, "--against", folder]) == 1  # the update's folder: where to go
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"verify --against {session}" in err
    finally:
        assert main(["writeback", str(session), "--config", config]) == 0  # SESSION's tool data back, and followed
    code, data = _verify(station, "back", "")
    assert code == 0 and data["reference"]["kind"] == "session"


def test_a_result_older_than_its_postures_is_refused_before_anything_opens(station, tmp_path, capsys):
    root, session, config = station
    assert (session / "result.yaml").is_file()  # saved by the fixture's writeback (it had none: solved and saved)

    def nudge(posture):
        posture["points_mm"][0][0] += 0.01

    against = _edit_postures(session, tmp_path, (2,), nudge)
    capsys.readouterr()
    assert main(["verify", "--config", config, "--against", str(against)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is older than the session's postures" in err
    assert f"run handeye calibrate {against}" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [against.name]  # no check session, no history
