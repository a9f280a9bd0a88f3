"""``capture --mock --guided`` rehearses the guided flow end to end (issue 25, finding 7b): the embedded
mock has no pendant, so a simulated operator jogs its arm through planned postures, says so on MOCK
lines and ends the run; a rehearsal config whose standalone mock is not there fails in one line (its operator
plays through the mock's --pendant-port: tests/station/test_guided_pendant.py)."""

import threading

import yaml

from handeye.calibration.session import read_session
from handeye.station.cli import main

MOCK = {"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}


def _run_in_thread(argv, timeout_s=150.0):
    """``main(argv)`` in a thread of its own; (finished, exit code): the old code waited forever."""
    outcome = {}
    thread = threading.Thread(target=lambda: outcome.setdefault("rc", main(argv)), daemon=True)
    thread.start()
    thread.join(timeout_s)
    return not thread.is_alive(), outcome.get("rc")


def test_the_mock_guided_capture_drives_itself_and_ends(tmp_path, capsys):
    station = tmp_path / "station.yaml"
    station.write_text(yaml.safe_dump({**MOCK, "guided": {"still_s": 0.3, "poll_s": 0.03},
                                       "mock": {"time_scale": 0.005}}))
    finished, rc = _run_in_thread(["capture", "--config", str(station), "--session", str(tmp_path / "g"), "--guided",
                                   "--postures", "4"])
    out = capsys.readouterr().out
    assert finished, "the guided capture on the embedded mock waited for an operator nobody plays"
    assert rc == 0
    lines = out.splitlines()
    assert any(line.startswith("MOCK the embedded mock station has no pendant: a simulated operator plans 4 postures")
               for line in lines)
    assert "MOCK operator (simulated): jogging to rest point 1 of 4 (the capture numbers what it takes)" in lines
    assert "MOCK operator (simulated): all 4 postures visited; ending the run as Ctrl-C would" in lines
    assert all(line.startswith("MOCK") for line in lines if line.strip())  # one message a line, each tagged
    session = read_session(tmp_path / "g")
    assert [p.index for p in session.postures] == [0, 1, 2, 3]
    assert f"MOCK next: handeye calibrate {tmp_path / 'g'} --report" in lines


def test_a_rehearsal_guided_capture_without_its_mock_fails_in_one_line(tmp_path, capsys):
    station = tmp_path / "station.yaml"
    station.write_text(yaml.safe_dump({"controller": {"protocol": "socket", "port": 1, "timeout_s": 0.5},
                                       "camera": {"backend": "mock", "mock_arm": "127.0.0.1:9"}}))
    finished, rc = _run_in_thread(["capture", "--config", str(station), "--session", str(tmp_path / "g"), "--guided"], 60)
    err = capsys.readouterr().err
    assert finished and rc != 0
    assert err.count("\n") == 1 and "127.0.0.1:9" in err
    assert not (tmp_path / "g").exists()
