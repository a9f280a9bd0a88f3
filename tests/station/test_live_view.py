"""The live view without a browser (issue 22): the token, the capture's events, the page's state against
the session on disk, the running calibration's predicted corners, and what the capture thread pays."""

from __future__ import annotations

import threading
import time
import urllib.error
import urllib.request
from dataclasses import replace

import numpy as np
import pytest

from handeye.calibration.session import read_session
from handeye.drivers.camera.stereo import nominal_xb3_model
from handeye.station.capture.loop import capture
from handeye.station.capture.events import CAPTURED, CaptureStarted, Measured, Prompt, Verdict
from handeye.station.cli import main
from handeye.station.config.station import default_config
from handeye.station.guided.capture import guided_capture
from handeye.station.guided.operator import mock_operator
from handeye.station.runtime import open_station
from handeye.station.view import live_view, loopback
from handeye.station.view.hub import ViewHub
from handeye.station.view.server import ViewServer
from handeye.station.view.state import Predictor

POSTURES = 5


def _config(postures=POSTURES):
    config = default_config().as_mock()
    return replace(config, plan=replace(config.plan, postures=postures),
                   guided=replace(config.guided, still_s=0.3, poll_s=0.03))


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """A planned mock capture with the live view open and an event-stream client reading it."""
    config, session = _config(), tmp_path_factory.mktemp("view") / "planned"
    events, states = [], []
    with open_station(config, session_dir=session) as link, live_view(config, link, session) as view:
        def observer(event):
            events.append(event)
            view.observer(event)

        reader = threading.Thread(target=_read_stream, args=(view.url, states), daemon=True)
        reader.start()
        time.sleep(0.2)
        capture(config, session, link, observer=observer)
        time.sleep(0.3)
        state = view.hub.state.to_json()
    return {"events": events, "state": state, "session": session, "url": view.url, "config": config,
            "model": link.stereo_model}


def _read_stream(url: str, states: list) -> None:
    try:
        with urllib.request.urlopen(url.replace("/?token", "/events?token"), timeout=30) as stream:
            for line in stream:
                states.append(line)
    except OSError:
        pass


def test_the_capture_tells_the_observer_each_step(planned):
    events = planned["events"]
    assert isinstance(events[0], CaptureStarted) and events[0].mode == "planned" and len(events[0].plan_joints) == POSTURES
    kinds = [type(e).__name__ for e in events[1:]]
    assert kinds == ["Prompt", "Measured", "Verdict"] * POSTURES
    verdicts = [e for e in events if isinstance(e, Verdict)]
    assert [v.posture for v in verdicts] == list(range(POSTURES)) and {v.word for v in verdicts} == {CAPTURED}
    measured = [e for e in events if isinstance(e, Measured)]
    assert all(m.result is not None and m.frame.left.shape[:2] == (960, 1280) for m in measured)


def test_the_page_state_is_the_session_on_disk(planned):
    state, session = planned["state"], read_session(planned["session"])
    assert state["progress"]["count"] == len(session.postures) == POSTURES
    assert [row["index"] for row in state["postures"]] == [p.index for p in session.postures]
    for row, posture in zip(state["postures"], session.postures):
        assert row["quality"]["corners"] == posture.extra["quality"]["corners"]
        assert row["quality"]["distance_mm"] == pytest.approx(posture.extra["quality"]["distance_mm"], abs=0.01)
    assert state["plan"]["total"] == POSTURES and state["plan"]["current"] == POSTURES - 1
    assert len(state["plan"]["flange_mm"]) == POSTURES and state["plan"]["done"] == list(range(POSTURES))
    assert state["progress"]["time_left_s"] == 0.0
    assert state["calibration"]["ok"] and state["calibration"]["d_org_mm"] < 1.0
    assert state["missing"] and not state["good_enough"]  # 6 postures are not enough for the verdict
    assert state["coverage"]["cells_seen"] == sum(map(sum, state["coverage"]["cells"]))


def test_the_running_calibration_predicts_the_next_postures_corners(planned):
    """From the postures before it, the corners of the last posture land within a pixel or two of where
    its measured points project (the mock's arm and camera have errors of their own)."""
    import cv2

    session, model = read_session(planned["session"]), planned["model"]
    predictor = Predictor(session, model)
    predictor.update(session.postures[:-1])
    last = session.postures[-1]
    left, right = predictor.predict_px(last.tool0_in_base)
    seen, _ = cv2.projectPoints(np.asarray(last.points_mm), np.zeros(3), np.zeros(3), model.K1, model.D1)
    assert np.median(np.linalg.norm(left - seen.reshape(-1, 2), axis=1)) < 2.0
    assert right.shape == left.shape
    predictor.update(session.postures[:2])
    assert predictor.predict_px(last.tool0_in_base) is None and "3 postures" in predictor.reason


