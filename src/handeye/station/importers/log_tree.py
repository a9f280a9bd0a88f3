"""Pose arrays in JSON or YAML of any nesting.

:func:`find_poses` walks a parsed document and collects its *pose leaves*:

- a list of 6, 7, 12 or 16 numbers; a list of 4 (or 3) lists of 4 numbers (a matrix); a list of six
  one-number lists (ViSP's pose vector column); positions and rotation vectors as such columns too
  (OpenCV's ``rvec``/``tvec``, ``[[x], [y], [z]]``);
- an OpenCV/ViSP matrix mapping ``{rows, cols, data}``;
- a mapping with a position (``position``, ``translation``, ``t``, ``xyz``, ... as 3 numbers or
  ``{x, y, z}``) and a rotation (``orientation``, ``rotation``, ``quaternion``, ``rvec``, ``rpy``,
  ... as 4 or 3 numbers, named components ``{x, y, z, w}`` / ``{roll, pitch, yaw}``, or a 3x3
  matrix), or flat keys ``x y z`` + ``qx qy qz qw`` / ``q1..q4`` / ``rx ry rz`` / ``a b c`` (KUKA) /
  ``w p r`` (Fanuc) / ``roll pitch yaw``.

Each leaf gets a *signature*: its path with the posture number replaced by ``*`` (list positions in
lists longer than two, and numbers at the end of keys such as ``T1_12`` or ``pose3``). The leaves
of a log fall into two signatures of the same postures: the robot's and the camera's.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .conventions import PoseConvention, conventions_for_width
from .names import side_of

__all__ = ["Leaf", "find_poses", "MAX_LEAVES", "MAX_DEPTH"]

#: Walks stop here: a hand-eye log has at most thousands of poses and a few levels of nesting.
MAX_LEAVES = 200_000
MAX_DEPTH = 40
#: A structure that fixes the position first (named position key), not the rotation reading.
POSITION_FIRST = "position_first"
_NUMBERED_KEY = re.compile(r"^(.*?[A-Za-z])[_\-]?(\d{1,6})$")
_POSITION_KEYS = ("position", "translation", "pos", "trans", "t", "xyz", "origin", "p", "tvec", "location", "point")
_ROTATION_KEYS = ("orientation", "rotation", "quaternion", "quat", "q", "rot", "r", "rvec", "rotvec", "rotation_vector",
                  "thetau", "theta_u", "euler", "rpy", "abc", "wpr", "angles", "rotation_matrix", "matrix", "rmat")


@dataclass(frozen=True)
class Leaf:
    """One pose found in a document.

    Attributes
    ----------
    signature : tuple
        The path with posture numbers replaced by ``*``.
    index : tuple
        The posture numbers taken out of the path.
    path : str
        The full path, for messages (``samples[3].robot``).
    values : tuple of float
        The pose's numbers in the layout of ``conventions``.
    conventions : tuple of PoseConvention or None
        The readings the structure allows (named components decide); ``None``: every reading of
        the width.
    names : tuple of str
        The keys on the path (for side and direction hints).
    """

    signature: tuple
    index: tuple
    path: str
    values: tuple
    conventions: tuple | None
    names: tuple


def _numbers(value, count: int | None = None):
    """A flat tuple of plain numbers (``int``/``float``, not bool) from a list, or ``None``."""
    if not isinstance(value, list) or not value or not all(type(v) in (int, float) for v in value):
        return None
    if count is not None and len(value) != count:
        return None
    try:
        return tuple(float(v) for v in value)
    except OverflowError:
        return None


def _column(value):
    """A column vector written as one-number lists (``[[x], [y], [z]]``, OpenCV's rvec/tvec) as a flat list."""
    if isinstance(value, list) and value and all(isinstance(r, list) and len(r) == 1 for r in value):
        return [r[0] for r in value]
    return value


def _vector3(value):
    value = _column(value)
    if isinstance(value, dict):
        keys = {str(k).lower(): v for k, v in value.items()}
        if all(k in keys for k in "xyz") and all(type(keys[k]) in (int, float) for k in "xyz"):
            try:
                return tuple(float(keys[k]) for k in "xyz")
            except OverflowError:
                return None
        return None
    return _numbers(value, 3)


def _rotation(value, key: str):
    """``(numbers, conventions)`` of a rotation value under ``key``, or ``None``."""
    key = key.lower()
    value = _column(value)
    if isinstance(value, dict):
        keys = {str(k).lower(): v for k, v in value.items()}
        for names, convention in ((("x", "y", "z", "w"), PoseConvention("quaternion", "xyzw", width=7)),
                                  (("qx", "qy", "qz", "qw"), PoseConvention("quaternion", "xyzw", width=7))):
            if all(n in keys and type(keys[n]) in (int, float) for n in names):
                return tuple(float(keys[n]) for n in names), (convention,)
        if all(n in keys for n in ("roll", "pitch", "yaw")):
            values = _numbers([keys["roll"], keys["pitch"], keys["yaw"]])
            if values:
                return values, tuple(PoseConvention("euler", sequence="xyz", degrees=d) for d in (True, False))
        values = _vector3(value)
        return (values, POSITION_FIRST) if values else None
    flat = _numbers(value)
    if flat is None and isinstance(value, list) and len(value) == 3 and all(_numbers(r, 3) for r in value):
        flat = tuple(v for r in value for v in r)  # a 3x3 rotation matrix, rows
    if flat is None:
        return None
    if len(flat) == 4:
        return flat, POSITION_FIRST
    if len(flat) == 3:
        if key in ("rvec", "rotvec", "rotation_vector", "thetau", "theta_u"):
            return flat, (PoseConvention("rotvec", width=6),)
        if key in ("rpy",):
            return flat, tuple(PoseConvention("euler", sequence="xyz", degrees=d) for d in (True, False))
        if key in ("abc",):
            return flat, (PoseConvention("euler", sequence="ZYX", degrees=True),)
        if key in ("wpr",):
            return flat, (PoseConvention("euler", sequence="xyz", degrees=True),)
        return flat, POSITION_FIRST
    if len(flat) == 9:
        return flat, "matrix"
    return None


def _flat_keys(keys: dict):
    """Flat ``x y z`` + rotation keys (module docstring): ``(numbers, conventions)`` or ``None``."""
    if not all(k in keys and type(keys[k]) in (int, float) for k in "xyz"):
        return None
    position = tuple(float(keys[k]) for k in "xyz")
    options = [
        (("qx", "qy", "qz", "qw"), (PoseConvention("quaternion", "xyzw", width=7),)),
        (("qw", "qx", "qy", "qz"), (PoseConvention("quaternion", "wxyz", width=7),)),
        (("q1", "q2", "q3", "q4"), POSITION_FIRST),
        (("a", "b", "c"), (PoseConvention("euler", sequence="ZYX", degrees=True),)),
        (("w", "p", "r"), (PoseConvention("euler", sequence="xyz", degrees=True),)),
        (("roll", "pitch", "yaw"), tuple(PoseConvention("euler", sequence="xyz", degrees=d) for d in (True, False))),
        (("rx", "ry", "rz"), POSITION_FIRST),
    ]
    for names, conventions in options:
        if all(n in keys and type(keys[n]) in (int, float) for n in names):
            return position + tuple(float(keys[n]) for n in names), conventions
    return None


def _leaf(value):
    """``(numbers, conventions)`` when ``value`` is a pose (module docstring), else ``None``."""
    if isinstance(value, list):
        flat = _numbers(value)
        if flat is not None:
            return (flat, None) if len(flat) in (6, 7, 12, 16) else None
        if len(value) in (3, 4) and all(_numbers(r, 4) for r in value):
            return tuple(float(v) for r in value for v in r), None
        if len(value) == 6 and all(_numbers(r, 1) for r in value):
            return tuple(float(r[0]) for r in value), None
        return None
    if not isinstance(value, dict):
        return None
    keys = {str(k).lower(): v for k, v in value.items()}
    if "data" in keys and "rows" in keys and "cols" in keys:
        data = keys["data"]
        flat = _numbers(data) if not (isinstance(data, list) and data and isinstance(data[0], list)) else _numbers(
            [v for r in data if isinstance(r, list) for v in r])
        if flat is not None and len(flat) in (6, 7, 12, 16):
            return flat, None
        return None
    found = _flat_keys(keys)
    if found:
        return found
    position = next((_vector3(keys[k]) for k in _POSITION_KEYS if k in keys and _vector3(keys[k])), None)
    if position is None:
        return None
    for k in _ROTATION_KEYS:
        if k in keys:
            rotation = _rotation(keys[k], k)
            if rotation is None:
                continue
            numbers, conventions = rotation
            if conventions == "matrix":
                m = np.array(numbers).reshape(3, 3)
                return tuple(np.column_stack([m, position]).ravel()), (PoseConvention("matrix", "row", width=12),)
            return position + numbers, conventions
    return None


def _token(key, length: int | None = None):
    """``(signature element, index or None)`` of a dict key or a list position."""
    if length is not None:
        return ("*", key) if length > 2 else (f"[{key}]", None)
    text = str(key)
    found = _NUMBERED_KEY.match(text)
    if found:
        return (found.group(1) + "_*", int(found.group(2)))
    return (text, None)


def find_poses(document) -> list:
    """Every pose leaf of a parsed JSON/YAML document (module docstring), in document order.

    Raises
    ------
    ValueError
        The document is nested deeper than :data:`MAX_DEPTH` or holds more than :data:`MAX_LEAVES`
        poses.
    """
    leaves: list = []
    stack = [(document, (), (), "", ())]
    visited = 0
    while stack:
        value, signature, index, path, names = stack.pop()
        visited += 1
        if visited > 50 * MAX_LEAVES:
            raise ValueError("too many values to be a hand-eye log")
        if len(signature) > MAX_DEPTH:
            raise ValueError(f"nested deeper than {MAX_DEPTH} levels")
        found = _leaf(value)
        if found is not None:
            numbers, conventions = found
            if conventions == POSITION_FIRST:
                conventions = [c for c in conventions_for_width(len(numbers)) if not c.rotation_first]
            leaves.append(Leaf(signature, index, path or "(top)", numbers,
                               tuple(conventions) if conventions else None, names))
            if len(leaves) > MAX_LEAVES:
                raise ValueError(f"more than {MAX_LEAVES} poses")
            continue
        children = []
        if isinstance(value, dict):
            for key, child in value.items():
                element, number = _token(key)
                children.append((child, signature + (element,), index + ((number,) if number is not None else ()),
                                 f"{path}.{key}" if path else str(key), names + (str(key),)))
        elif isinstance(value, list):
            for k, child in enumerate(value):
                element, number = _token(k, len(value))
                children.append((child, signature + (element,), index + ((number,) if number is not None else ()),
                                 f"{path}[{k}]", names))
        stack.extend(reversed(children))
    return leaves


def side_hint(leaves: list) -> str | None:
    """``robot``/``camera`` from the keys of a group of leaves (``None``: the names do not say)."""
    return side_of([n for leaf in leaves[:1] for n in leaf.names])


def conventions_of(leaves: list) -> list:
    """The readings a group of leaves allows: what their structure fixes, else every reading of the width."""
    fixed = [leaf.conventions for leaf in leaves if leaf.conventions]
    if fixed and len(fixed) == len(leaves) and len(set(fixed)) == 1:
        return list(fixed[0])
    return conventions_for_width(len(leaves[0].values))
