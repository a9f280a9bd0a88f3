"""The modules that moved rooms (issue 39) keep their old paths for one release: importing one warns with
the new path and gives the very module at the new path.  # handeye-rooms-shim (the codemod leaves this file)"""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "handeye"
OLD = {"handeye.calibration.registry": "handeye.base.registry", "handeye.calibration.errors": "handeye.base.errors",
       "handeye.calibration.kinematics": "handeye.robot.kinematics", "handeye.calibration.transforms": "handeye.geometry.transforms",
       "handeye.drivers.camera.stereo_calibration": "handeye.drivers.camera.stereo_fit"}


def _aliases():
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text()
        if "handeye-rooms-shim" in text and "alias_module(__name__, " in text:
            new = text.split('alias_module(__name__, "')[1].split('"')[0]
            yield ".".join(("handeye", *path.relative_to(PACKAGE).with_suffix("").parts)), new


@pytest.mark.parametrize("old, new", sorted(OLD.items()))
def test_an_old_path_warns_and_is_the_new_module(old, new):
    # a fresh interpreter: here the old module may have been imported (and warned) already
    code = (f"import warnings; warnings.simplefilter('error', DeprecationWarning)\n"
            f"try:\n    import {old}\nexcept DeprecationWarning as w:\n    print('warned:', w)\n"
            f"warnings.simplefilter('ignore')\nimport sys, {old}, {new}\nprint(sys.modules['{old}'] is {new})")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.splitlines()
    assert out[0].startswith(f"warned: {old} moved to {new}"), out
    assert out[1] == "True"


def test_every_alias_names_a_module_that_exists():
    aliases = dict(_aliases())
    assert set(OLD.items()) <= set(aliases.items()) and len(aliases) >= 20, aliases
    for new in aliases.values():
        importlib.import_module(new)  # the new home imports without the alias


def test_the_old_names_reach_the_new_objects():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from handeye.calibration.registry import Registry
        from handeye.base import Registry as NewRegistry
    assert Registry is NewRegistry
