"""Robot Web Services: what only RWS has (users, mastership, manual mode, 503, generations, TLS
pinning, the program loaded through the file service), against the mock RWS server of both
generations. The contract and fault tests of every back end run on rws too (rws1, rws2)."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.drivers.controller import ControllerConnectionError, ControllerRefused, ControllerTimeout, ProtocolError, ToolData, open_controller
from handeye.drivers.controller.rws_codec import parse_rapid_value, rapid_literal
from handeye.drivers.controller.types import AT, READY
from handeye.mocks.controller import start_mock_controller
from handeye.rapid.generate import render_program
from handeye.rapid.station import default_station

TOOL = ToolData((12.5, -3.25, 88.0), (0.5, 0.5, -0.5, 0.5), 1.4, (0.0, 10.0, 70.0))


@pytest.fixture(params=[1, 2], ids=["rws1", "rws2"])
def rws(request):
    with start_mock_controller("rws", generation=request.param, time_scale=0.002, ack_timeout_s=None) as srv:
        yield srv


#: The per-call timeout of the tests that load modules: the mock parses and links them in the request.
LOAD_TIMEOUT = 5.0


def _open(server, **changes):
    options = {**server.client_options(), "timeout": 1.0, "motion_timeout": 10.0, "backoff_s": 0.02, **changes}
    return open_controller("rws", **options)


def test_generation_is_detected_from_the_controller(rws):
    with _open(rws) as c:
        assert c.generation == rws.generation
        assert c.robotware == rws.robotware
        assert c.info().program == f"RAPID_RWS{rws.generation}"
        assert c.controller_state() == {"ctrlstate": "motoron", "opmode": "AUTO", "execution": "running",
                                        "robotware": rws.robotware}


def test_a_generation_asked_for_that_the_controller_does_not_speak_is_refused(rws):
    other = 2 if rws.generation == 1 else 1
    with pytest.raises(ProtocolError, match=f"speaks RWS {rws.generation}.0, not the RWS {other}.0"):
        _open(rws, generation=other)


def test_wrong_password_names_the_cause_and_writes_nothing(rws):
    before = rws.robot.tool
    with pytest.raises(ControllerRefused, match="wrong user or password") as info:
        with _open(rws, password="not-robotics") as c:
            c.set_tool(TOOL)
    assert info.value.code == 401
    assert rws.writes == 0 and rws.robot.tool == before


def test_writes_are_done_under_mastership_and_release_it(rws):
    with _open(rws) as c:
        back = c.set_tool(TOOL)
        assert back.close_to(TOOL) and rws.robot.tool.close_to(TOOL)
        assert rws.master is None  # released after the write


def test_mastership_held_elsewhere_is_refused_naming_it_and_nothing_is_written(rws):
    before = rws.robot.tool
    with _open(rws) as c:
        rws.faults.mastership_held = True
        with pytest.raises(ControllerRefused, match="mastership") as info:
            c.set_tool(TOOL)
        assert info.value.code == 403
        with pytest.raises(ControllerRefused, match="mastership"):
            c.goto_posture(3)
        assert rws.robot.tool == before and rws.robot.moves == 0
        rws.faults.mastership_held = False
        assert c.set_tool(TOOL).close_to(TOOL)


@pytest.mark.filterwarnings("ignore::urllib3.exceptions.InsecureRequestWarning")  # verify=False: a bare client
def test_rws2_refuses_a_write_without_mastership_rws1_takes_it_implicitly(rws):
    import requests

    auth = (requests.auth.HTTPBasicAuth if rws.generation == 2 else requests.auth.HTTPDigestAuth)("Default User", "robotics")
    base = f"{'https' if rws.generation == 2 else 'http'}://127.0.0.1:{rws.port}"
    with requests.Session() as http:
        if rws.generation == 1:
            r = http.post(f"{base}/rw/rapid/symbol/data/RAPID/T_ROB1/HeTool/tHeCamera?action=set&json=1",
                          data={"value": rapid_literal([True, [[1, 2, 3], [1, 0, 0, 0]], [1, [0, 0, 1], [1, 0, 0, 0], 0, 0, 0]])},
                          auth=auth)
            assert r.status_code == 204
            assert rws.robot.tool.position_mm == (1.0, 2.0, 3.0)
        else:
            r = http.post(f"{base}/rw/rapid/symbol/RAPID/T_ROB1/HeTool/tHeCamera/data", auth=auth, verify=False,
                          data={"value": "[TRUE,[[1,2,3],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]]"},
                          headers={"Accept": "application/hal+json;v=2.0"})
            assert r.status_code == 403
            assert r.json()["status"]["code"] == -1073445862
            assert rws.robot.tool.position_mm != (1.0, 2.0, 3.0)


def test_busy_controller_is_retried_within_the_budget(rws):
    with _open(rws) as c:
        rws.faults.busy_next = 3
        assert np.allclose(c.read_joints(), rws.robot.current_joints, atol=1e-4)
        assert c.busy_answers == 3 and rws.faults.fired["busy"] == 3


def test_controller_busy_for_the_whole_budget_is_a_timeout_naming_503(rws):
    before = rws.robot.tool
    with _open(rws, timeout=0.3) as c:
        rws.faults.busy = True
        with pytest.raises(ControllerTimeout, match="busy \\(HTTP 503"):
            c.read_joints()
        with pytest.raises(ControllerTimeout, match="503"):
            c.set_tool(TOOL)
        rws.faults.busy = False
    assert rws.robot.tool == before


def test_manual_mode_asks_for_rmmp_and_the_pendant_allows(rws):
    rws.opmode = "MANR"
    with _open(rws) as c:
        assert c.set_tool(TOOL).close_to(TOOL)
        assert [s["rmmp"] for s in rws.sessions.values()] == ["modify"]


@pytest.mark.parametrize("policy, error, words", [("deny", ControllerRefused, "denied"),
                                                  ("ignore", ControllerTimeout, "press Allow on the FlexPendant")])
def test_manual_mode_without_the_pendants_allow_writes_nothing(rws, policy, error, words):
    rws.opmode, rws.rmmp_policy = "MANR", policy
    before = rws.robot.tool
    with _open(rws, rmmp_timeout=0.2, poll_s=0.02) as c:
        with pytest.raises(error, match=words):
            c.set_tool(TOOL)
    assert rws.writes == 0 and rws.robot.tool == before


def test_motors_off_refuses_a_move_naming_it(rws):
    with _open(rws) as c:
        rws.set_motors(False)
        with pytest.raises(ControllerRefused, match="motors .* are off"):
            c.goto_posture(4)
        assert rws.robot.moves == 0


def test_a_certificate_that_is_not_the_pinned_one_is_refused():
    with start_mock_controller("rws", generation=2, time_scale=0.002) as server:
        with pytest.raises(ControllerConnectionError, match="does not match controller.tls_fingerprint"):
            _open(server, tls_fingerprint="ab" * 32, retries=0)
        with pytest.raises(ControllerConnectionError, match="RobotWare 7 controller answers HTTPS only"):  # plain HTTP
            open_controller("rws", host="127.0.0.1", port=server.port, timeout=1.0, retries=0)


def test_the_program_is_uploaded_loaded_and_started_and_pers_survive_a_restart(rws):
    station = default_station().with_(protocol="rws", postures=tuple(tuple(row) for row in rws.robot.postures[:5]),
                                      controller_address="auto")
    modules = [(m.filename, m.text) for m in render_program(station, protocol="rws")]
    with _open(rws, timeout=LOAD_TIMEOUT) as c:
        c.set_tool(TOOL)
        c.load_program([m for m in modules if not m[0].startswith("HeTool")])  # HeTool stays: its PERS value too
        assert "$HOME/handeye/HeMain.mod" in rws.files
        assert c.info().postures == 5 and c.status().state == READY
        assert c.read_tool().close_to(TOOL)
        assert c.goto_posture(5).state == AT
        c.acknowledge(5)
        rws.restart()  # a warm start: PERS values kept
        assert c.read_tool().close_to(TOOL)
        c.stop_program()
        assert not rws.running
        with pytest.raises(ControllerRefused, match="program .* is stopped"):
            c.goto_posture(1)


@pytest.mark.filterwarnings("ignore::urllib3.exceptions.InsecureRequestWarning")
def test_xhtml_answers_without_json(rws):
    import requests

    if rws.generation == 2:
        auth, kw = requests.auth.HTTPBasicAuth("Default User", "robotics"), {"verify": False}
    else:
        auth, kw = requests.auth.HTTPDigestAuth("Default User", "robotics"), {}
    scheme = "https" if rws.generation == 2 else "http"
    r = requests.get(f"{scheme}://127.0.0.1:{rws.port}/rw/motionsystem/mechunits/ROB_1/jointtarget", auth=auth, **kw)
    assert r.status_code == 200 and r.headers["Content-Type"].startswith("application/xhtml+xml")
    assert '<li class="ms-jointtarget" title="ROB_1"><span class="rax_1">' in r.text
    r.close()


def test_rapid_values_round_trip():
    value = [True, [[1.5, -2, 3e-7], [1, 0, 0, 0]], [0.9, [0, 0, 30], [1, 0, 0, 0], 0, 0, 0]]
    assert parse_rapid_value(rapid_literal(value)) == value
    assert parse_rapid_value('[9E+09,"a ""b""",FALSE]') == [9e9, 'a "b"', False]
    for bad in ("[1,2", "1,2]", "[x]", ""):
        with pytest.raises(ValueError):
            parse_rapid_value(bad)


