"""The import rules of ARCHITECTURE.md, checked on the source."""

import ast
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOMS = ("calibration", "drivers", "station", "rapid", "mocks")
# room -> rooms it must not import
FORBIDDEN = {
    "calibration": {"drivers", "station", "rapid", "mocks"},
    "drivers": {"station", "mocks"},
    "rapid": {"drivers", "station", "mocks"},
    "mocks": {"station"},
}
CALIBRATION_THIRD_PARTY = {"numpy", "scipy", "yaml"}


def _imports(path: Path, room: str):
    tree = ast.parse(path.read_text())
    package = ["handeye", room] + list(path.relative_to(REPO / room).parent.parts)
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
    return sorted((REPO / room).rglob("*.py"))


@pytest.mark.parametrize("room", sorted(FORBIDDEN))
def test_rooms_import_only_downwards(room):
    bad = []
    for file in _files(room):
        for name in _imports(file, room):
            parts = name.split(".")
            target = parts[1] if parts[0] == "handeye" and len(parts) > 1 else None
            if target in FORBIDDEN[room]:
                bad.append(f"{file.relative_to(REPO)} imports {name}")
    assert not bad, bad


def test_calibration_needs_only_numpy_scipy_yaml():
    stdlib = set(sys.stdlib_module_names)
    bad = []
    for file in _files("calibration"):
        for name in _imports(file, "calibration"):
            top = name.split(".")[0]
            if top not in stdlib and top != "handeye" and top not in CALIBRATION_THIRD_PARTY:
                bad.append(f"{file.relative_to(REPO)} imports {name}")
    assert not bad, bad