def test_the_page_needs_the_token(planned, tmp_path):
    hub = ViewHub(planned["config"], nominal_xb3_model()).start()
    server = ViewServer(hub).start()
    try:
        base = server.url.split("?")[0]
        for url in (base, base + "?token=wrong", base + "events", base + "preview.png?token=" + server.token[:-1]):
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(url, timeout=5)
            assert refused.value.code == 403
        page = urllib.request.urlopen(server.url, timeout=5).read().decode()
        assert "EventSource" in page and "http" not in page.replace("http://www.w3.org/2000/svg", "")  # nothing from elsewhere
        with urllib.request.urlopen(server.url.replace("/?token", "/events?token"), timeout=5) as stream:
            assert stream.readline() == b"event: state\n"
    finally:
        hub.close()
        server.close(linger_s=0.0)
    assert server.url.startswith("http://127.0.0.1:") and len(server.token) >= 20


def test_the_capture_thread_only_hands_over_the_latest_frame(planned):
    """A burst of grabs costs the capture thread microseconds each; the view encodes a few, not all."""
    hub = ViewHub(planned["config"], nominal_xb3_model(), frame_interval_s=0.2).start()
    frame = planned["events"][2].frame
    try:
        started = time.perf_counter()
        for k in range(200):
            hub.observe(Measured(k, frame))
        spent = time.perf_counter() - started
        time.sleep(0.5)
    finally:
        hub.close()
    assert spent / 200 < 1e-3
    assert 1 <= hub.encoded <= 4


def test_the_guided_capture_tells_the_observer_too(tmp_path):
    config, session, events = _config(3), tmp_path / "guided", []
    stop = threading.Event()
    with open_station(config, session_dir=session) as link, mock_operator(config, link, stop) as operator:
        def on_posture(report):
            operator.captured(report)

        guided_capture(config, session, link, on_posture=on_posture, stop=stop, observer=events.append)
    assert isinstance(events[0], CaptureStarted) and events[0].mode == "guided" and events[0].plan_joints is None
    assert isinstance(events[1], Prompt) and events[1].kind == "jog"
    captured = [e for e in events if isinstance(e, Verdict) and e.word == CAPTURED]
    assert [v.posture for v in captured] == [p.index for p in read_session(session).postures]
    assert all(e.tool02base is not None for e in events if isinstance(e, Measured))


def test_view_host_needs_view_and_a_foreign_address_is_named(tmp_path, capsys):
    assert main(["capture", "--mock", "--session", str(tmp_path / "s"), "--view-host", "0.0.0.0"]) != 0
    assert "--view-host needs --view" in capsys.readouterr().err
    assert loopback("127.0.0.1") and loopback("::1") and loopback("localhost")
    assert not loopback("0.0.0.0") and not loopback("192.168.1.10")


def _published(hub, before: int) -> dict:
    """The next frame the hub publishes after version ``before``."""
    import json

    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        _, _, _, version, text = hub.wait(hub.state_version, before, 0.2)
        if version != before:
            return json.loads(text)
    raise AssertionError("the hub published no frame")


def _scaled(points_px, side: dict, full_width: int) -> np.ndarray:
    scale = side["size"][0] / full_width
    return (np.asarray(points_px, float) + 0.5) * scale - 0.5


def test_the_board_state_and_corners_shown_are_the_captures_own_detection(planned):
    """Issue 40.2: for the same frame, the page's "board found" and its corners are what the capture finds:
    a live frame through the capture's detector (not a quick search on the small copy, which said "no board"
    while both images showed it), a measured one with the capture's own corners, a grab being measured as
    "measuring", a frame without the board as "no board" where the capture finds none either."""
    from dataclasses import replace as copy

    from handeye.drivers.camera.errors import NoBoardInView
    from handeye.drivers.camera.triangulate import triangulate_images

    config = planned["config"]
    measured = [e for e in planned["events"] if isinstance(e, Measured) and e.result is not None][:2]
    hub = ViewHub(config, planned["model"]).start()
    try:
        for event in measured:
            width = event.frame.left.shape[1]
            before = hub.frame_version
            hub.offer_live(event.frame)
            live = _published(hub, before)
            assert live["kind"] == "live" and live["found"] == [True, True]
            for side, corners in zip(live["sides"], (event.result.left_px, event.result.right_px)):
                assert np.max(np.abs(np.asarray(side["corners"]) - _scaled(corners, side, width))) < 0.05
            before = hub.frame_version
            hub.observe(event)
            shown = _published(hub, before)
            assert shown["kind"] == "measured" and shown["found"] == [True, True]
            assert np.allclose(shown["sides"][0]["corners"], _scaled(event.result.left_px, shown["sides"][0], width),
                               atol=0.01)
            before = hub.frame_version
            hub.capture_frame(event.frame)
            grab = _published(hub, before)
            assert grab["kind"] == "grab" and grab["found"] == [None, None] and grab["sides"][0]["corners"] is None
        blank = copy(measured[0].frame, left=np.full_like(measured[0].frame.left, 90),
                     right=np.full_like(measured[0].frame.right, 90))
        with pytest.raises(NoBoardInView):
            triangulate_images(blank.left, blank.right, board=f"{config.target.corners[0]}x{config.target.corners[1]}",
                               square_mm=config.target.square_mm, model=planned["model"])
        before = hub.frame_version
        hub.offer_live(blank)
        empty = _published(hub, before)
        assert empty["found"] == [False, False] and empty["sides"][0]["corners"] is None
    finally:
        hub.close()
