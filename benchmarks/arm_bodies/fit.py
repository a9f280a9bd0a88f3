"""Fit the IRB 1400's capsules to the public IRB 1410 link meshes (issue 41), and write them where they are used.

Reads ``link0.stl .. link6.stl`` of ``../shared/reference/irb1410-arte/`` (ARTE, LGPL-3.0; ASCII STL in
metres, mesh ``i`` in ARTE's DH frame ``i``), places them in the package's frames with every axis at 0
(``robot.arm_meshes``: mesh ``i`` by frame ``i`` of ``src/handeye/robot/robots/irb1400.yaml``'s own DH
table, which corrects ARTE's d1 and d6 (10 mm short); the base mesh lifted so its foot is at base z 0,
12 mm), and fits per link the capsules of :data:`PARTS` (``robot.capsule_fit``: least total volume,
every vertex inside, none reaching much beyond its mesh's box), each radius grown by :data:`MARGIN_MM` for the meshes' own uncertainty (about 10 mm).

The tube of the upper arm (mesh 4, turned by axis 4) is fitted on axis 4, so axis 4 turns its capsule into
itself, and cut where it is :data:`TUBE_CUT_MM` before the wrist centre: the part behind rides on link 3 and
is named ``link 3`` (what the camera is checked against: "camera against link 3"), the part in front rides
on link 4 (``link 4``, not checked against the camera, which works next to the wrist).

Writes (``--write``): the fitted ``link_bodies`` between the ``# fitted:`` markers of the robot file, and the
placed vertices (``tests/calibration/data/irb1410_arte_vertices.csv``, 0.01 mm, with the licence note),
which the containment test (``tests/calibration/test_arm_bodies.py``) reads in a clone without ``../shared``.
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

from handeye.robot.arm_meshes import place_link_meshes, read_ascii_stl, write_vertex_table
from handeye.robot.capsule_fit import fit_capsules, grown
from handeye.robot.kinematics import ROBOTS_DIR, load_robot

REPO = Path(__file__).resolve().parents[2]
MESHES = REPO.parent / "shared" / "reference" / "irb1410-arte"
ROBOT_FILE = ROBOTS_DIR / "irb1400.yaml"
VERTICES = REPO / "tests" / "calibration" / "data" / "irb1410_arte_vertices.csv"
LICENCE = VERTICES.with_name("irb1410_arte_COPYING.LESSER.txt")
#: Added to every fitted radius: the meshes are good to about 10 mm (an educational model, not ABB's CAD).
MARGIN_MM = 10.0
#: The tube's capsule is cut this far before the wrist centre (link 3 behind, link 4 in front).
TUBE_CUT_MM = 200.0
#: Per mesh: (name, capsules, the axis (1-based) the capsules lie on or None, slack mm). The slack keeps a
#: capsule (by a cost on its volume) from reaching much farther than that beyond its mesh's box before the margin
#: is added: the least volume alone sends a capsule of link 1 down to the floor (60 mm: 18 mm above it, as the
#: clearance check's spheres see it), where link 1 is not (its lowest vertex is 129 mm up); 4 capsules and 30 mm
#: keep them 63 mm above it.
PARTS = [("base", 3, None, 60.0), ("link 1", 4, None, 30.0), ("link 2", 2, None, 60.0), ("link 3", 2, None, 60.0),
         ("link 4", 1, 4, 60.0), ("link 5", 1, None, 60.0), ("link 6", 1, 6, 60.0)]
BEGIN, END = "# fitted: begin", "# fitted: end"
SOURCE = ("ARTE (A Robotics Toolbox for Education, A. Gil, Universidad Miguel Hernandez), repository 4rtur1t0/ARTE, "
          "robots/ABB/IRB1410/right/link0-6.stl at a8df0b121e3b6e9c09b52a870ce29a54b0e971ea, LGPL-3.0")


def placed_meshes(robot, folder: Path) -> list:
    """The seven meshes' vertices in base with every axis at 0, mm."""
    return place_link_meshes(robot, [read_ascii_stl(folder / f"link{i}.stl", scale=1000.0) for i in range(len(PARTS))])


def fitted_bodies(robot, meshes) -> list:
    """``[(name, part, start (3,), end (3,), radius)]`` of every link's capsules (the tube cut in two)."""
    points = robot.chain_points(np.zeros(robot.dof))
    out = []
    for link, ((name, count, axis, slack), vertices) in enumerate(zip(PARTS, meshes)):
        line = None if axis is None else (points[axis - 1], robot.axes[axis - 1])
        for capsule, members in fit_capsules(vertices, count, line=line, slack_mm=slack):
            capsule = grown(capsule, vertices[members], MARGIN_MM)
            if link == 4:
                out += _cut_tube(robot, capsule)
            else:
                out.append((name, link, capsule.start, capsule.end, capsule.radius))
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


def write_vertices(meshes, folder: Path) -> None:
    """The placed vertices (the test's fixture) and the licence beside them."""
    write_vertex_table(VERTICES, meshes, [
        "Vertices of the IRB 1410 link meshes, placed in the IRB 1400 model's base frame with every axis at 0, mm.",
        f"Derived from {SOURCE}.",
        "Licence: GNU LGPL-3.0 (irb1410_arte_COPYING.LESSER.txt beside this file). Each vertex once; link = mesh number.",
        "Made by: python benchmarks/arm_bodies/fit.py --write (issue 41)."])
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
    meshes = placed_meshes(robot, args.meshes)
    bodies = fitted_bodies(robot, meshes)
    print(yaml_block(bodies))
    if args.write:
        write_robot_file(bodies)
        write_vertices(meshes, args.meshes)
        print(f"wrote {ROBOT_FILE.relative_to(REPO)} and {VERTICES.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
