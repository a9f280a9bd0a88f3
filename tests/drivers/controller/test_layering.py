"""The rooms keep to ARCHITECTURE.md: drivers/ never imports station/ or mocks/; rapid/ only calibration/."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
RULES = {
    "drivers/controller": {"station", "mocks", "rapid"},
    "rapid": {"station", "mocks", "drivers"},
    "mocks": {"station"},
}


def _imported_rooms(path: Path) -> set:
    rooms = set()
    depth_of_file = len(path.relative_to(REPO / 'src' / 'handeye').parts) - 1  # folders below the package (src/handeye)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            parts = path.relative_to(REPO / 'src' / 'handeye').parts[:depth_of_file - node.level + 1]
            target = list(parts) + (node.module.split(".") if node.module else [])
            if target:
                rooms.add(target[0])
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            for name in names:
                if name.startswith("handeye."):
                    rooms.add(name.split(".")[1])
    return rooms


@pytest.mark.parametrize("folder", sorted(RULES))
def test_imports_respect_the_rooms(folder):
    files = sorted((REPO / "src" / "handeye" / folder).rglob("*.py"))
    assert files
    for path in files:
        bad = _imported_rooms(path) & RULES[folder]
        assert not bad, f"{path.relative_to(REPO / 'src' / 'handeye')} imports {sorted(bad)}"
