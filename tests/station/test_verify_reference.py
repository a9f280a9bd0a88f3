"""Which write-back a check follows (``station.verify.reference``), and the tooldata advice it gives: it never
advises undoing the latest deliberate write-back (issue 42.2). The whole path on the mock station is in
``test_verify.py``; here the history's cases the station test does not reach."""

from __future__ import annotations

import json

from handeye.station.verify.history import append_record, history_path
from handeye.station.verify.reference import follow, lineage
from handeye.station.verify.result import _tooldata_advice

HELD = {"position_mm": [-118.0, 34.5, 92.0], "quaternion_wxyz": [0.703087, 0.01412, -0.018827, 0.710715]}
SESSION_TOOL = {"position_mm": [-117.0, 34.5, 92.0], "quaternion_wxyz": HELD["quaternion_wxyz"]}


def _sessions(tmp_path, *names):
    for name in names:
        (tmp_path / name).mkdir()
        (tmp_path / name / "session.yaml").write_text("format: handeye-session/1\n")
    return [tmp_path / name for name in names]


def _written(folder, of, tool=HELD):
    append_record(history_path(folder), {"kind": "writeback", "session": str(folder.resolve()), "of": str(of.resolve()),
                                         "what": "calibration written (ml)", "readback_ok": True, "tool": tool})


def test_without_a_write_back_or_after_sessions_own_the_check_is_against_session(tmp_path):
    cal, = _sessions(tmp_path, "cal_01")
    assert follow(cal).kind == "session"
    _written(cal, cal)
    assert follow(cal).kind == "session" and follow(cal).line() is None


def test_a_check_folder_descends_from_its_session(tmp_path):
    cal, = _sessions(tmp_path, "cal_01")
    check = tmp_path / "cal_01-verify-20261206-101500"
    check.mkdir()
    assert lineage(check) == str(cal.resolve())
    (check / "verify.json").write_text(json.dumps({"session": "cal_01"}))  # relative, as given on another cwd
    assert lineage(check) == str(cal.resolve())


def test_after_another_sessions_write_back_the_advice_is_to_check_that_one_not_to_restore(tmp_path):
    cal1, cal2 = _sessions(tmp_path, "cal_01", "cal_02")
    _written(cal1, cal1, SESSION_TOOL)
    _written(cal2, cal2)  # cal_02 written on purpose after cal_01
    reference = follow(cal1)
    assert reference.kind == "other" and reference.folder == str(cal2.resolve())
    diag = {"held": HELD, "session": SESSION_TOOL}
    line = _tooldata_advice(reference, diag, str(cal1), "--mock")
    assert "restore it" not in line and "handeye writeback" not in line
    assert f"handeye verify --against {cal2.resolve()} --mock" in line and "nothing to restore" in line
    moved = dict(HELD, position_mm=[-110.0, 34.5, 92.0])  # neither wrote what the robot holds: restore the latest
    line = _tooldata_advice(reference, {"held": moved, "session": SESSION_TOOL}, str(cal1), "--mock")
    assert f"restore that one (handeye writeback {cal2.resolve()} --mock)" in line


def test_with_sessions_own_write_back_latest_the_advice_restores_session(tmp_path):
    cal, = _sessions(tmp_path, "cal_01")
    _written(cal, cal, SESSION_TOOL)
    line = _tooldata_advice(follow(cal), {"held": HELD, "session": SESSION_TOOL}, str(cal), "--mock")
    assert f"restore it (handeye writeback {cal} --mock)" in line
