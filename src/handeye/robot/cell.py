"""The cell around the robot: keep-out volumes in the base frame, what the flange carries, the board's stand.

A volume answers one question, :meth:`signed_distance`: how far a point (base frame, mm) is from it,
negative inside. Three kinds of keep-out volume:

- :class:`Box`: a box, axis-aligned in the base frame, or in a frame of its own (``box2base``; the
  board's stand is one, aligned with the board);
- :class:`Cylinder`: a vertical cylinder (a column, a pillar of a fixture);
- :class:`Floor`: everything below a height.

What the flange carries (the camera, its bracket, a cable loop) is given in tool0 as boxes
(axis-aligned in tool0) and :class:`Sphere` objects. The board's own stand is derived from the
board's pose (:func:`board_stand`). Where the controller has ABB's World Zones option, each volume
becomes a world zone (:meth:`world_zone`): an axis-aligned box or a vertical cylinder in base,
``WZBoxDef`` / ``WZCylDef``; a box of a frame of its own becomes its axis-aligned bounding box.

Frames as in conventions.md: ``base``, ``tool0``, ``target``; lengths in mm.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import BoardGeometry

__all__ = [
    "DEFAULT_CARRIED",
    "Box",
    "CellModel",
    "Cylinder",
    "Floor",
    "KeepOut",
    "Sphere",
    "WORLD_ZONE_REACH_MM",
    "board_stand",
    "floor_height",
]

#: Half the side of the box a floor becomes as a world zone: far beyond any IRB reach.
WORLD_ZONE_REACH_MM = 10000.0


def _points(points: ArrayLike) -> np.ndarray:
    return np.asarray(points, dtype=float)


def _matrix(rows) -> np.ndarray:
    return np.asarray(rows, dtype=float).reshape(4, 4)


@dataclass(frozen=True)
class Box:
    """A box: ``min_mm <= p <= max_mm`` in its own frame.

    Attributes
    ----------
    name : str
    min_mm, max_mm : tuple of float, shape (3,)
        Opposite corners in the box's frame.
    box2parent : tuple of tuple, shape (4, 4), optional
        The box's frame in the frame it is given in (base for a keep-out volume, tool0 for a carried
        box); None: the box is axis-aligned in that frame.
    """

    name: str
    min_mm: tuple
    max_mm: tuple
    box2parent: tuple | None = None

    kind = "box"

    def signed_distance(self, points: ArrayLike) -> np.ndarray:
        """Distance (mm) of points ``(..., 3)`` in the parent frame from the box, negative inside; ``(...)``."""
        p = _points(points)
        if self.box2parent is not None:
            frame = _matrix(self.box2parent)
            p = (p - frame[:3, 3]) @ frame[:3, :3]
        low, high = np.asarray(self.min_mm, float), np.asarray(self.max_mm, float)
        centre, half = (low + high) / 2, (high - low) / 2
        q = np.abs(p - centre) - half
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
        return outside + np.minimum(np.max(q, axis=-1), 0.0)

    def corners(self) -> np.ndarray:
        """The 8 corners ``(8, 3)`` in the parent frame."""
        low, high = np.asarray(self.min_mm, float), np.asarray(self.max_mm, float)
        grid = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
        local = low + grid * (high - low)
        if self.box2parent is None:
            return local
        frame = _matrix(self.box2parent)
        return local @ frame[:3, :3].T + frame[:3, 3]

    @property
    def top_mm(self) -> float:
        """The highest point in the parent frame, mm."""
        return float(self.corners()[:, 2].max())

    def world_zone(self) -> dict:
        """The world zone of this volume: ``{type: box, name, min_mm, max_mm}``, axis-aligned in base
        (a box of a frame of its own: its bounding box)."""
        corners = self.corners()
        return {"type": "box", "name": self.name, "min_mm": tuple(corners.min(axis=0).tolist()),
                "max_mm": tuple(corners.max(axis=0).tolist())}

    def to_dict(self) -> dict:
        out = {"type": "box", "name": self.name, "min_mm": list(self.min_mm), "max_mm": list(self.max_mm)}
        if self.box2parent is not None:
            out["box2parent"] = [list(row) for row in self.box2parent]
        return out


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder in base: ``|p_xy - centre| <= radius`` and ``z_min <= z <= z_max``.

    Attributes
    ----------
    name : str
    centre_mm : tuple of float, shape (2,)
        Axis position (x, y) in base.
    radius_mm : float
    z_mm : tuple of float, shape (2,)
        Bottom and top heights in base.
    """

    name: str
    centre_mm: tuple
    radius_mm: float
    z_mm: tuple

    kind = "cylinder"

    def signed_distance(self, points: ArrayLike) -> np.ndarray:
        """Distance (mm) of points ``(..., 3)`` in base from the cylinder, negative inside; ``(...)``."""
        p = _points(points)
        radial = np.linalg.norm(p[..., :2] - np.asarray(self.centre_mm, float), axis=-1) - self.radius_mm
        low, high = self.z_mm
        axial = np.maximum(low - p[..., 2], p[..., 2] - high)
        outside = np.hypot(np.maximum(radial, 0.0), np.maximum(axial, 0.0))
        return outside + np.minimum(np.maximum(radial, axial), 0.0)

    @property
    def top_mm(self) -> float:
        """The height of its top in base, mm."""
        return float(self.z_mm[1])

    def world_zone(self) -> dict:
        """``{type: cylinder, name, base_mm: [x, y, z_min], radius_mm, height_mm}`` (``WZCylDef``)."""
        low, high = self.z_mm
        return {"type": "cylinder", "name": self.name, "base_mm": (float(self.centre_mm[0]), float(self.centre_mm[1]),
                                                                  float(low)),
                "radius_mm": float(self.radius_mm), "height_mm": float(high - low)}

    def to_dict(self) -> dict:
        return {"type": "cylinder", "name": self.name, "centre_mm": list(self.centre_mm), "radius_mm": self.radius_mm,
                "z_mm": list(self.z_mm)}


