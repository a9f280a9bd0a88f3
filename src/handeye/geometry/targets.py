"""Calibration targets by name: the one place a board is described (issue 37).

Three kinds are the package's own, in :data:`TARGETS` (a :class:`~handeye.base.registry.Registry`
like the methods' and the back ends', so another installed package adds one through the entry-point
group ``handeye.targets``):

``checkerboard``
    Today's board, :class:`~handeye.geometry.board.BoardGeometry`: ``corners`` inner corners
    (long side first) of ``square_mm``. Must be seen whole.
``charuco``
    :class:`CharucoBoard`: a checkerboard of ``squares`` (x, y) squares of ``square_mm`` with ArUco markers
    of ``marker_mm`` from OpenCV's ``dictionary`` in its white squares (OpenCV's ``cv2.aruco.CharucoBoard``;
    ``legacy`` for boards printed by OpenCV before 4.6 with an even number of rows). Its inner corners are
    the checkerboard's: ``corners = squares - 1``, and corner id ``k = row * nx + col`` is both OpenCV's
    ChArUco id and the canonical index of the target frame, so a view may hold any subset of the corners.
``circles``
    :class:`CircleGrid`: OpenCV's asymmetric circle grid of ``corners = (per row, rows)`` circles, ``square_mm``
    the spacing between neighbouring circles of one row (``cv2.findCirclesGrid(..., CALIB_CB_ASYMMETRIC_GRID)``).
    Must be seen whole (OpenCV finds the grid as a whole).

The target frame (conventions.md) is the same for every kind: origin at corner 0, x along the long side, y
along the short side, z = x × y into the board. Pure numpy/standard library: the detectors are in
``handeye.drivers.camera`` (OpenCV).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import ClassVar, TypeVar, cast

import numpy as np
import numpy.typing as npt

from .board import STATION_BOARD, BoardGeometry
from ..base import CalibrationError, brief
from ..base import Registry

__all__ = ["MIN_CORNERS", "MIN_SPAN_FRACTION", "view_refusal", "CharucoBoard", "CircleGrid", "TargetKind", "TARGETS", "register_target", "target_kind", "target_to_dict",
           "target_from_dict", "parse_target_spec", "STATION_CHARUCO", "STATION_CIRCLES", "partial_ok", "describe"]

_Board = TypeVar("_Board", bound=BoardGeometry)

#: ArUco dictionaries OpenCV predefines (``cv2.aruco.DICT_*``), with their marker counts.
DICTIONARIES = {f"DICT_{bits}X{bits}_{count}": count for bits in (4, 5, 6, 7) for count in (50, 100, 250, 1000)}
DICTIONARIES.update({"DICT_ARUCO_ORIGINAL": 1024, "DICT_APRILTAG_16h5": 30, "DICT_APRILTAG_25h9": 35,
                     "DICT_APRILTAG_36h10": 2320, "DICT_APRILTAG_36h11": 587})


@dataclass(frozen=True)
class CharucoBoard(BoardGeometry):
    """A ChArUco board: a checkerboard whose white squares hold ArUco markers.

    Attributes
    ----------
    corners : tuple of int
        Inner corners ``(squares_x - 1, squares_y - 1)``; id ``row * nx + col`` (OpenCV's and canonical).
    square_mm : float
    marker_mm : float
        Side of a marker (smaller than the square).
    dictionary : str
        OpenCV dictionary name, ``DICT_5X5_100`` ...
    legacy : bool
        OpenCV's legacy layout (boards made before OpenCV 4.6 with an even number of square rows).
    """

    marker_mm: float = 22.0
    dictionary: str = "DICT_5X5_100"
    legacy: bool = False
    kind: ClassVar[str] = "charuco"

    @property
    def squares(self) -> tuple[int, int]:
        return int(self.corners[0]) + 1, int(self.corners[1]) + 1


@dataclass(frozen=True)
class CircleGrid(BoardGeometry):
    """OpenCV's asymmetric circle grid: ``corners = (per row, rows)`` circles; ``square_mm`` is the spacing
    of two circles in one row; circle ``k = row * per_row + col`` sits at ``((2 col + row % 2) s/2, row s/2)``
    (OpenCV's object points with its ``size`` = ``s/2``)."""

    diameter_mm: float | None = None
    kind: ClassVar[str] = "circles"

    def grid(self, square_mm: float | None = None) -> np.ndarray:
        s = 0.5 * float(square_mm if square_mm is not None else (self.square_mm or 1.0))
        per_row, rows = int(self.corners[0]), int(self.corners[1])
        row, col = np.divmod(np.arange(per_row * rows), per_row)
        return np.stack([(2 * col + row % 2) * s, row * s, np.zeros(len(row))], axis=1).astype(float)


#: The station's ChArUco board: 14 x 9 squares (13 x 8 inner corners, as the checkerboard) of 30 mm,
#: 22 mm markers of DICT_5X5_100 (63 markers).
STATION_CHARUCO = CharucoBoard(STATION_BOARD.corners, STATION_BOARD.square_mm, 22.0, "DICT_5X5_100", False)
#: OpenCV's sample asymmetric grid: 4 circles per row, 11 rows, 40 mm between circles of a row.
STATION_CIRCLES = CircleGrid((4, 11), 40.0)


def target_kind(board: object) -> str:
    """``checkerboard``, ``charuco``, ``circles`` (or a plug-in's kind) of a board geometry."""
    return getattr(board, "kind", "checkerboard")


def partial_ok(board: object) -> bool:
    """True when a view may hold a subset of the board's corners (ids tell which): ChArUco, not the grids."""
    kind = target_kind(board)
    return kind in TARGETS and TARGETS[kind].partial


def _number(value, key: str, low: float, high: float) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not low < value <= high:
        raise ValueError(f"{key} must be a number of mm in ({low:g}, {high:g}]; got {brief(value)}")
    return float(value)


def _pair(value, key: str, low: int) -> tuple[int, int]:
    if (not isinstance(value, (list, tuple)) or len(value) != 2
            or not all(isinstance(c, int) and not isinstance(c, bool) and low <= c <= 1000 for c in value)):
        raise ValueError(f"{key} must be two whole numbers {low}..1000; got {brief(value)}")
    return int(value[0]), int(value[1])


def _long_first(pair: tuple[int, int], key: str) -> tuple[int, int]:
    if pair[0] < pair[1]:
        raise ValueError(f"{key}: give the long side first: [{pair[1]}, {pair[0]}] (x runs along the long side)")
    return pair


def _checkerboard(data: dict) -> BoardGeometry:
    corners = _long_first(_pair(data.get("corners", list(STATION_BOARD.corners)), "corners", 2), "corners")
    square = data.get("square_mm", STATION_BOARD.square_mm)
    return BoardGeometry(corners, None if square is None else _number(square, "square_mm", 0, 1e4))


def _charuco(data: dict) -> CharucoBoard:
    d = STATION_CHARUCO
    if "squares" in data and "corners" in data:
        raise ValueError("give a ChArUco board's squares or its corners (squares - 1), not both")
    if "corners" in data:
        squares = tuple(c + 1 for c in _pair(data["corners"], "corners", 2))
    else:
        squares = _pair(data.get("squares", list(d.squares)), "squares", 3)
    squares = _long_first((int(squares[0]), int(squares[1])), "squares")
    square = _number(data.get("square_mm", d.square_mm), "square_mm", 0, 1e4)
    marker = _number(data.get("marker_mm", d.marker_mm), "marker_mm", 0, 1e4)
    if marker >= square:
        raise ValueError(f"marker_mm ({marker:g}) must be smaller than square_mm ({square:g})")
    dictionary = data.get("dictionary", d.dictionary)
    if dictionary not in DICTIONARIES:
        raise ValueError(f"dictionary must be an OpenCV ArUco dictionary like DICT_5X5_100; got {brief(dictionary)}")
    markers = (squares[0] * squares[1]) // 2
    if markers > DICTIONARIES[dictionary]:
        raise ValueError(f"a {squares[0]}x{squares[1]} ChArUco board needs {markers} markers; {dictionary} has "
                         f"{DICTIONARIES[dictionary]}: choose a larger dictionary")
    legacy = data.get("legacy", d.legacy)
    if not isinstance(legacy, bool):
        raise ValueError(f"legacy must be true or false; got {brief(legacy)}")
    return CharucoBoard((squares[0] - 1, squares[1] - 1), square, marker, dictionary, legacy)


def _circles(data: dict) -> CircleGrid:
    d = STATION_CIRCLES
    corners = _pair(data.get("corners", list(d.corners)), "corners", 2)
    square = _number(data.get("square_mm", d.square_mm), "square_mm", 0, 1e4)
    diameter = data.get("diameter_mm")
    return CircleGrid(corners, square, None if diameter is None else _number(diameter, "diameter_mm", 0, square))


@dataclass(frozen=True)
class TargetKind:
    """One kind of target in :data:`TARGETS`.

    Attributes
    ----------
    name : str
    summary : str
    keys : tuple of str
        The keys of its description (besides ``type``).
    parse : callable
        ``parse(mapping) -> BoardGeometry`` (raises ValueError with one line).
    partial : bool
        A view may hold a subset of its corners (by id).
    detector : str or callable, optional
        ``"module:attribute"`` of its image detector for a plug-in's kind (the package's own are in
        ``handeye.drivers.camera.targets``).
    """

    name: str
    summary: str
    keys: tuple
    parse: Callable
    partial: bool = False
    detector: object = None
    defaults: dict = field(default_factory=dict)


#: Every target kind by name (the package's, then those of entry points ``handeye.targets``).
TARGETS: Registry[TargetKind] = Registry("target", "handeye.targets", TargetKind)


def register_target(kind: TargetKind) -> TargetKind:
    """Add a target kind to :data:`TARGETS` (or replace the one of its name); returns it."""
    return TARGETS.register(kind)


register_target(TargetKind("checkerboard", "a checkerboard, seen whole", ("corners", "square_mm"), _checkerboard))
register_target(TargetKind("charuco", "a ChArUco board (checkerboard with ArUco markers): partial views by corner id",
                           ("squares", "corners", "square_mm", "marker_mm", "dictionary", "legacy"), _charuco, partial=True))
register_target(TargetKind("circles", "OpenCV's asymmetric circle grid, seen whole", ("corners", "square_mm", "diameter_mm"),
                           _circles))


def target_from_dict(data: object) -> BoardGeometry:
    """A board from a description ``{type: ..., keys}`` (``type`` missing: checkerboard).

    Raises
    ------
    ValueError
        One line naming the key at fault.
    """
    if not isinstance(data, dict):
        raise ValueError(f"a target is a mapping with type and its keys; got {brief(data)}")
    kind = data.get("type", "checkerboard")
    if not isinstance(kind, str) or kind.lower() not in TARGETS:
        raise ValueError(f"type must be one of {', '.join(TARGETS.names())}; got {brief(kind)}")
    entry = TARGETS[kind.lower()]
    unknown = sorted(set(data) - {"type", *entry.keys}, key=str)
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!s} of a {entry.name} target; known: type, {', '.join(entry.keys)}")
    return entry.parse({k: v for k, v in data.items() if k != "type"})


def target_to_dict(board: BoardGeometry) -> dict:
    """The description of a board (what session.yaml and the station config hold)."""
    kind = target_kind(board)
    if kind == "charuco":
        charuco = cast(CharucoBoard, board)  # the kind "charuco" is CharucoBoard's (its ClassVar)
        if charuco.square_mm is None:
            raise ValueError("a ChArUco board's description needs its square_mm")
        return {"type": "charuco", "squares": list(charuco.squares), "square_mm": float(charuco.square_mm),
                "marker_mm": float(charuco.marker_mm), "dictionary": charuco.dictionary, "legacy": bool(charuco.legacy)}
    out = {"type": kind, "corners": [int(c) for c in board.corners]}
    if board.square_mm is not None:
        out["square_mm"] = float(board.square_mm)
    diameter = cast(CircleGrid, board).diameter_mm if kind == "circles" else None  # "circles" is CircleGrid's kind
    if diameter is not None:
        out["diameter_mm"] = float(diameter)
    return out


def describe(board: BoardGeometry) -> str:
    """One line naming a board: ``13x8 checkerboard of 30 mm``, ``ChArUco 14x9 squares of 30 mm, 22 mm DICT_5X5_100``."""
    kind = target_kind(board)
    if kind == "charuco":
        charuco = cast(CharucoBoard, board)  # the kind "charuco" is CharucoBoard's (its ClassVar)
        sx, sy = charuco.squares
        return (f"ChArUco {sx}x{sy} squares of {charuco.square_mm:g} mm, {charuco.marker_mm:g} mm markers "
                f"{charuco.dictionary}" + (" (legacy layout)" if charuco.legacy else ""))
    nx, ny = board.corners
    size = f" of {board.square_mm:g} mm" if board.square_mm else ""
    return f"{nx}x{ny} asymmetric circle grid{size}" if kind == "circles" else f"{nx}x{ny} checkerboard{size}"


def parse_target_spec(text: str, square_mm: float | None = None) -> BoardGeometry:
    """A board from a command line's ``--board``: ``13x8`` (checkerboard corners, as before), a kind name
    (``charuco``, ``circles``, ``checkerboard``: the station's board of that kind) or a kind with keys,
    ``charuco:squares=10x7,square_mm=25,marker_mm=18,dictionary=DICT_4X4_50,legacy=true``.

    Raises
    ------
    CalibrationError
        One line saying what to write.
    """
    text = str(text).strip()
    kind, _, rest = text.partition(":")
    if kind.lower() not in TARGETS:
        from ..geometry import BoardGeometry as _Board  # noqa: PLC0415

        try:
            a, b = (int(v) for v in text.lower().replace("×", "x").split("x"))
        except ValueError:
            raise CalibrationError(f"--board must be inner corners like 13x8 or a target {', '.join(TARGETS.names())} "
                                   f"(with keys: charuco:squares=14x9,square_mm=30,marker_mm=22); got {text!r}") from None
        try:
            return _checkerboard({"corners": [a, b], "square_mm": square_mm}) if square_mm else _Board(
                _long_first(_pair([a, b], "--board", 2), "--board"))
        except ValueError as exc:
            raise CalibrationError(f"--board {exc}") from None
    data: dict = {"type": kind.lower()}
    for item in filter(None, (p.strip() for p in rest.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise CalibrationError(f"--board: write key=value after {kind}:, e.g. charuco:squares=14x9; got {item!r}")
        data[key.strip()] = _spec_value(value.strip())
    if square_mm is not None and "square_mm" not in data:
        data["square_mm"] = float(square_mm)
    try:
        return target_from_dict(data)
    except ValueError as exc:
        raise CalibrationError(f"--board {kind}: {exc}") from None


def _spec_value(value: str):
    if "x" in value.lower() and all(p.strip().isdigit() for p in value.lower().split("x")):
        return [int(p) for p in value.lower().split("x")]
    if value.lower() in ("true", "false"):
        return value.lower() == "true"
    try:
        return int(value) if value.isdigit() else float(value)
    except ValueError:
        return value


def with_square(board: _Board, square_mm: float) -> _Board:
    """The same board with another square size (any kind)."""
    return replace(board, square_mm=float(square_mm))


#: Fewest corners of a partial view (a pose needs 3; a check of spacing and planarity needs more).
MIN_CORNERS = 6
#: The seen corners must span at least this fraction of the board along its long side and along its
#: short side (their bounding box in the target frame), or the pose is poorly fixed.
MIN_SPAN_FRACTION = 0.25


def view_refusal(ids: npt.ArrayLike, board: BoardGeometry) -> str:
    """Why the corners ``ids`` (target indices) of ``board`` cannot fix a board pose ("" when they can)."""
    ids = np.asarray(ids, int)
    if len(ids) < MIN_CORNERS:
        return f"only {len(ids)} corners of the board seen (at least {MIN_CORNERS}): bring more of the board into view"
    grid = board.grid(1.0)
    seen = grid[ids, :2]
    full = np.ptp(grid[:, :2], axis=0)
    span = np.ptp(seen, axis=0) / np.maximum(full, 1e-12)
    if np.min(span) < MIN_SPAN_FRACTION:
        return (f"the seen corners span only {100 * span[0]:.0f} % x {100 * span[1]:.0f} % of the board "
                f"(at least {100 * MIN_SPAN_FRACTION:.0f} % each way): too little to fix its pose")
    rank = np.linalg.matrix_rank(seen - seen.mean(axis=0), tol=1e-6)
    if rank < 2:
        return "the seen corners lie on one line of the board: too little to fix its pose"
    return ""
