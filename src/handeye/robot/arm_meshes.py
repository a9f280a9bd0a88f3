"""Link meshes of an arm placed in the robot model's frames: what the capsules of a robot file must contain.

A mesh is read from an ASCII STL file (facets of three ``vertex x y z`` lines; any unit, scaled on
reading). Mesh ``i`` is drawn in the standard-DH frame ``i`` of some model (link 0 in its base frame);
:func:`place_link_meshes` puts it in base with every axis at 0 by frame ``i`` of *our* DH table, so a
model whose table differs from ours (the ARTE IRB 1410: d1 and d6 10 mm short) is corrected link by
link, and lifts the base mesh so that its lowest point is on the mounting plane (base z 0).

A capsule fit must hold the mesh's surface, not only its vertices (a long facet between two capsules:
the lower arm's sides, 800 mm long, have vertices only at their ends): :func:`read_ascii_stl_facets`
gives the facets as rows of vertex indices; ``robot.capsule_fit.facet_depths`` measures them.

The vertex table (:func:`write_vertex_table`, :func:`read_vertex_table`) holds the placed points as
text: ``link,x_mm,y_mm,z_mm`` rows after ``#`` comment lines (source and licence).
"""

from __future__ import annotations

from collections.abc import Sequence
import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .kinematics import RobotModel, dh_transforms

__all__ = ["home_link_frames", "place_link_meshes", "read_ascii_stl", "read_ascii_stl_faces", "read_vertex_table",
           "write_vertex_table"]

_VERTEX = re.compile(r"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)\s*$", re.MULTILINE)


def read_ascii_stl(path: str | Path, scale: float = 1.0) -> np.ndarray:
    """The distinct vertices ``(n, 3)`` of an ASCII STL file, times ``scale`` (1000: metres to mm).

    Raises
    ------
    ValueError
        If the file holds no ``vertex`` line (a binary STL, or no mesh at all).
    """
    text = Path(path).read_text(encoding="ascii", errors="replace")
    rows = _VERTEX.findall(text)
    if not rows:
        raise ValueError(f"{path}: no 'vertex x y z' lines (only ASCII STL is read)")
    return np.unique(np.array(rows, float), axis=0) * float(scale)


def read_ascii_stl_faces(path: str | Path) -> np.ndarray:
    """The facets of an ASCII STL file as rows ``(m, 3)`` of indices into :func:`read_ascii_stl`'s vertices.

    Raises
    ------
    ValueError
        If the file holds no ``vertex`` line, or a number of them that is not a multiple of 3.
    """
    text = Path(path).read_text(encoding="ascii", errors="replace")
    rows = _VERTEX.findall(text)
    if not rows or len(rows) % 3:
        raise ValueError(f"{path}: expected facets of three 'vertex x y z' lines (only ASCII STL is read)")
    _, inverse = np.unique(np.array(rows, float), axis=0, return_inverse=True)
    return inverse.reshape(-1, 3)


def home_link_frames(robot: RobotModel) -> np.ndarray:
    """Standard-DH frames ``(k + 1, 4, 4)`` of the robot's table with every axis at 0 (frame 0 = base)."""
    links = dh_transforms(robot.dh, np.radians(robot.dh[:, 3]))
    frames = [np.eye(4)]
    for link in links:
        frames.append(frames[-1] @ link)
    return np.array(frames)


def place_link_meshes(robot: RobotModel, meshes: Sequence[ArrayLike]) -> list:
    """Meshes ``[(n_i, 3)]`` (mm, mesh ``i`` in DH frame ``i``) in base with every axis at 0, ``[(n_i, 3)]``.

    Mesh 0 (the base) is lifted so its lowest vertex lies at base z 0 (the robot's foot on the mounting
    plane); mesh ``i >= 1`` is put by frame ``i`` of ``robot``'s own table (:func:`home_link_frames`)."""
    frames = home_link_frames(robot)
    placed = []
    for i, points in enumerate(meshes):
        points = np.asarray(points, float)
        if i == 0:
            placed.append(points - [0.0, 0.0, points[:, 2].min()])
        else:
            placed.append(points @ frames[i, :3, :3].T + frames[i, :3, 3])
    return placed


def write_vertex_table(path: str | Path, points_by_link: Sequence[ArrayLike], header_lines: Sequence[str] = ()) -> None:
    """Write ``[(n_i, 3)]`` (mm) as ``link,x_mm,y_mm,z_mm`` rows at 0.01 mm, after ``# `` header lines."""
    lines = [f"# {line}".rstrip() for line in header_lines] + ["link,x_mm,y_mm,z_mm"]
    for link, points in enumerate(points_by_link):
        lines += [f"{link},{x:.2f},{y:.2f},{z:.2f}" for x, y, z in np.asarray(points, float)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def read_vertex_table(path: str | Path) -> list:
    """The points of :func:`write_vertex_table`, ``[(n_i, 3)]`` by link (links 0 .. the largest named)."""
    rows = [line for line in Path(path).read_text(encoding="utf-8").splitlines() if line and not line.startswith("#")]
    if not rows or rows[0] != "link,x_mm,y_mm,z_mm":
        raise ValueError(f"{path}: expected the header 'link,x_mm,y_mm,z_mm' after the comment lines")
    table = np.array([[float(v) for v in row.split(",")] for row in rows[1:]]).reshape(-1, 4)
    links = table[:, 0].astype(int)
    return [table[links == i, 1:] for i in range(int(links.max()) + 1 if len(links) else 0)]

