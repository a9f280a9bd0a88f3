"""The plant's publishing against a real mosquitto on 127.0.0.1 (TLS, passwords, an ACL): events reach
the fleet's history exactly once and in order across a broker stopped mid-stream; a cell cannot publish
under another cell's topic; a broker fault is one warning line and never fails the command."""

from __future__ import annotations

import dataclasses
import signal
import time

import pytest
import yaml

from plant_broker import MOSQUITTO_MISSING, PREFIX, Broker

from handeye.station.plant.fleet_config import fleet_from_dict
from handeye.station.plant.hooks import publish_event
from handeye.station.plant.outbox import Outbox
from handeye.station.plant.publisher import deliver
from handeye.station.plant.settings import plant_rule
from handeye.station.plant.store import History
from handeye.station.plant.subscriber import FleetSubscriber

pytestmark = pytest.mark.skipif(MOSQUITTO_MISSING is not None, reason=MOSQUITTO_MISSING or "")


@pytest.fixture
def broker(tmp_path):
    b = Broker(tmp_path / "broker", cells=("cell01", "cell02")).start()
    yield b
    b.stop()


def _fleet(broker, history):
    return FleetSubscriber(fleet_from_dict({"mqtt": broker.fleet_mqtt()}), history).start()


def _plant(broker, cell, tmp_path, **extra):
    return plant_rule(broker.cell_plant(cell, tmp_path / f"outbox-{cell}", **extra), "plant", {})


def _wait(condition, timeout_s=10.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def _event(plant, n):
    return {"topic_prefix": plant.mqtt.topic_prefix, "kind": "calibrate", "n": n}


def test_events_reach_the_fleet_once_and_in_order_across_a_broker_restart(broker, tmp_path, capsys):
    history = History(tmp_path / "history.sqlite")
    fleet = _fleet(broker, history)
    plant = _plant(broker, "cell01", tmp_path)
    cell = plant.mqtt.topic_prefix
    for n in range(1, 4):
        publish_event("calibrate", plant, lambda n=n: _event(plant, n))
    assert capsys.readouterr().err == ""
    broker.stop(signal.SIGTERM)  # mid-stream: the next events wait in the outbox
    for n in range(4, 7):
        publish_event("verify", plant, lambda n=n: _event(plant, n))
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("handeye verify: warning: plant: broker 127.0.0.1:") for line in err)
    assert "not reachable" in err[0] and f"event(s) wait in {tmp_path / 'outbox-cell01'}" in err[0]
    assert len(Outbox(plant.outbox_dir()).pending()) == 3
    broker.start()
    for n in range(7, 11):
        publish_event("calibrate", plant, lambda n=n: _event(plant, n))
    assert Outbox(plant.outbox_dir()).pending() == []
    assert _wait(lambda: len(history.events(cell)) == 10), history.events(cell)
    arrived = [e["seq"] for e in history.events(cell, by_arrival=True)]
    assert arrived == list(range(1, 11)) and [e["n"] for e in history.events(cell)] == list(range(1, 11))
    assert _wait(lambda: (history.state(cell) or {}).get("seq") == 10)
    fleet.stop()


def test_an_event_sent_again_after_a_crash_is_kept_once(broker, tmp_path):
    history = History(":memory:")
    fleet = _fleet(broker, history)
    plant = _plant(broker, "cell01", tmp_path)
    outbox = Outbox(plant.outbox_dir())
    first = outbox.add(_event(plant, 1))
    kept = outbox.pending()[0][1].read_bytes()
    assert deliver(plant, outbox).sent == 1
    (outbox.folder / f"{first['seq']:012d}.json").write_bytes(kept)  # the crash came between the ack and the removal
    outbox.add(_event(plant, 2))
    assert deliver(plant, outbox).sent == 2
    assert _wait(lambda: len(history.events(plant.mqtt.topic_prefix)) == 2 and fleet.duplicates == 1)
    assert [e["seq"] for e in history.events(plant.mqtt.topic_prefix, by_arrival=True)] == [1, 2]
    fleet.stop()


def test_a_cell_cannot_publish_under_another_cells_topic(broker, tmp_path):
    """The ACL (tests/plant_broker.acl_text, as docs/plant.md documents it): cell01's credentials on cell02's
    topic are dropped by the broker; cell02's own events arrive."""
    history = History(":memory:")
    fleet = _fleet(broker, history)
    own = _plant(broker, "cell01", tmp_path)
    intruder = dataclasses.replace(own, mqtt=dataclasses.replace(own.mqtt, topic_prefix=f"{PREFIX}/cell02"))
    publish_event("calibrate", intruder, lambda: _event(intruder, 1))
    honest = _plant(broker, "cell02", tmp_path)
    publish_event("calibrate", honest, lambda: dict(_event(honest, 2)))
    assert _wait(lambda: len(history.events(f"{PREFIX}/cell02")) == 1)
    time.sleep(0.3)
    assert [e["n"] for e in history.events(f"{PREFIX}/cell02")] == [2]  # cell01's forgery never arrived
    fleet.stop()


def test_a_payload_naming_another_cell_is_not_kept(broker, tmp_path):
    history = History(":memory:")
    fleet = _fleet(broker, history)
    plant = _plant(broker, "cell01", tmp_path)
    publish_event("calibrate", plant, lambda: {"topic_prefix": f"{PREFIX}/cell02", "kind": "calibrate"})
    publish_event("calibrate", plant, lambda: _event(plant, 2))
    assert _wait(lambda: len(history.events(plant.mqtt.topic_prefix)) == 1 and fleet.rejected == 2)  # the event and the state it left
    assert history.cells() == [plant.mqtt.topic_prefix]
    fleet.stop()


