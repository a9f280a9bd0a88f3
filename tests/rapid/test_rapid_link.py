"""The generated RAPID's link recovery (idle timeout, takeover) and write key (HeKey.sys)."""

from __future__ import annotations

import re
import stat

import pytest

from handeye.drivers.controller import protocol as P
from handeye.rapid.checks import check_program, for_rapidchecker
from handeye.rapid.errors import RapidError, StationConfigError
from handeye.base.write_key import write_key_code
from handeye.rapid.generate import render_key, render_link, render_program, write_modules
from handeye.rapid.station import default_station, load_station
from handeye.station.cli import main

KEY = "Cell7-key_2024"


def keyed(**changes):
    return default_station().with_(write_key=KEY, **changes)


def test_hekey_is_a_system_module_holding_the_key_and_its_code():
    module = render_key(keyed())
    assert module.filename == "HeKey.sys"
    assert module.text.startswith("MODULE HeKey(SYSMODULE, NOVIEW)\n") and module.text.endswith("ENDMODULE\n")
    assert f'LOCAL CONST string HE_WRITE_KEY := "{KEY}";' in module.text
    assert f"LOCAL CONST dnum HE_WRITE_CODE := {write_key_code(KEY)};" in module.text
    assert "FUNC bool HeKeyMatches(string key)" in module.text and "FUNC bool HeCodeMatches(dnum code)" in module.text
    with pytest.raises(RapidError, match="controller.write_key"):
        render_key(default_station())


@pytest.mark.parametrize("protocol", ["socket", "serial", "modbus"])
def test_the_program_never_holds_the_key(protocol):
    modules = render_program(keyed(), protocol=protocol)
    assert [m.name for m in modules] == ["HeMain", {"socket": "HeSocket", "serial": "HeSerial", "modbus": "HeIo"}[protocol],
                                         "HeTool"]
    for m in modules:
        assert KEY not in m.text and str(write_key_code(KEY)) not in m.text
    link = modules[1].text
    assert ("HeCodeMatches(GInputDnum(giHeToolKey))" if protocol == "modbus" else "HeKeyMatches(key)") in link
    plain = render_link(default_station(), protocol).text  # no key configured: no call into HeKey, writes refused
    assert "HeKeyMatches" not in plain and "HeCodeMatches" not in plain
    assert ("SetGO goHeToolErr, 9;" if protocol == "modbus" else '" ERR 9 no write key: set controller.write_key"') in plain


def test_repr_of_a_station_hides_the_key():
    assert KEY not in repr(keyed()) and KEY not in str(keyed())


def test_socket_module_times_out_idle_clients_and_lets_the_pc_take_over():
    text = render_link(keyed(idle_timeout_s=2.5), "socket").text
    assert "LOCAL CONST num HE_IDLE_TIMEOUT := 2.5;" in text
    assert "LOCAL CONST num HE_SLICE := 0.5;" in text and "LOCAL CONST num HE_ACCEPT_POLL := 0.05;" in text
    assert "IF ClkRead(heIdleClock) >= HE_IDLE_TIMEOUT THEN" in text
    assert "SocketReceive heSockA \\Str:=chunk \\Time:=slice;" in text
    assert "SocketAccept heListener, heSockB \\ClientAddress:=clientAddress \\Time:=HE_ACCEPT_POLL;" in text
    assert "heOnB := NOT heOnB;" in text  # the spare socketdev becomes the current one
    assert "IF heBye OR (heKeyFails >= HE_KEY_TRIES) THEN" in text
    # the slice is at most half the idle timeout, so an idle PC is noticed in time
    assert "HE_SLICE := 0.15;" in render_link(keyed(idle_timeout_s=0.3), "socket").text
    # the time of a move never counts as idleness
    for proc in ("HeLinkWaitRequest", "HeLinkAtPosture"):
        body = text.split(f"PROC {proc}()", 1)[1].split("ENDPROC", 1)[0]
        assert "HeIdleRestart;" in body


