"""How a capture run ends (issue 42, finding 10): a guided run with no posture fails in one line saying so and
what to do (never "next: handeye calibrate"); the live page of a finished run says it finished (not "capture 3
more", not "moving to posture 11"), of a stopped one that it stopped; the page listens on IPv6 hosts too."""

from __future__ import annotations

import json
import socket
import urllib.request

import pytest

from handeye.drivers.camera.stereo import nominal_xb3_model
from handeye.station.cli import main
from handeye.station.config.station import default_config
from handeye.station.view.hub import ViewHub
from handeye.station.view.server import ViewServer


def _stopped_at_once(monkeypatch):
    """The guided loop runs with its stop already set: the operator ended it before any posture."""
    from handeye.station.guided import capture as guided

    real = guided.guided_capture

    def ended_at_once(config, session_dir, link, **kwargs):
        kwargs["stop"].set()
        return real(config, session_dir, link, **kwargs)

    monkeypatch.setattr(guided, "guided_capture", ended_at_once)


def test_a_guided_run_with_no_posture_fails_saying_nothing_was_captured(tmp_path, capsys, monkeypatch):
    _stopped_at_once(monkeypatch)
    session = tmp_path / "g"
    assert main(["capture", "--mock", "--session", str(session), "--guided", "--postures", "3"]) == 1
    out, err = capsys.readouterr()
    assert err.count("\n") == 1 and err.startswith("handeye capture: error: nothing was captured into "), err
    assert "show the camera the whole board" in err and "run the same command again" in err
    assert "next: handeye calibrate" not in out + err
    assert "0 postures captured this run (0 before)" in out


def _final_states(monkeypatch) -> list:
    """Every state the live view publishes, as JSON."""
    states, real = [], ViewHub._publish_state

    def publish(self):
        real(self)
        states.append(json.loads(self.state_json))

    monkeypatch.setattr(ViewHub, "_publish_state", publish)
    return states


def test_a_finished_planned_capture_page_says_finished(tmp_path, capsys, monkeypatch):
    states = _final_states(monkeypatch)
    session = tmp_path / "p"
    assert main(["capture", "--mock", "--session", str(session), "--postures", "3", "--view", "--yes"]) == 0
    out = capsys.readouterr().out
    last = states[-1]
    assert last["ended"] == {"text": last["ended"]["text"], "ok": True}
    assert last["hint"]["text"].startswith("FINISHED: 3 of 3 postures in ")
    assert f"next: handeye calibrate {session} --report" in last["hint"]["text"]
    assert f"MOCK next: handeye calibrate {session} --report" in out.splitlines()
    assert last["prompt"]["kind"] == "ended" and "moving to posture" not in last["prompt"]["text"]
    assert last["plan"]["current"] is None
    assert not any("more" in line for line in last["missing"])  # the shortfalls, without "capture N more"
    assert any(line.startswith("postures 3 (needs >= 15)") for line in last["missing"])


def test_a_guided_run_with_no_posture_page_says_it_stopped_and_why(tmp_path, capsys, monkeypatch):
    _stopped_at_once(monkeypatch)
    states = _final_states(monkeypatch)
    assert main(["capture", "--mock", "--session", str(tmp_path / "g"), "--guided", "--postures", "3", "--view"]) == 1
    capsys.readouterr()
    assert states[-1]["ended"]["ok"] is False
    assert states[-1]["hint"]["text"].startswith("STOPPED: ") and "nothing was captured" in states[-1]["hint"]["text"]


def test_a_view_closed_without_the_commands_last_word_says_stopped():
    hub = ViewHub(default_config().as_mock(), nominal_xb3_model()).start()
    hub.close()
    state = json.loads(hub.state_json)
    assert state["ended"]["ok"] is False and state["hint"]["text"].startswith("STOPPED: the capture stopped")


def _ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as probe:
            probe.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.skipif(not _ipv6_loopback(), reason="this machine has no IPv6 loopback")
def test_the_live_view_listens_on_an_ipv6_host(tmp_path, capsys):
    hub = ViewHub(default_config().as_mock(), nominal_xb3_model()).start()
    server = ViewServer(hub, "::1").start()
    try:
        assert server.url.startswith("http://[::1]:")
        assert b"EventSource" in urllib.request.urlopen(server.url, timeout=5).read()
    finally:
        hub.close()
        server.close(linger_s=0.0)
    assert main(["capture", "--mock", "--session", str(tmp_path / "p"), "--plan-only", "--view", "--view-host", "::1"]) == 0
    out = capsys.readouterr().out
    assert "MOCK live view: http://[::1]:" in out