def test_an_empty_task_is_reported_and_the_station_installs_the_program_over_rws(tmp_path):
    from handeye.rapid.generate import write_modules
    from handeye.station.runtime import _program_loader

    idle = tmp_path / "idle"
    idle.mkdir()
    (idle / "HeMain.mod").write_text("MODULE HeMain\n  PROC main()\n    WHILE TRUE DO\n      WaitTime 0.05;\n"
                                   "    ENDWHILE\n  ENDPROC\nENDMODULE\n")
    with start_mock_controller("rws", generation=2, time_scale=0.002, program=idle) as server:
        with _open(server, timeout=LOAD_TIMEOUT) as c:
            assert c.info().postures == 0
            assert np.allclose(c.read_joints(), 0.0)  # reading needs no program
            with pytest.raises(ControllerRefused, match="no handeye program runs in T_ROB1"):
                c.goto_posture(1)
            postures = server.robot.postures[:4] if len(server.robot.postures) else default_station().postures[:4]
            station = default_station().with_(protocol="rws", postures=tuple(tuple(r) for r in postures))
            rapid_dir = tmp_path / "rapid"
            write_modules(render_program(station, protocol="rws"), rapid_dir)
            _program_loader(c)(postures, rapid_dir)
            assert c.info().postures == 4
            assert c.goto_posture(4).state == AT
            assert np.allclose(server.robot.current_joints, postures[3])
            c.acknowledge(4)
            c.set_tool(TOOL)
            _program_loader(c)(postures, rapid_dir)  # a resumed capture: HeTool is not loaded again
            assert c.read_tool().close_to(TOOL)