def test_serial_module_forgets_the_session_and_the_unfinished_line_after_silence():
    text = render_link(keyed(idle_timeout_s=4), "serial").text
    assert "LOCAL CONST num HE_IDLE_TIMEOUT := 4;" in text
    serve = text.split("PROC HeServeOne(num waitTime)", 1)[1].split("ENDPROC", 1)[0]
    idle = serve.split("IF slice <= 0 THEN", 1)[1].split("    ENDIF\n    IF waitTime", 1)[0]
    assert "HeNewSession;" in idle and "ClearIOBuff heChannel;" in idle
    assert "heLine := ReadStr(heChannel \\Time:=slice);" in serve
    assert "IF heBye THEN\n      HeNewSession;" in serve  # BYE ends the session on a line too
    new_session = text.split("PROC HeNewSession()", 1)[1].split("ENDPROC", 1)[0]
    assert "heAuthorised := FALSE;" in new_session and "heKeyFails := 0;" in new_session


def test_io_module_locks_tool_writes_after_wrong_key_codes():
    text = render_link(keyed(), "modbus").text
    assert f"LOCAL CONST num HE_KEY_TRIES := {P.KEY_TRIES};" in text
    gate = text.split("PROC HeApplyTool()", 1)[1].split("ENDPROC", 1)[0]
    assert "IF heKeyFails >= HE_KEY_TRIES THEN\n      SetGO goHeToolErr, 9;" in gate
    assert "heKeyFails := heKeyFails + 1;" in gate and "HeStoreTool;" in gate
    assert "heKeyFails := 0;" in text.split("PROC HeLinkOpen()", 1)[1].split("ENDPROC", 1)[0]  # only a restart unlocks


def test_checks_know_module_attributes():
    text = render_key(keyed()).text
    assert check_program([("HeKey", text)]) == []
    bad = text.replace("(SYSMODULE, NOVIEW)", "(SYSMODULE, SECRET)")
    assert any("unknown module attribute 'SECRET'" in str(f) for f in check_program([("HeKey", bad)]))
    assert for_rapidchecker(text).startswith("MODULE HeKey(SYSMODULE)\n")
    assert for_rapidchecker(text).split("\n", 1)[1] == text.split("\n", 1)[1]  # nothing else touched


@pytest.mark.parametrize("value, message", [
    ("short", "8 to 32"),
    ("x" * 33, "8 to 32"),
    ("has space here", "8 to 32"),
    (12345678, "quote it in YAML"),
])
def test_bad_write_keys_are_refused_without_echo(tmp_path, value, message):
    path = tmp_path / "station.yaml"
    import yaml

    path.write_text(yaml.safe_dump({"controller": {"write_key": value}}))
    with pytest.raises(StationConfigError, match=message) as info:
        load_station(path)
    assert str(value) not in str(info.value)


@pytest.mark.parametrize("idle", [0.05, 0, 10.5, "soon"])
def test_idle_timeout_outside_its_range_is_refused(tmp_path, idle):
    path = tmp_path / "station.yaml"
    path.write_text(f"controller: {{idle_timeout_s: {idle}}}\n")
    with pytest.raises(StationConfigError, match="idle_timeout_s"):
        load_station(path)


def test_rapid_generate_writes_hekey_only_with_a_key(tmp_path, capsys):
    config = tmp_path / "station.yaml"
    config.write_text(f"controller: {{protocol: socket, write_key: {KEY}, idle_timeout_s: 3}}\ncamera: {{backend: xb3}}\n")
    assert main(["rapid", "generate", "--config", str(config), "-o", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["HeKey.sys", "HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    assert "HeKey.sys holds the station's write key" in out and "never copy it into sessions" in out
    assert KEY not in out
    key_file = tmp_path / "out" / "HeKey.sys"
    assert KEY in key_file.read_text() and stat.S_IMODE(key_file.stat().st_mode) == 0o600
    assert "HE_IDLE_TIMEOUT := 3;" in (tmp_path / "out" / "HeSocket.mod").read_text()
    assert all(KEY not in p.read_text() for p in (tmp_path / "out").glob("*.mod"))
    assert main(["rapid", "generate", "-o", str(tmp_path / "plain")]) == 0  # no key: no HeKey.sys
    assert "refuse every tool write" in capsys.readouterr().out
    assert not (tmp_path / "plain" / "HeKey.sys").exists()


def test_write_modules_of_a_program_never_writes_hekey(tmp_path):
    paths = write_modules(render_program(keyed()), tmp_path)
    assert [p.name for p in paths] == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    assert not re.search(re.escape(KEY), "".join(p.read_text() for p in paths))
