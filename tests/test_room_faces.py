"""Each room's ``__init__`` is its face: a module of one room imports another room only from that room's
face (``from ..robot import load_robot``), never from its modules (``from ..robot.kinematics import ...``),
and every name it takes is one the face exports."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "handeye"
ROOMS = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file())


def _imports(source: str, module: list[str], is_package: bool):
    """(imported module, names) for each import of a module at ``handeye.<module>``."""
    package = ["handeye", *module] if is_package else ["handeye", *module[:-1]]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            target = base + (node.module.split(".") if node.module else [])
            yield target, [alias.name for alias in node.names], node.lineno
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split("."), [], node.lineno


def face_breaches(source: str, module: list[str], is_package: bool = False) -> list[str]:
    """The imports of ``handeye.<module>`` that reach past another room's face."""
    bad = []
    for target, names, line in _imports(source, module, is_package):
        if target[:1] != ["handeye"] or len(target) < 2 or target[1] == module[0]:
            continue
        where = f"handeye.{'.'.join(module)}:{line}"
        if len(target) > 2 or not names:
            bad.append(f"{where} imports {'.'.join(target)} (a module of room {target[1]}): import from handeye.{target[1]}")
            continue
        face = importlib.import_module(f"handeye.{target[1]}")
        missing = [n for n in names if n not in face.__all__]
        if missing:
            bad.append(f"{where} imports {missing} from handeye.{target[1]}, which does not export them")
    return bad


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        if len(rel.parts) > 1:
            is_package = rel.name == "__init__"
            yield path, list(rel.parts[:-1] if is_package else rel.parts), is_package


@pytest.mark.parametrize("room", ROOMS)
def test_rooms_meet_only_at_their_faces(room):
    bad = []
    for path, module, is_package in _modules():
        if module[0] == room:
            bad += face_breaches(path.read_text(), module, is_package)
    assert not bad, "\n".join(bad)


def test_a_deep_import_is_seen():
    source = "from ..robot.kinematics import load_robot\nfrom ..robot import load_robot, nothing_such\nimport handeye.base.files\n"
    bad = face_breaches(source, ["station", "x"])
    assert len(bad) == 3, bad
    assert "handeye.robot.kinematics" in bad[0] and "nothing_such" in bad[1] and "handeye.base.files" in bad[2]
    assert face_breaches("from ..robot import load_robot\nfrom .kinematics import RobotModel\n", ["station", "x"]) == []


@pytest.mark.parametrize("room", ROOMS)
def test_every_face_name_loads(room):
    face = importlib.import_module(f"handeye.{room}")
    assert face.__doc__ and face.__all__
    missing = [name for name in face.__all__ if getattr(face, name, None) is None]
    assert not missing, missing