def test_a_program_that_cannot_start_is_reported_and_nothing_moves(rws):
    station = default_station().with_(protocol="rws")
    modules = [(m.filename, m.text) for m in render_program(station, protocol="rws") if m.name != "HeTool"]
    with _open(rws, timeout=LOAD_TIMEOUT) as c:
        rws.set_motors(False)
        with pytest.raises(ControllerRefused, match="motors are off"):
            c.load_program(modules)
        c.close()
        c.connect()
        assert c.info().postures == 0 and "not started" in c.info().program
        assert np.allclose(c.read_joints(), rws.robot.current_joints, atol=1e-4)
        with pytest.raises(ControllerRefused, match="no handeye program runs"):
            c.goto_posture(1)
        rws.set_motors(True)
        c.load_program(modules)
        assert c.info().postures == 12 and c.goto_posture(2).at_posture(2)
    assert rws.robot.moves == 1


def test_the_rate_limiter_keeps_the_average_below_the_ceiling(monkeypatch):
    from handeye.drivers.controller import rws_transport

    clock = {"now": 100.0, "slept": 0.0}

    def sleep(seconds):
        clock["now"] += seconds
        clock["slept"] += seconds

    monkeypatch.setattr(rws_transport.time, "monotonic", lambda: clock["now"])
    monkeypatch.setattr(rws_transport.time, "sleep", sleep)
    limiter = rws_transport.RateLimiter(20.0, burst=10)
    for _ in range(10):
        limiter.wait()
    assert clock["slept"] == 0.0  # a burst passes at once
    for _ in range(40):
        limiter.wait()
    assert clock["slept"] == pytest.approx(40 / 20.0)  # then 20 per second
    clock["now"] += 10.0  # a quiet spell refills the burst, no more
    for _ in range(10):
        limiter.wait()
    assert clock["slept"] == pytest.approx(2.0)


def test_the_guided_program_is_refused_in_one_line_over_rws():
    # Robot Web Services has no guided program: the refusal names the link (it raised AttributeError on
    # Controller.name, which no back end has, until pyright found it). Nothing is sent: no server needed.
    robot = open_controller("rws", connect=False)
    with pytest.raises(ControllerRefused, match="the rws link has no guided program: capture --guided"):
        robot.guide(1, 0)
    with pytest.raises(ControllerRefused, match="the rws link has no guided program"):
        robot.wait_operator(0.1)
