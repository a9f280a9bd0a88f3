"""The cell's outbox and the fleet's table, without a broker: numbers only grow, each event is one
atomic file, a resent event is kept once, and the alarms say what the events show."""

from __future__ import annotations

import json
import time

from handeye.station.plant.fleet import fleet_table
from handeye.station.plant.fleet_config import fleet_from_dict
from handeye.station.plant.outbox import Outbox
from handeye.station.plant.store import History


def test_numbers_grow_across_delivery_and_a_lost_rename(tmp_path):
    outbox = Outbox(tmp_path / "out")
    assert [outbox.add({"n": n})["seq"] for n in range(3)] == [1, 2, 3]
    (seq, first), *_ = outbox.pending()
    copy = first.read_bytes()
    outbox.done(first)
    assert outbox.last_seq() == 1 and [s for s, _ in outbox.pending()] == [2, 3]
    for _, path in outbox.pending():
        outbox.done(path)
    assert outbox.pending() == [] and outbox.add({"n": 9})["seq"] == 4  # none pending: the last sent counts
    first.write_bytes(copy)  # a crash lost the rename of #1: it waits again, the next number is still 5
    assert [s for s, _ in outbox.pending()] == [1, 4] and outbox.add({})["seq"] == 5
    assert json.loads((tmp_path / "out" / "000000000004.json").read_text())["n"] == 9
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".")]  # no temporary file left


def test_the_history_keeps_an_event_once(tmp_path):
    history = History(tmp_path / "h.sqlite")
    assert history.add("a/b/c/d/e", {"seq": 1, "kind": "calibrate"})
    assert not history.add("a/b/c/d/e", {"seq": 1, "kind": "calibrate", "again": True})
    assert history.add("a/b/c/d/f", {"seq": 1}) and history.count() == 2
    assert History(tmp_path / "h.sqlite").events("a/b/c/d/e")[0].get("again") is None  # on disk, the first


def _events(history, cell, *events):
    for seq, event in enumerate(events, 1):
        history.add(cell, dict(event, seq=seq, topic_prefix=cell))


def test_the_alarms_follow_the_events():
    fleet = fleet_from_dict({"verify_interval_h": 24, "stale_after_h": 1, "drift_alarm_mm": 0.5})
    history, now = History(":memory:"), time.time()
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(now))
    cal = {"kind": "calibrate", "camera_serial": "A", "time": stamp, "predicted_error_mm": 0.3, "verdict": "pass"}
    _events(history, "p/s/a/l/quiet", cal, {"kind": "verify", "verdict": "ok", "camera_serial": "A", "time": stamp,
                                            "size": {"translation_mm": 0.01}})
    _events(history, "p/s/a/l/serial", cal, {"kind": "verify", "verdict": "ok", "camera_serial": "B", "time": stamp})
    _events(history, "p/s/a/l/drift", cal, {"kind": "verify", "verdict": "drift", "time": stamp,
                                            "diagnosis": {"cause": "joint", "translation_mm": 0.7}})
    _events(history, "p/s/a/l/tool", cal, {"kind": "writeback", "verdict": "readback_differs", "time": stamp})
    old = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(now - 30 * 3600))
    history.add("p/s/a/l/old", dict(cal, seq=1, time=old), received=now - 30 * 3600)
    rows = {row["cell"].rsplit("/", 1)[1]: row for row in fleet_table(history, fleet, now)["cells"]}
    assert rows["quiet"]["alarms"] == [] and rows["quiet"]["drift_trend_mm"] == [0.01]
    assert 23.9 < rows["quiet"]["verify_due_in_h"] <= 24 and rows["quiet"]["predicted_error_mm"] == 0.3
    assert rows["serial"]["alarms"] == ["camera serial changed: A -> B since the last calibration"]
    assert rows["drift"]["alarms"] == ["drift: 0.700 mm (joint)"]
    assert rows["tool"]["alarms"] == ["tooldata mismatch: the controller holds another camera tooldata than the calibration"]
    assert [a.split(":")[0].split(" by")[0] for a in rows["old"]["alarms"]] == ["verify overdue", "stopped reporting"]


def test_a_bad_plant_yaml_is_one_line_naming_the_key(tmp_path, capsys):
    from handeye.station.cli import main

    config = tmp_path / "plant.yaml"
    for text, words in (("mqtt: {hots: x}\n", "unknown key mqtt.hots"), ("cells: a/b\n", "cells must be 5 topic levels"),
                        ("verify_interval_h: 0\n", "verify_interval_h must be between")):
        config.write_text(text)
        assert main(["plant", "--config", str(config)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"handeye plant: error: {config}: {words}"), err


def test_an_outbox_that_cannot_be_written_is_one_warning(tmp_path, capsys):
    from handeye.station.plant.hooks import publish_event
    from handeye.station.plant.settings import plant_rule

    (tmp_path / "file").write_text("not a folder")
    plant = plant_rule({"outbox": str(tmp_path / "file" / "out"), "publish_timeout_s": 0.2,
                        "mqtt": {"host": "127.0.0.1", "port": 1, "topic_prefix": "a/b/c/d/e"}}, "plant", {})
    publish_event("verify", plant, lambda: {"topic_prefix": "a/b/c/d/e"})
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("handeye verify: warning: plant: the event was not published"), err
