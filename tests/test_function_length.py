"""Small functions with one job: no function in any room is over 80 lines.

A function is counted from its ``def`` line to its last line (signature and docstring included), for
every function and method, nested ones too, in every room (calibration, drivers, station, rapid,
mocks). A function that must stay longer (a numeric kernel that reads best as one block) is named
below with the reason.
"""

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ROOMS = ("base", "geometry", "robot", "calibration", "drivers", "station", "rapid", "mocks")
MAX_BODY_LINES = 80

#: (file, function) -> why it may be longer. Numeric kernels that read best as one block go here,
#: each with its reason; none needs it today.
ALLOWED: dict = {}


def _function_bodies():
    """``(file, qualified name, body lines, line)`` of every function of the rooms."""
    for room in ROOMS:
        for path in sorted((REPO / "src" / "handeye" / room).rglob("*.py")):
            tree = ast.parse(path.read_text())
            yield from _walk(tree, path.relative_to(REPO).as_posix(), "")


def _walk(node, file, prefix):
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
            name = f"{prefix}{child.name}"
            yield file, name, child.end_lineno - child.lineno + 1, child.lineno
            yield from _walk(child, file, f"{name}.")
        elif isinstance(child, ast.ClassDef):
            yield from _walk(child, file, f"{prefix}{child.name}.")
        else:
            yield from _walk(child, file, prefix)


def test_no_function_over_80_lines():
    long = [f"{file}:{line} {name} ({lines} lines)" for file, name, lines, line in _function_bodies()
            if lines > MAX_BODY_LINES and (file, name) not in ALLOWED]
    assert not long, f"split these into functions with one job each (or name a numeric kernel in ALLOWED): {long}"


def test_allow_list_names_only_long_functions():
    lengths = {(file, name): lines for file, name, lines, _ in _function_bodies()}
    stale = [f"{file} {name}: {'gone' if (file, name) not in lengths else f'{lengths[file, name]} lines'}"
             for file, name in ALLOWED if lengths.get((file, name), 0) <= MAX_BODY_LINES]
    assert not stale, f"remove from ALLOWED: {stale}"


def test_the_counter_sees_a_long_function():
    source = "def f():\n    '''doc'''\n" + "    x = 1\n" * 85 + "\n\nclass C:\n    def g(self):\n        return 1\n"
    found = {name: lines for _, name, lines, _ in _walk(ast.parse(source), "x.py", "")}
    assert found == {"f": 87, "C.g": 2}
