"""The rooms' import rules (ARCHITECTURE.md) as import-linter contracts (``[tool.importlinter]`` in
pyproject.toml), run here so that every test run, CI's included, checks them."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "src" / "handeye"
LINT = Path(sys.executable).with_name("lint-imports")

pytestmark = pytest.mark.skipif(not LINT.exists(), reason="import-linter is not installed (the test extra has it)")


def _contract() -> dict:
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["importlinter"]
    assert config["root_package"] == "handeye"
    (layers,) = [c for c in config["contracts"] if c["type"] == "layers"]
    return layers


def _lint(cwd: Path, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT), "--config", "pyproject.toml"], cwd=cwd, capture_output=True, text=True,
                          env=env, timeout=300)


def test_the_rooms_keep_their_layers():
    done = _lint(REPO)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "0 broken" in done.stdout


def test_every_room_is_in_the_layers():
    rooms = {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()}
    named = {room.strip() for layer in _contract()["layers"] for room in layer.split("|")}
    assert named == rooms, f"rooms not in the contract: {rooms - named}; named but absent: {named - rooms}"


@pytest.mark.parametrize("importer, imported", [("calibration", "station"), ("drivers", "rapid"), ("mocks", "station")])
def test_the_contract_breaks_on_a_forbidden_import(tmp_path, importer, imported):
    """The same contract on a package of empty rooms with one forbidden arrow: lint-imports refuses it."""
    root = tmp_path / "handeye"
    for layer in _contract()["layers"]:
        for room in layer.split("|"):
            (root / room.strip()).mkdir(parents=True)
            (root / room.strip() / "__init__.py").write_text("")
    (root / "__init__.py").write_text("")
    (root / importer / "wrong.py").write_text(f"from ..{imported} import anything  # noqa\n")
    (tmp_path / "pyproject.toml").write_text((REPO / "pyproject.toml").read_text())
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    env.pop("PYTHONSAFEPATH", None)
    done = _lint(tmp_path, env)
    assert done.returncode != 0 and "BROKEN" in done.stdout, done.stdout[-2000:] + done.stderr[-1000:]
    assert f"handeye.{importer}.wrong -> handeye.{imported}" in done.stdout
