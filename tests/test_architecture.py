"""The import rules of ARCHITECTURE.md beyond the rooms' layers (those are import-linter's contract, in
pyproject.toml): the core's third-party imports, the mocks named in no driver string, no docstring read."""

import ast
import re
import sys
from pathlib import Path

import pytest
from helpers import docstring_nodes

REPO = Path(__file__).resolve().parents[1]
ROOMS = ("base", "geometry", "robot", "calibration", "drivers", "station", "rapid", "mocks")
# Which room may import which: the import-linter contract in pyproject.toml (tests/test_import_contracts.py).
CALIBRATION_THIRD_PARTY = {"numpy", "scipy", "yaml"}
#: What each of the lower rooms may import beyond the standard library and handeye.
THIRD_PARTY = {"base": {"yaml"}, "geometry": CALIBRATION_THIRD_PARTY, "robot": CALIBRATION_THIRD_PARTY,
               "calibration": CALIBRATION_THIRD_PARTY}


def _imports(path: Path, room: str):
    tree = ast.parse(path.read_text())
    package = ["handeye", room] + list(path.relative_to(REPO / "src" / "handeye" / room).parent.parts)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                yield ".".join(base + ([node.module] if node.module else []))
            else:
                yield node.module


def _files(room):
    return sorted((REPO / "src" / "handeye" / room).rglob("*.py"))


@pytest.mark.parametrize("room", sorted(THIRD_PARTY))
def test_the_core_needs_only_numpy_scipy_yaml(room):
    stdlib = set(sys.stdlib_module_names)
    bad = []
    for file in _files(room):
        for name in _imports(file, room):
            top = name.split(".")[0]
            if top not in stdlib and top != "handeye" and top not in THIRD_PARTY[room]:
                bad.append(f"{file.relative_to(REPO)} imports {name}")
    assert not bad, bad


#: A module path into the mocks inside a string: "handeye.mocks.camera:MockCamera", f"{root}.mocks.camera".
MOCKS_IN_A_STRING = re.compile(r"(^|[.\s'\"/])mocks([.:/]|$)")


def test_drivers_name_no_mocks_in_strings():
    # an import hidden in a "module:Class" string is an import all the same: the mocks register themselves
    bad = []
    for file in _files("drivers"):
        tree = ast.parse(file.read_text())
        docstrings = docstring_nodes(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                if MOCKS_IN_A_STRING.search(node.value):
                    bad.append(f"{file.relative_to(REPO)}:{node.lineno} names the mocks in {node.value!r}")
    assert not bad, bad


def test_the_string_check_sees_a_hidden_import(tmp_path):
    for text in ('T = "handeye.mocks.camera:MockCamera"', 'T = f"{ROOT}.mocks.camera:MockCamera"'):
        tree = ast.parse(text)
        found = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
                 and MOCKS_IN_A_STRING.search(n.value)]
        assert found, text


@pytest.mark.parametrize("room", ROOMS)
def test_no_room_reads_docstrings(room):
    # what a method, a back end or a key is, is declared in a table, not parsed from a docstring
    bad = [f"{file.relative_to(REPO)}" for file in _files(room) if "__doc__" in file.read_text()]
    assert not bad, bad