@dataclass(frozen=True)
class Floor:
    """Everything below ``z_mm`` in base (the floor, a table top the arm must stay above).

    Attributes
    ----------
    name : str
    z_mm : float
    """

    name: str
    z_mm: float

    kind = "floor"

    def signed_distance(self, points: ArrayLike) -> np.ndarray:
        """Height (mm) of points ``(..., 3)`` in base above the floor, negative below; ``(...)``."""
        return _points(points)[..., 2] - self.z_mm

    @property
    def top_mm(self) -> float:
        """The floor's height in base, mm."""
        return float(self.z_mm)

    def world_zone(self) -> dict:
        """A box from far below up to the floor, :data:`WORLD_ZONE_REACH_MM` wide either way."""
        reach = WORLD_ZONE_REACH_MM
        return {"type": "box", "name": self.name, "min_mm": (-reach, -reach, -reach), "max_mm": (reach, reach, self.z_mm)}

    def to_dict(self) -> dict:
        return {"type": "floor", "name": self.name, "z_mm": self.z_mm}


#: A keep-out volume of the cell (``CellModel.keep_out``).
KeepOut = Box | Cylinder | Floor


@dataclass(frozen=True)
class Sphere:
    """A sphere carried by the flange (tool0 frame): a cable loop, a lamp.

    Attributes
    ----------
    name : str
    centre_mm : tuple of float, shape (3,)
    radius_mm : float
    """

    name: str
    centre_mm: tuple
    radius_mm: float

    kind = "sphere"

    def to_dict(self) -> dict:
        return {"type": "sphere", "name": self.name, "centre_mm": list(self.centre_mm), "radius_mm": self.radius_mm}