@pytest.mark.parametrize("change, words", [
    (lambda m: dataclasses.replace(m, password="wrong-password"), "refused the connection"),
    (lambda m: dataclasses.replace(m, tls=dataclasses.replace(m.tls, ca="/etc/ssl/certs/ca-certificates.crt")),
     "not reachable"),
    (lambda m: dataclasses.replace(m, tls=dataclasses.replace(m.tls, ca="/nonexistent/ca.pem")), "no file"),
])
def test_a_broker_that_refuses_us_is_one_warning_and_the_event_waits(broker, tmp_path, capsys, change, words):
    plant = _plant(broker, "cell01", tmp_path)
    plant = dataclasses.replace(plant, mqtt=change(plant.mqtt))
    publish_event("writeback", plant, lambda: _event(plant, 1))
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("handeye writeback: warning: plant: ") and words in err[0]
    assert len(Outbox(plant.outbox_dir()).pending()) == 1


def test_plain_tcp_with_a_password_works_too(broker, tmp_path):
    history = History(":memory:")
    fleet = FleetSubscriber(fleet_from_dict({"mqtt": broker.fleet_mqtt(tls=False)}), history).start()
    plant = _plant(broker, "cell02", tmp_path, tls=False)
    publish_event("calibrate", plant, lambda: _event(plant, 1))
    assert _wait(lambda: len(history.events(plant.mqtt.topic_prefix)) == 1)
    fleet.stop()


def _station_file(tmp_path, broker, cell="cell01", **plant_extra) -> str:
    path = tmp_path / "station.yaml"
    path.write_text(yaml.safe_dump({"controller": {"protocol": "mock"}, "camera": {"backend": "mock"},
                                    "plant": broker.cell_plant(cell, tmp_path / f"outbox-{cell}", **plant_extra)}))
    return str(path)


def test_the_commands_publish_their_events(broker, tmp_path, capsys):
    """demo, then writeback --config (with plant:) and calibrate of a session whose capture recorded plant:."""
    from handeye.station.cli import main

    history = History(":memory:")
    fleet = _fleet(broker, history)
    assert main(["demo", "--session", str(tmp_path / "demo"), "--postures", "14", "--no-report"]) == 0
    session = tmp_path / "demo" / "session"
    station = _station_file(tmp_path, broker)
    assert main(["writeback", str(session), "--config", station]) == 0
    head = yaml.safe_load((session / "session.yaml").read_text())
    head["capture"]["config"]["plant"] = yaml.safe_load(open(station))["plant"]  # as a capture with plant: records it
    (session / "session.yaml").write_text(yaml.safe_dump(head))
    assert main(["calibrate", str(session), "--quiet", "--json", str(tmp_path / "r.json")]) == 0
    assert "warning" not in capsys.readouterr().err
    cell = f"{PREFIX}/cell01"
    assert _wait(lambda: len(history.events(cell)) == 2)
    writeback, calibrate = history.events(cell)
    assert writeback["kind"] == "writeback" and writeback["verdict"] == "written" and writeback["result"]["mock"]
    assert calibrate["kind"] == "calibrate" and calibrate["verdict"] is None and calibrate["session"] == "session"
    from handeye.station.plant.events import session_hash

    assert calibrate["session_hash"] == session_hash(session) != writeback["session_hash"]  # session.yaml edited between
    assert calibrate["camera_serial"] == "mock" and calibrate["board"] == {"corners": [13, 8], "square_mm": 30.0}
    assert 0 < calibrate["predicted_error_mm"] < 1.0 and calibrate["uncertainty"]["translation_mm"]
    fleet.stop()


def test_a_command_with_the_broker_down_still_succeeds_with_one_warning(broker, tmp_path, capsys):
    from handeye.station.cli import main

    assert main(["demo", "--session", str(tmp_path / "demo"), "--postures", "14", "--no-report"]) == 0
    capsys.readouterr()
    broker.stop()
    assert main(["writeback", str(tmp_path / "demo" / "session"), "--config", _station_file(tmp_path, broker)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "handeye writeback: warning: plant: broker" in err[0] and "not reachable" in err[0]


def test_verify_publishes_its_verdict(broker, tmp_path):
    from handeye.station.cli import main

    history = History(":memory:")
    fleet = _fleet(broker, history)
    assert main(["demo", "--session", str(tmp_path / "demo"), "--postures", "14", "--no-report"]) == 0
    code = main(["verify", "--config", _station_file(tmp_path, broker, "cell02"), "--against",
                 str(tmp_path / "demo" / "session"), "--yes", "--postures", "3"])
    assert code in (0, 3, 4)
    assert _wait(lambda: len(history.events(f"{PREFIX}/cell02")) == 1)
    (event,) = history.events(f"{PREFIX}/cell02")
    assert event["kind"] == "verify" and event["verdict"] == {0: "ok", 3: "drift", 4: "inconclusive"}[code]
    assert event["diagnosis"]["cause"] is not None and event["session"] == "session"
    fleet.stop()


def test_a_broker_that_never_answers_costs_the_budget_and_one_warning(tmp_path, capsys):
    import socket

    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen(5)  # accepts the connection, never says anything
    plant = plant_rule({"outbox": str(tmp_path / "out"), "publish_timeout_s": 0.3,
                        "mqtt": {"host": "127.0.0.1", "port": silent.getsockname()[1], "topic_prefix": f"{PREFIX}/cell01"}},
                       "plant", {})
    try:
        publish_event("calibrate", plant, lambda: _event(plant, 1))
    finally:
        silent.close()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did not answer" in err[0] and len(Outbox(plant.outbox_dir()).pending()) == 1
