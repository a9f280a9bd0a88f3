"""Fit the IRB 1400's capsules to the public IRB 1410 link meshes (issue 41), and write them where they are used.

Reads ``link0.stl .. link6.stl`` of ``../shared/reference/irb1410-arte/`` (ARTE, LGPL-3.0; ASCII STL in
metres, mesh ``i`` in ARTE's DH frame ``i``), places them in the package's frames with every axis at 0
(``robot.arm_meshes``: mesh ``i`` by frame ``i`` of ``src/handeye/robot/robots/irb1400.yaml``'s own DH
table, which corrects ARTE's d1 and d6 (10 mm short); the base mesh lifted so its foot is at base z 0,
12 mm), and fits per link the capsules of :data:`PARTS` to the mesh's SURFACE (``robot.capsule_fit.
fit_surface_capsules``: the facets cut into sub-triangles with edges of at most :data:`SPACING_MM`, each
held whole by one capsule; k-means groups, then least total volume, none reaching much beyond its mesh's
box), each radius grown by :data:`MARGIN_MM` for the meshes' own uncertainty (about 10 mm): every point of
every facet, not only the vertices, is the margin deep (``surface.py`` measures it). About a minute.

The tube of the upper arm (mesh 4, turned by axis 4) is fitted on axis 4, so axis 4 turns its capsule into
itself, and cut where it is :data:`TUBE_CUT_MM` before the wrist centre: the part behind rides on link 3 and
is named ``link 3`` (what the camera is checked against: "camera against link 3"), the part in front rides
on link 4 (``link 4``, not checked against the camera, which works next to the wrist).

Writes (``--write``): the fitted ``link_bodies`` between the ``# fitted:`` markers of the robot file, the
placed vertices (``tests/calibration/data/irb1410_arte_vertices.csv``, 0.01 mm, with the licence note) and a
decimated set of surface samples (``irb1410_arte_surface.csv`` beside it: every sample less than
:data:`TIGHT_MM` beyond the margin deep, one per :data:`TIGHT_VOXEL_MM` cube, and one per
:data:`VOXEL_MM` cube of all the others), which the containment test
(``tests/calibration/test_arm_bodies.py``) reads in a clone without ``../shared``.
Without ``--write`` it prints the bodies.

Usage (from the repository root, in the project's venv):
    python benchmarks/arm_bodies/fit.py [--meshes ../shared/reference/irb1410-arte] [--write]
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import numpy as np

from handeye.robot.arm_meshes import place_link_meshes, read_ascii_stl, read_ascii_stl_faces, write_vertex_table
from handeye.robot.capsule_fit import Capsule, facet_grid, fit_surface_capsules, grown
from handeye.robot.kinematics import ROBOTS_DIR, load_robot

REPO = Path(__file__).resolve().parents[2]
MESHES = REPO.parent / "shared" / "reference" / "irb1410-arte"
ROBOT_FILE = ROBOTS_DIR / "irb1400.yaml"
VERTICES = REPO / "tests" / "calibration" / "data" / "irb1410_arte_vertices.csv"
SURFACE = VERTICES.with_name("irb1410_arte_surface.csv")
LICENCE = VERTICES.with_name("irb1410_arte_COPYING.LESSER.txt")
#: Added to every fitted radius: the meshes are good to about 10 mm (an educational model, not ABB's CAD).
MARGIN_MM = 10.0
#: The facets are cut into sub-triangles with edges at most this long (mm); each is held whole by one capsule.
SPACING_MM = 5.0
#: The surface fixture: samples less than this beyond the margin deep (the tight places) one per TIGHT_VOXEL_MM cube,
#: all others one per VOXEL_MM cube.
TIGHT_MM, TIGHT_VOXEL_MM, VOXEL_MM = 3.0, 8.0, 30.0
#: The tube's capsule is cut this far before the wrist centre (link 3 behind, link 4 in front).
TUBE_CUT_MM = 200.0
#: Per mesh: (name, capsules, the axis (1-based) the capsules lie on or None, slack mm). The slack keeps a
#: capsule (by a cost on its volume) from reaching much farther than that beyond its mesh's box before the margin
#: is added: the least volume alone sends a capsule of link 1 down to the floor, where link 1 is not (its lowest
#: vertex is 129 mm up); 5 capsules and 30 mm keep them 62 mm above it. Five capsules for the base and link 1
#: (flat boxes and side motors: one capsule would have to be as thick as the part is wide), three for the lower
#: arm's long plates, four for the axis-3 housing.
PARTS = [("base", 5, None, 60.0), ("link 1", 5, None, 30.0), ("link 2", 3, None, 60.0), ("link 3", 4, None, 60.0),
         ("link 4", 1, 4, 60.0), ("link 5", 1, None, 60.0), ("link 6", 1, 6, 60.0)]
BEGIN, END = "# fitted: begin", "# fitted: end"
SOURCE = ("ARTE (A Robotics Toolbox for Education, A. Gil, Universidad Miguel Hernandez), repository 4rtur1t0/ARTE, "
          "robots/ABB/IRB1410/right/link0-6.stl at a8df0b121e3b6e9c09b52a870ce29a54b0e971ea, LGPL-3.0")


def placed_meshes(robot, folder: Path) -> list:
    """The seven meshes' vertices in base with every axis at 0, mm."""
    return place_link_meshes(robot, [read_ascii_stl(folder / f"link{i}.stl", scale=1000.0) for i in range(len(PARTS))])


def placed_facets(robot, folder: Path) -> list:
    """The seven meshes' facets ``[(m_i, 3, 3)]`` in base with every axis at 0, mm."""
    meshes = placed_meshes(robot, folder)
    return [meshes[i][read_ascii_stl_faces(folder / f"link{i}.stl")] for i in range(len(PARTS))]


