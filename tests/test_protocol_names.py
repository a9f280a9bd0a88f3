"""One place per controller back end (issue 20): no code outside a back end's own modules and the
registries decides by a protocol's name, and no text lists the protocols by hand and misses one.

A back end is one registry entry (``drivers/controller/backends.py``): its class, default port,
link settings, RAPID link module and mock. Everything else asks the registry, so a plug-in's
protocol is reached exactly as a built-in one.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from handeye.drivers.controller.backends import CONTROLLERS
from helpers import docstring_nodes

REPO = Path(__file__).resolve().parents[1]
ROOMS = ("base", "geometry", "robot", "calibration", "drivers", "rapid", "mocks", "station")
#: The package's own controller back ends (no plug-in installed here).
BUILT_IN = CONTROLLERS.names()

#: Files where a protocol's name belongs, and why.
ALLOWED = {
    "drivers/controller/backends.py": "the registry: each back end's entry, and the default protocol",
    "drivers/controller/socket_client.py": "the socket back end's own client",
    "drivers/controller/serial_client.py": "the serial back end's own client",
    "drivers/controller/modbus_client.py": "the modbus back end's own client (its errors carry its name)",
    "drivers/controller/modbus_map.py": "the modbus back end's register map (its errors carry its name)",
    "drivers/controller/rws_client.py": "the rws back end's own client",
    "rapid/links.py": "the RAPID side of the package's own back ends (rapid never reads the registry)",
    "mocks/backends.py": "the mocks' registration: which server serves which of the package's back ends",
    "mocks/controller/line_server.py": "the socket and serial mocks' own servers",
    "mocks/controller/modbus_server.py": "the modbus mock's own server",
    "mocks/controller/rws_server.py": "the rws mock's own server",
}
#: Files where a protocol's word means something else: how many times, and what.
OTHER_MEANING = {
    "drivers/camera/xb3.py": (1, "'serial': the camera's serial number"),
    "mocks/cell.py": (4, "'serial': the mock camera's serial number in the cell service's replies"),
    "rapid/interpreter/builtins/serial.py": (1, "'serial': RAPID's serial channels (the interpreter's binding)"),
}


def protocol_constants(source: str, names=BUILT_IN) -> list[tuple[int, str]]:
    """``(line, value)`` of every string constant in code (docstrings aside) that is a protocol's name."""
    tree = ast.parse(source)
    docs = docstring_nodes(tree)
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs
            and node.value.lower() in names]


def _python_files():
    for room in ROOMS:
        for path in sorted((REPO / "src" / "handeye" / room).rglob("*.py")):
            yield path.relative_to(REPO / 'src' / 'handeye').as_posix(), path


def test_no_code_outside_a_back_end_and_the_registries_names_a_protocol():
    found = {}
    for rel, path in _python_files():
        hits = protocol_constants(path.read_text())
        if hits and rel not in ALLOWED:
            found[rel] = hits
    strays = {rel: hits for rel, hits in found.items()
              if rel not in OTHER_MEANING or len(hits) != OTHER_MEANING[rel][0]}
    assert not strays, ("protocol names in code outside the back ends' own modules and the registries (ask "
                        f"CONTROLLERS / RAPID_LINKS / mock_protocols instead): {strays}")
    assert set(OTHER_MEANING) <= set(found)  # each exception still needed


def test_the_allowed_files_exist():
    assert all((REPO / "src" / "handeye" / rel).is_file() for rel in list(ALLOWED) + list(OTHER_MEANING))


def test_the_scan_sees_a_protocol_special_case():
    snippet = '"""A docstring may say socket."""\nif link.protocol == "serial":\n    port = {"modbus": 502}\n'
    assert protocol_constants(snippet) == [(2, "serial"), (3, "modbus")]


#: A list of protocol names in prose: two or more of them joined by ',', '|', '/', 'or', 'and'.
_NAME = r"[`\"']*(?:{names})[`\"']*"
_JOIN = r"(?:\s*(?:,|\||/)\s*(?:or\s+|and\s+)?|\s+(?:or|and)\s+)"


def protocol_lists(text: str, names=BUILT_IN) -> list[set]:
    """The sets of protocol names each hand-written list in ``text`` holds."""
    name = _NAME.format(names="|".join(map(re.escape, names)))
    pattern = re.compile(rf"{name}(?:{_JOIN}{name})+", re.IGNORECASE)
    words = re.compile("|".join(map(re.escape, names)), re.IGNORECASE)
    return [{w.lower() for w in words.findall(m.group(0))} for m in pattern.finditer(text)]


def test_no_text_lists_the_protocols_and_misses_one():
    # "socket, serial or modbus" written before rws existed: a list of most of them must name all
    stale = []
    for room in ROOMS:
        for path in sorted((REPO / "src" / "handeye" / room).rglob("*")):
            if path.suffix not in (".py", ".yaml", ".md") or not path.is_file():
                continue
            for found in protocol_lists(path.read_text()):
                if len(found) >= len(BUILT_IN) - 1 and found != set(BUILT_IN):
                    stale.append(f"{path.relative_to(REPO / 'src' / 'handeye')}: {sorted(found)}")
    assert not stale, stale


def test_the_list_scan_sees_a_stale_list():
    assert protocol_lists("back ends by name (``socket``, ``serial``, ``modbus``)") == [{"socket", "serial", "modbus"}]
    assert protocol_lists("socket | serial | modbus | rws") == [set(BUILT_IN)]
