"""How deep the meshes' facets, not only their vertices, lie in the robot file's capsules (issue 41).

The fit (``fit.py``) holds every vertex :data:`fit.MARGIN_MM` deep; a facet whose corners lie in different
capsules of a link can leave their union between its corners (the lower arm's sides run 800 mm between two
capsules). Prints per link the least depth of its facets at all axes 0 (``capsule_fit.facet_depths``, facets
sampled every 5 mm, a lower bound) and how many facets are less than the margin deep or outside. The bodies
move rigidly with their links, so the figures hold at every posture.

Then the capsules' conservatism for the base and links 1-3: the volume of the union of the link's own capsules
(link 3's without the tube's, which holds link 4 on axis 4) over the volume of its mesh's convex hull (the union
by 400,000 seeded random points in its box), and how far the capsules reach beyond the mesh's box.

Usage (from the repository root, in the project's venv):
    python benchmarks/arm_bodies/surface.py [--meshes ../shared/reference/irb1410-arte]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fit  # noqa: E402

from handeye.robot.arm_meshes import read_ascii_stl_faces  # noqa: E402
from handeye.robot.body_cover import link_capsules  # noqa: E402
from handeye.robot.capsule_fit import Capsule, facet_depths  # noqa: E402
from handeye.robot.clearance import arm_capsules  # noqa: E402
from handeye.robot.kinematics import load_robot  # noqa: E402


def conservatism(held, vertices, seed: int = 0, count: int = 400_000) -> tuple[float, float]:
    """``(union volume / the vertices' convex hull's volume, mm the capsules reach beyond the vertices' box)``."""
    low = np.min([np.minimum(c.start, c.end) - c.radius for c in held], axis=0)
    high = np.max([np.maximum(c.start, c.end) + c.radius for c in held], axis=0)
    points = np.random.default_rng(seed).uniform(low, high, (count, 3))
    union = np.mean(np.any([c.contains(points) for c in held], axis=0)) * np.prod(high - low)
    beyond = max(float(np.max(vertices.min(axis=0) - low)), float(np.max(high - vertices.max(axis=0))))
    return float(union / ConvexHull(vertices).volume), beyond


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=Path, default=fit.MESHES, help="folder of link0.stl .. link6.stl")
    args = parser.parse_args(argv)
    if not (args.meshes / "link0.stl").is_file():
        print(f"surface.py: error: no link0.stl in {args.meshes}; give --meshes FOLDER", file=sys.stderr)
        return 1
    robot = load_robot("IRB1400")
    meshes = fit.placed_meshes(robot, args.meshes)
    faces = [read_ascii_stl_faces(args.meshes / f"link{i}.stl") for i in range(len(meshes))]
    pivots, capsules = robot.home_pivots(), arm_capsules(robot)
    for link, rows in enumerate(link_capsules(robot)):
        held = [Capsule(pivots[capsules[c][1]] + capsules[c][2], pivots[capsules[c][1]] + capsules[c][3],
                        capsules[c][4]) for c in rows]
        depth = facet_depths(held, meshes[link][faces[link]], 5.0)
        print(f"mesh {link}: {len(depth)} facets, least depth {depth.min():.1f} mm, "
              f"{int(np.sum(depth < fit.MARGIN_MM))} under the {fit.MARGIN_MM:g} mm margin, {int(np.sum(depth < 0))} "
              f"possibly outside")
    members = link_capsules(robot)
    for link in range(4):
        own = [c for c in members[link] if capsules[c][1] == link and c not in members[link + 1]]
        held = [Capsule(pivots[link] + capsules[c][2], pivots[link] + capsules[c][3], capsules[c][4]) for c in own]
        ratio, beyond = conservatism(held, meshes[link])
        print(f"link {link}: {len(held)} capsules, {ratio:.2f} times its mesh's hull, up to {beyond:.0f} mm beyond its box")
    return 0


if __name__ == "__main__":
    sys.exit(main())