def fitted_bodies(robot, facets) -> list:
    """``[(name, part, start (3,), end (3,), radius)]`` of every link's capsules (the tube cut in two)."""
    points = robot.chain_points(np.zeros(robot.dof))
    out = []
    for link, ((name, count, axis, slack), faces) in enumerate(zip(PARTS, facets)):
        line = None if axis is None else (points[axis - 1], robot.axes[axis - 1])
        capsules, grid = fit_surface_capsules(faces, count, line=line, slack_mm=slack, spacing_mm=SPACING_MM)
        for capsule, members in capsules:
            capsule = grown(capsule, grid[members], MARGIN_MM)
            if link == 4:
                out += _cut_tube(robot, capsule)
            else:
                out.append((name, link, capsule.start, capsule.end, capsule.radius))
    return out


def _voxel_pick(points, size: float) -> np.ndarray:
    """One point (the first) of ``points`` ``(n, 3)`` per cube of side ``size`` mm, ``(k, 3)``."""
    _, first = np.unique(np.floor(points / size).astype(np.int64), axis=0, return_index=True)
    return points[np.sort(first)]


def surface_fixture(facets, bodies) -> list:
    """Per link, the decimated surface samples of the fixture ``[(n_i, 3)]`` (see the module's docstring)."""
    out = []
    for link, faces in enumerate(facets):
        grid, _, _ = facet_grid(faces, SPACING_MM)
        mine = [Capsule(np.asarray(a, float), np.asarray(b, float), r) for _, part, a, b, r in bodies
                if part == link or (link == 4 and part == 3 and a[1] == 0 and a[2] == b[2])]
        depth = np.max([c.radius - c.distances(grid) for c in mine], axis=0)
        tight = depth < MARGIN_MM + TIGHT_MM
        out.append(np.vstack([_voxel_pick(grid[tight], TIGHT_VOXEL_MM), _voxel_pick(grid[~tight], VOXEL_MM)]))
    return out


def _cut_tube(robot, capsule) -> list:
    """The tube's capsule (on axis 4) in two at :data:`TUBE_CUT_MM` before the wrist centre."""
    wrist = robot.chain_points(np.zeros(robot.dof))[4]
    cut = np.round(wrist - TUBE_CUT_MM * robot.axes[3])
    return [("link 3", 3, capsule.start, cut, capsule.radius), ("link 4", 4, cut, capsule.end, capsule.radius)]


def yaml_block(bodies) -> str:
    """The robot file's ``link_bodies`` rows, one flow mapping a line."""
    def xyz(v):
        return "[" + ", ".join(f"{x:g}" for x in np.asarray(v, float) + 0.0) + "]"
    return "\n".join(f"  - {{name: {name}, link: {part}, from_mm: {xyz(a)}, to_mm: {xyz(b)}, radius_mm: {r:g}}}"
                     for name, part, a, b, r in bodies)


def write_robot_file(bodies) -> None:
    """Replace the rows between the robot file's ``# fitted:`` markers."""
    text = ROBOT_FILE.read_text(encoding="utf-8")
    head, rest = text.split(BEGIN + "\n", 1)
    _, tail = rest.split(END, 1)
    ROBOT_FILE.write_text(head + BEGIN + "\n" + yaml_block(bodies) + "\n" + END + tail, encoding="utf-8")


def write_fixtures(meshes, surface, folder: Path) -> None:
    """The placed vertices and surface samples (the test's fixtures) and the licence beside them."""
    licence = "Licence: GNU LGPL-3.0 (irb1410_arte_COPYING.LESSER.txt beside this file)."
    made = "Made by: python benchmarks/arm_bodies/fit.py --write (issue 41)."
    write_vertex_table(VERTICES, meshes, [
        "Vertices of the IRB 1410 link meshes, placed in the IRB 1400 model's base frame with every axis at 0, mm.",
        f"Derived from {SOURCE}.", licence + " Each vertex once; link = mesh number.", made])
    write_vertex_table(SURFACE, surface, [
        f"Points on the facets of the IRB 1410 link meshes (a grid of at most {SPACING_MM:g} mm on every facet), placed",
        "in the IRB 1400 model's base frame with every axis at 0, mm; decimated: the samples less than "
        f"{MARGIN_MM + TIGHT_MM:g} mm inside the fitted",
        f"capsules one per {TIGHT_VOXEL_MM:g} mm cube, the others one per {VOXEL_MM:g} mm cube.",
        f"Derived from {SOURCE}.", licence + " link = mesh number.", made])
    shutil.copyfile(folder / "COPYING.LESSER.txt", LICENCE)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=Path, default=MESHES, help="folder of link0.stl .. link6.stl")
    parser.add_argument("--write", action="store_true", help="write the robot file's rows and the vertex fixture")
    args = parser.parse_args(argv)
    if not (args.meshes / "link0.stl").is_file():
        print(f"fit.py: error: no link0.stl in {args.meshes}; give --meshes FOLDER", file=sys.stderr)
        return 1
    robot = load_robot("IRB1400")
    facets = placed_facets(robot, args.meshes)
    bodies = fitted_bodies(robot, facets)
    print(yaml_block(bodies))
    if args.write:
        write_robot_file(bodies)
        write_fixtures(placed_meshes(robot, args.meshes), surface_fixture(facets, bodies), args.meshes)
        print(f"wrote {ROBOT_FILE.relative_to(REPO)}, {VERTICES.relative_to(REPO)} and {SURFACE.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
