"""Generated RAPID: rapidchecker's grammar and format checks, our own checks, parity with the codec."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from handeye.drivers.controller import protocol as P
from handeye.drivers.controller.modbus_map import load_register_map
from handeye.rapid.checks import check_program, for_rapidchecker, string_length
from handeye.rapid.errors import RapidError, StationConfigError
from handeye.rapid.generate import (
    IO_SIGNALS,
    KEY_TRIES,
    RAPID_PROTOCOL_VERSION,
    render_key,
    render_link,
    render_program,
    render_tool,
    write_modules,
)
from handeye.rapid.station import default_station, load_station
from handeye.rapid.links import LINK_MODULES

PROTOCOLS = tuple(LINK_MODULES)


KEY = "Cell7-key_2024"


@pytest.fixture(scope="module")
def programs():
    station = default_station()
    return {p: render_program(station, protocol=p) for p in PROTOCOLS}


@pytest.fixture(scope="module")
def keyed_programs():
    """The programs of a station with a write key (their link modules call HeKey's routines)."""
    station = default_station().with_(write_key=KEY)
    return {p: render_program(station, protocol=p) for p in PROTOCOLS}


def test_every_module_passes_rapidchecker(programs, keyed_programs, tmp_path):
    modules = [(protocol, m) for protocol, program in programs.items() for m in program]
    modules += [(f"keyed_{protocol}", program[1]) for protocol, program in keyed_programs.items()]
    auto = default_station().with_(controller_address="auto", pc_address="192.168.125.10", source="auto test")
    modules.append(("auto", render_link(auto, "socket")))
    distinct = {}  # HeMain and HeTool are the same text for every link: rapidchecker reads each text once
    for folder, module in modules:
        distinct.setdefault(module.text, (folder, module))
    files = []
    for folder, module in distinct.values():
        files += write_modules([module], tmp_path / folder)
    # HeKey.sys as rapidchecker 0.1.x can parse it (its grammar lacks NOVIEW; our checks cover that word)
    key = render_key(default_station().with_(write_key=KEY))
    (tmp_path / "key").mkdir()
    files.append(tmp_path / "key" / "HeKey.sys")
    files[-1].write_text(for_rapidchecker(key.text))
    result = subprocess.run([sys.executable, "-m", "rapidchecker", *map(str, files)], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert len(modules) == 3 * len(programs) + len(keyed_programs) + 1  # 4 links: 17 modules and HeKey
    assert len(files) == len(distinct) + 1  # 11 files (the rws link module is the same with a key)


def test_rapidchecker_is_not_vacuous(programs, tmp_path):
    main = programs["socket"][0]
    broken = main.text.replace("    HeLinkOpen;\n", "    HeLinkOpen\n")  # missing ';'
    path = tmp_path / "Broken.mod"
    path.write_text(broken)
    # the name as given (relative) and a wide console: rapidchecker wraps its report at the terminal
    # width, and a long temporary folder (a pytest-xdist worker's) would split an absolute path
    result = subprocess.run([sys.executable, "-m", "rapidchecker", path.name], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120, env={**os.environ, "COLUMNS": "1000"})
    assert result.returncode == 1 and "Broken.mod" in result.stdout


@pytest.mark.parametrize("protocol", PROTOCOLS)
def test_own_checks_pass(programs, keyed_programs, protocol):
    modules = [(m.name, m.text) for m in programs[protocol]]
    assert check_program(modules, approved=default_station().postures_array, external=IO_SIGNALS) == []
    # with a key: the program and HeKey.sys loaded together into one task
    key = render_key(default_station().with_(write_key=KEY))
    keyed = [(m.name, m.text) for m in keyed_programs[protocol]] + [(key.name, key.text)]
    assert check_program(keyed, approved=default_station().postures_array, external=IO_SIGNALS) == []
    if protocol == "rws":  # RWS writes the tool by symbol, authorised by the controller's users: no key routine
        assert "HeKey" not in keyed[1][1]
        return
    # without HeKey the keyed link module does not resolve: HeKey.sys must be loaded
    findings = check_program(keyed[:3], approved=default_station().postures_array, external=IO_SIGNALS)
    assert findings and all("HeKeyMatches" in str(f) or "HeCodeMatches" in str(f) for f in findings)


def test_module_files_and_names(programs):
    assert [m.filename for m in programs["socket"]] == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    assert [m.name for m in programs["serial"]][1] == "HeSerial"
    assert [m.name for m in programs["modbus"]][1] == "HeIo"
    for modules in programs.values():
        for m in modules:
            assert m.text.startswith(f"MODULE {m.name}\n") and m.text.endswith("ENDMODULE\n")
            assert m.text.isascii()


def test_main_embeds_exactly_the_approved_postures(programs):
    main = programs["socket"][0].text
    station = default_station()
    found = re.findall(r"CONST jointtarget (jtHePost\d+) := \[\[([^\]]*)\],\[9E9,9E9,9E9,9E9,9E9,9E9\]\];", main)
    assert len(found) == len(station.postures)
    values = np.array([[float(v) for v in body.split(",")] for _, body in found])
    assert np.allclose(values, station.postures_array, atol=5e-5)
    moves = re.findall(r"MoveAbsJ (\w+), vHeMove, fine, tool0;", main)
    assert sorted(moves) == sorted(name for name, _ in found)
    assert "CONST speeddata vHeMove := [200,100,5000,1000];" in main


def test_socket_module_accepts_only_the_pc(programs):
    station = default_station().with_(pc_address="192.168.125.10", controller_address="auto", port=2001)
    text = render_link(station, "socket").text
    assert 'HE_PC_ADDRESS := "192.168.125.10"' in text and "HE_PORT := 2001" in text
    assert "SocketBind heListener, GetSysInfo(\\LanIp), HE_PORT;" in text
    assert "IF clientAddress <> HE_PC_ADDRESS THEN" in text


def test_rendering_refuses_postures_outside_the_limits():
    station = default_station()
    bad = [list(p) for p in station.postures]
    bad[2][4] = 120.0  # axis 5 limit is 115
    with pytest.raises(StationConfigError, match="posture 3: axis 5"):
        render_program(station, postures=bad)
    with pytest.raises(StationConfigError, match="NaN|nan"):
        render_program(station, postures=[[0, 0, float("nan"), 0, 0, 0]])


def test_tool_module_holds_the_calibrated_frame():
    from handeye.geometry.transforms import transform_from_pose

    frame = transform_from_pose([12.5, -3.25, 88.0], [0.5, 0.5, -0.5, 0.5])
    text = render_tool(default_station(), frame, comments=["method mcb"]).text
    assert "PERS tooldata tHeCamera := [TRUE,[[12.5,-3.25,88],[0.5,0.5,-0.5,0.5]],[1,[0,0,60],[1,0,0,0],0,0,0]];" in text
    with pytest.raises(RapidError, match="over 1 m"):
        render_tool(default_station(), transform_from_pose([2000, 0, 0], [1, 0, 0, 0]))


# --- parity between the RAPID dispatcher and the codec in drivers/controller/protocol.py

def _dispatcher_cases(text):
    cases = {}
    for block in re.split(r'\n    CASE "', text)[1:]:
        name = block.split('"', 1)[0]
        body = block.split("\n    CASE", 1)[0].split("\n    DEFAULT", 1)[0]
        m = re.search(r"HeArgs\((\d)\)", body)
        words = re.search(r"IF heWordCount = (\d) THEN", body)  # word arguments (KEY)
        cases[name] = int(m.group(1)) if m else (int(words.group(1)) - 2 if words else None)
    return cases


@pytest.mark.parametrize("keyed", [False, True], ids=["no-key", "key"])
@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_dispatcher_handles_every_protocol_command_with_its_arguments(programs, keyed_programs, protocol, keyed):
    text = (keyed_programs if keyed else programs)[protocol][1].text
    cases = _dispatcher_cases(text)
    assert set(cases) == set(P.SPECS) - set(P.GUIDED_COMMANDS)  # the guided program's: test_rapid_guided.py
    for name, spec in P.SPECS.items():
        if name not in P.GUIDED_COMMANDS:
            assert cases[name] == len(spec.args), name
    # tool writes are refused with the codec's E_AUTH until KEY succeeded; reading stays open
    bodies = {block.split('"', 1)[0]: block for block in re.split(r'\n    CASE "', text)[1:]}
    for name in ("TOOLPOS", "TOOLROT", "TOOLLOAD", "TOOLSAVE"):
        assert f'IF NOT heAuthorised THEN\n        heReply := id + " ERR {P.E_AUTH} not authorised: send KEY first";' \
            in bodies[name], name
    for name in ("GETTOOLPOS", "GETTOOLROT", "GETTOOLLOAD", "JOINTS", "GOTO"):
        assert "heAuthorised" not in bodies[name].split("\n    CASE")[0], name
    assert "HeCheckKey id, heWords{3};" in bodies["KEY"]


@pytest.mark.parametrize("keyed", [False, True], ids=["no-key", "key"])
@pytest.mark.parametrize("protocol", ["socket", "serial"])
def test_rapid_replies_use_the_codec_error_codes_and_fit(programs, keyed_programs, protocol, keyed):
    text = (keyed_programs if keyed else programs)[protocol][1].text
    codes = {int(c) for c in re.findall(r'" ERR (\d+) ', text)} | {int(c) for c in re.findall(r'"0 ERR (\d+) ', text)}
    assert codes and codes <= set(P.ERROR_CODES)
    assert P.E_AUTH in codes
    for literal in re.findall(r'"(?:[^"\n]|"")*"', text):
        assert string_length(literal) <= P.MAX_MESSAGE
    assert RAPID_PROTOCOL_VERSION == P.PROTOCOL_VERSION
    assert f'" OK {P.PROTOCOL_VERSION} RAPID"' in text
    assert f"LOCAL CONST num HE_KEY_TRIES := {P.KEY_TRIES};" in text and KEY_TRIES == P.KEY_TRIES


def test_io_module_uses_the_signals_of_the_register_map(programs):
    text = programs["modbus"][1].text
    used = set(re.findall(r"\b([gd][io]He\w+|a[io]He\w+)\b", text))
    assert used == set(IO_SIGNALS)
    from handeye.drivers.controller.modbus_map import GUIDED_REGISTERS

    mapped = {name for reg in load_register_map().registers.values() for name in reg.signals()
              if reg.name not in GUIDED_REGISTERS}  # the guided HeIo's: test_rapid_guided.py
    for reg in load_register_map().registers.values():
        assert len(reg.signals()) == reg.count, reg.name
    assert used == mapped
    # state codes of the I/O module and of the map agree
    from handeye.drivers.controller.modbus_map import STATE_CODES

    from handeye.rapid.generate import render_guide

    main, guide = programs["modbus"][0].text, render_guide(default_station()).text
    for name, code in STATE_CODES.items():
        assert f"CONST num HE_{name} := {code};" in guide
        if name not in ("PROMPT", "JOG", "DONE"):  # the guided program's own states
            assert f"CONST num HE_{name} := {code};" in main


# --- station config

def test_station_yaml(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text(
        "robot: IRB1400\n"
        "controller: {protocol: modbus, pc_address: 192.168.125.10, controller_address: auto, port: 1500}\n"
        "motion: {speed_tcp_mm_s: 150}\n"
        "tool: {name: tXb3, mass_kg: 1.4, cog_mm: [0, 10, 70]}\n"
        "postures: [[0, 0, 0, 0, 30, 0], [10, -5, 5, 0, 40, 90]]\n"
        "capture: {anything: for the later station issue}\n")
    station = load_station(path)
    assert (station.protocol, station.port, station.tool_name, station.speed_tcp_mm_s) == ("modbus", 1500, "tXb3", 150.0)
    assert station.speed_ori_deg_s == 100.0  # from the built-in station
    modules = render_program(station)
    assert [m.name for m in modules] == ["HeMain", "HeIo", "HeTool"]
    assert "PERS tooldata tXb3 :=" in modules[2].text and "tXb3 := t;" in modules[1].text


@pytest.mark.parametrize("text, message", [
    ("controller: {protocol: profinet}", "protocol"),
    ("controller: {pc_address: 300.1.1.1}", "pc_address"),
    ("controller: {port: 0}", "port"),
    ("controller: {colour: red}", "unknown key"),
    ("tool: {name: tool0}", "tool.name"),
    ("tool: {name: a_name_that_is_far_too_long_for_rapid_x}", "tool.name"),
    ("tool: {mass_kg: 0}", "mass_kg"),
    ("motion: {speed_tcp_mm_s: .nan}", "speed_tcp_mm_s"),
    ("postures: [[0, 0, 0, 0, 0]]", "6 joint angles"),
    ("postures: [[0, 71, 0, 0, 0, 0]]", "axis 2"),
    ("[1, 2]", "mapping"),
    ("controller: {port: [", "not valid YAML"),
])
def test_bad_station_configs_are_refused(tmp_path, text, message):
    path = tmp_path / "station.yaml"
    path.write_text(text)
    with pytest.raises(StationConfigError, match=message):
        load_station(path)


def test_missing_config_names_what_to_do(tmp_path):
    with pytest.raises(StationConfigError, match="not found.*--config"):
        load_station(tmp_path / "nope.yaml")


def test_rapid_literals():
    from handeye.rapid.literals import jointtarget_literal, speeddata_literal, tooldata_literal

    assert tooldata_literal(np.eye(4), 0.5) == "[TRUE,[[0,0,0],[1,0,0,0]],[0.5,[0,0,0],[1,0,0,0],0,0,0]]"
    assert jointtarget_literal([1, -2.00004, 3.12345, 0, 0, -300]) == \
        "[[1,-2,3.1235,0,0,-300],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    assert speeddata_literal(200, 100) == "[200,100,5000,1000]"
    with pytest.raises(ValueError, match="mass"):
        tooldata_literal(np.eye(4), 0.0)
    with pytest.raises(ValueError):
        jointtarget_literal([0, 0, 0])
