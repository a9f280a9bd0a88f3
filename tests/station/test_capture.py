"""Guided capture against the embedded mock station, over real sockets."""

import os
import signal
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest
import yaml

from handeye.calibration.session import read_session
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.geometry.transforms import rotation_error_deg, translation_error_mm
from handeye.station.capture.loop import capture
from handeye.station.config.station import default_config
from handeye.station.runtime import open_station


def _config(postures):
    config = default_config()
    return replace(config, plan=replace(config.plan, postures=postures))


def _indices(session_dir):
    return sorted(p.index for p in read_session(session_dir).postures)


def test_capture_plans_programs_and_measures(tmp_path, no_leaked_threads):
    config = _config(8)
    with open_station(config, mock=True) as link:
        summary = capture(config, tmp_path / "s", link)
        truth = link.truth_cam2tool0
    assert summary.complete and summary.captured == list(range(8)) and not summary.skipped
    session = read_session(tmp_path / "s")
    assert [p.index for p in session.postures] == list(range(8))
    assert all(p.points_mm.shape == (104, 3) and p.extra["quality"]["corners"] == 104 for p in session.postures)
    record = session.extra["capture"]
    assert len(record["plan_joints_deg"]) == 8 and record["plan_score"]["rotation_axis_spread_deg"] > 0
    assert sorted(f.name for f in (tmp_path / "s" / "rapid").iterdir()) == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    # the joints the robot reported are the planned ones, and the measurements calibrate
    for p, planned in zip(session.postures, record["plan_joints_deg"]):
        assert np.allclose(p.joints_deg, planned, atol=1e-3)
    result = calibrate(problem_from_session(session))
    assert rotation_error_deg(result.x, truth) < 0.1 and translation_error_mm(result.x, truth) < 1.0


def test_resume_after_a_crash_between_grab_and_acknowledge(tmp_path, no_leaked_threads):
    config = _config(6)
    with open_station(config, mock=True) as link:
        real_ack = link.controller.acknowledge
        calls = []

        def crash_on_third(k, *args, **kwargs):
            calls.append(k)
            if len(calls) == 3:
                raise KeyboardInterrupt  # the PC dies after writing posture 3, before its ACK
            return real_ack(k, *args, **kwargs)

        link.controller.acknowledge = crash_on_third
        with pytest.raises(KeyboardInterrupt):
            capture(config, tmp_path / "s", link)
        assert _indices(tmp_path / "s") == [0, 1, 2]
        status = link.controller.status()
        assert status.awaiting_ack and status.posture == 3  # the robot still waits at posture 3
        link.controller.acknowledge = real_ack
        messages = []
        summary = capture(config, tmp_path / "s", link, progress=messages.append)
    assert summary.already == [0, 1, 2] and summary.captured == [3, 4, 5]  # the postures' file numbers
    assert "posture 2 was already on disk: acknowledged" in messages  # file 002, the controller's posture 3
    assert _indices(tmp_path / "s") == list(range(6))


def test_postures_that_fail_quality_are_skipped_with_the_reason(tmp_path, no_leaked_threads):
    config = _config(3)  # a posture that fails costs every search stage of OpenCV, three times: few of them
    with open_station(config, mock=True) as link:
        first = capture(config, tmp_path / "s", link, stop_after=2)
        assert first.captured == [0, 1]
        board = link.mock.truth["board2base"].copy()
        board[:3, 3] += [0.0, 2000.0, 0.0]  # someone moved the board away
        link.camera.set_scene(target2base=board)
        second = capture(config, tmp_path / "s", link)
    assert second.captured == [] and sorted(second.skipped) == [2]
    assert all("skipped after 3 attempt(s)" in reason for reason in second.skipped.values())
    header = yaml.safe_load((tmp_path / "s" / "session.yaml").read_text())
    assert sorted(header["capture"]["skipped"]) == ["2"]
    assert _indices(tmp_path / "s") == [0, 1]


def test_a_killed_capture_restarts_and_finishes_every_posture_once(tmp_path):
    """The real command in a subprocess, killed (SIGKILL) mid-run, then run again."""
    session = tmp_path / "s"
    command = [sys.executable, "-m", "handeye.station", "capture", "--mock", "--session", str(session), "--postures", "10"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    try:
        while time.monotonic() < deadline:
            if len(list((session / "postures").glob("*.yaml"))) >= 3 or process.poll() is not None:
                break
            time.sleep(0.05)
    finally:
        os.kill(process.pid, signal.SIGKILL)
        process.wait()
    before = _indices(session)  # reads and validates every file: none is half-written
    assert 3 <= len(before) < 10, before
    yaml.safe_load((session / "session.yaml").read_text())
    # a kill between writing a temporary file and renaming it may leave that temporary beside the whole
    # target; the resume removes it
    again = subprocess.run(command, capture_output=True, text=True, timeout=180)
    assert again.returncode == 0, again.stderr
    assert "resuming" in again.stdout
    assert not list(session.rglob("*.tmp"))
    assert _indices(session) == list(range(10))
    controller_posture = [p.extra["controller_posture"] for p in read_session(session).postures]
    assert controller_posture == list(range(1, 11))  # file NNN: the program's jtHePost<NNN + 1>