#: The XB3 (277 x 42 x 37 mm) at the default nominal mount, and its bracket from the flange, in tool0: what the
#: station's flange carries unless ``cell.carried`` says otherwise (and what the mock's arm carries).
DEFAULT_CARRIED = (Box("camera", (-136.0, 11.0, 58.0), (-94.0, 288.0, 100.0)),
                   Box("bracket", (-140.0, -45.0, 0.0), (45.0, 45.0, 58.0)))


def floor_height(volumes: Sequence[KeepOut]) -> float | None:
    """The highest :class:`Floor` among ``volumes`` (None when there is none)."""
    floors = [v.z_mm for v in volumes if isinstance(v, Floor)]
    return max(floors) if floors else None


def board_stand(board2base: ArrayLike, board: BoardGeometry, margin_mm: float, depth_mm: float, floor_z_mm: float | None = None,
                name: str = "board stand") -> list:
    """The board's stand as keep-out boxes, from the board's pose.

    The plate: the printed pattern (one square beyond the outer inner corners on every side) grown by
    ``margin_mm`` on every side and in front of the printed face, reaching ``depth_mm`` behind it
    (target +z, away from the camera), in the target frame. The leg: when a floor is given and the
    plate stands above it, an axis-aligned box in base under the plate's footprint down to the floor.

    Parameters
    ----------
    board2base : array-like, shape (4, 4)
        The board's target frame in base (measured or estimated).
    board : BoardGeometry
    margin_mm, depth_mm : float
    floor_z_mm : float, optional
        Height of the floor in base.

    Returns
    -------
    list of Box
    """
    frame = np.asarray(board2base, float)
    cols, rows = board.corners
    s = cast(float, board.square_mm)  # a stand is built for a board of known squares
    low = (-s - margin_mm, -s - margin_mm, -margin_mm)
    high = (cols * s + margin_mm, rows * s + margin_mm, depth_mm)
    plate = Box(name, low, high, tuple(tuple(float(v) for v in row) for row in frame))
    out = [plate]
    corners = plate.corners()
    bottom = corners[:, 2].min()
    if floor_z_mm is not None and bottom > floor_z_mm:
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        out.append(Box(f"{name} leg", (float(lo[0]), float(lo[1]), float(floor_z_mm)),
                       (float(hi[0]), float(hi[1]), float(bottom))))
    return out


@dataclass(frozen=True)
class CellModel:
    """The geometry of a cell, as the station config gives it (``cell`` section).

    Attributes
    ----------
    keep_out : tuple
        :class:`Box`, :class:`Cylinder` and :class:`Floor` volumes in base.
    carried : tuple
        :class:`Box` (in tool0) and :class:`Sphere` bodies the flange carries.
    stand_margin_mm : float or None
        The board's stand (:func:`board_stand`): its margin; None: the board has no stand to keep out of.
    stand_depth_mm : float
        How far the stand reaches behind the printed face.
    """

    keep_out: tuple = ()
    carried: tuple = ()
    stand_margin_mm: float | None = 50.0
    stand_depth_mm: float = 100.0

    def volumes(self, board2base: ArrayLike | None = None, board: BoardGeometry | None = None) -> list:
        """Every keep-out volume: the configured ones, and the board's stand when the board's pose is given."""
        out = list(self.keep_out)
        if board2base is not None and board is not None and self.stand_margin_mm is not None:
            out += board_stand(board2base, board, self.stand_margin_mm, self.stand_depth_mm, floor_height(self.keep_out))
        return out

    def world_zone_volumes(self, board2base: ArrayLike | None = None, board: BoardGeometry | None = None) -> list:
        """The volumes as the controller's world zones see them: floors as they are, boxes axis-aligned in
        base (a box of a frame of its own: its bounding box), cylinders as they are."""
        out = []
        for volume in self.volumes(board2base, board):
            if isinstance(volume, Box) and volume.box2parent is not None:
                zone = volume.world_zone()
                out.append(Box(volume.name, zone["min_mm"], zone["max_mm"]))
            else:
                out.append(volume)
        return out
