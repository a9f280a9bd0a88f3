"""The public face of the package: each room re-exports its names, importing a room is cheap,
``handeye.__version__`` and ``py.typed`` ship, a checkout that is not installed says what to do."""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.resources
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOMS = ("base", "geometry", "robot", "calibration", "drivers", "drivers.controller", "drivers.camera", "rapid", "mocks", "station")
HEAVY = ("numpy", "scipy", "cv2", "pymodbus", "serial", "matplotlib")


def _run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO).stdout


@pytest.mark.parametrize("room", ROOMS)
def test_every_room_exports_its_names_with_a_docstring(room):
    module = importlib.import_module(f"handeye.{room}")
    assert module.__doc__ and module.__all__
    missing = [name for name in module.__all__ if getattr(module, name, None) is None]
    assert not missing, missing
    assert set(module.__all__) <= set(dir(module))
    with pytest.raises(AttributeError, match="has no attribute 'nothing_here'"):
        module.nothing_here  # noqa: B018


def test_the_calibration_entry_points_import_from_the_room():
    assert _run("from handeye.calibration import calibrate, read_session; print(calibrate.__name__, read_session.__name__)") \
        .split() == ["calibrate", "read_session"]


def test_importing_the_rooms_and_building_the_command_line_loads_nothing_heavy():
    code = ("import sys, handeye, handeye.base, handeye.geometry, handeye.robot, handeye.calibration, handeye.drivers, handeye.drivers.controller, "
            "handeye.drivers.camera, handeye.rapid, handeye.mocks, handeye.station\n"
            "from handeye.station.cli import build_parser\n"
            "build_parser()\n"
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    assert _run(code).strip() == "[]"


def test_the_version_is_the_installed_distributions():
    import handeye

    assert handeye.__version__ == importlib.metadata.version("handeye")
    assert handeye.__version__[0].isdigit()
    text = (REPO / "pyproject.toml").read_text()
    assert f'version = "{handeye.__version__}"' in text


def test_the_package_is_typed():
    assert importlib.resources.files("handeye").joinpath("py.typed").is_file()
    setup = (REPO / "setup.py").read_text()
    assert 'package_data["handeye"] = ["py.typed"]' in setup and 'package_dir={"": "src"}' in setup


def test_a_checkout_that_is_not_installed_stops_with_one_line():
    hide = ("import sys\n"
            "sys.meta_path[:] = [f for f in sys.meta_path if 'editable' not in getattr(f, '__module__', '').lower()]\n"
            "sys.path[:] = [p for p in sys.path if 'editable' not in p and not p.rstrip('/').endswith('/src')]\n"
            "import pytest\n"
            "sys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', '--collect-only', 'tests/calibration/test_rotations.py']))")
    done = subprocess.run([sys.executable, "-c", hide], capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 4, done.stdout + done.stderr
    assert 'handeye is not importable' in done.stdout + done.stderr
    assert 'pip install -e ".[test]"' in done.stdout + done.stderr
