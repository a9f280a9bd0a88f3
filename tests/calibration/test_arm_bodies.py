"""The robot file's capsules hold the arm (issue 41): every vertex of the IRB 1410 link meshes, moved with its
link, lies inside that link's capsules at 2,000 random postures over the joint ranges, with the stated margin.

The meshes (``../shared/reference/irb1410-arte``, ARTE, LGPL-3.0) are placed in the package's frames by
``robot.arm_meshes``; the placed vertices are kept in ``data/irb1410_arte_vertices.csv`` (derived,
LGPL-3.0: ``data/irb1410_arte_COPYING.LESSER.txt``) so the test runs in a clone without ``../shared``; beside
``../shared`` the copy is first checked against the meshes. The capsules were fitted by
``python benchmarks/arm_bodies/fit.py --write``; ``robot.body_cover`` moves each vertex by its DH frame
(the serial angles through the parallelogram's coupling) and the capsules by the checks' own chain.
"""

from pathlib import Path

import numpy as np
import pytest

from handeye.robot.arm_meshes import place_link_meshes, read_ascii_stl, read_vertex_table
from handeye.robot.body_cover import link_capsules, outside_counts
from handeye.robot.kinematics import ROBOTS_DIR, FrameBody, RobotModel, load_robot

from helpers import SHARED

FIXTURE = Path(__file__).with_name("data") / "irb1410_arte_vertices.csv"
MESHES = SHARED / "reference" / "irb1410-arte"
POSTURES = 2000
#: The margin the robot file states: every vertex at least this deep inside its capsules.
MARGIN_MM = 10.0


@pytest.fixture(scope="module")
def robot():
    return load_robot("IRB1400")


@pytest.fixture(scope="module")
def vertices():
    return read_vertex_table(FIXTURE)


def _postures(robot, count=POSTURES, seed=41) -> np.ndarray:
    """``(count, 6)`` uniform over the joint limits, the four corners of axes 2 and 3 (the parallelogram's
    extremes: the serial angle of axis 3 is axis 3 - axis 2) among them."""
    low, high = robot.joint_limits_deg.T
    joints = np.random.default_rng(seed).uniform(low, high, size=(count, robot.dof))
    for row, (a2, a3) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1)]):
        joints[row, 1], joints[row, 2] = robot.joint_limits_deg[1, a2], robot.joint_limits_deg[2, a3]
    return joints


def test_the_fixture_is_the_meshes_placed(robot, vertices):
    if not (MESHES / "link0.stl").is_file():
        pytest.skip("../shared/reference/irb1410-arte is only beside a development checkout; the fixture is used")
    placed = place_link_meshes(robot, [read_ascii_stl(MESHES / f"link{i}.stl", 1000.0) for i in range(7)])
    assert [len(p) for p in placed] == [len(v) for v in vertices]
    for mesh, copy in zip(placed, vertices):
        assert np.abs(mesh - copy).max() <= 0.005 + 1e-9  # written at 0.01 mm


def test_the_placed_meshes_stand_where_the_readme_says(vertices):
    """At all axes 0: the base's rear cable box at x -398, its foot at z 0; link 1's motors at |y| 341; the
    lower arm 160 mm below axis 2 (z 475); the flange's face (tool0, x 955) within the flange mesh."""
    base, link1, link2, flange = vertices[0], vertices[1], vertices[2], vertices[6]
    assert base[:, 0].min() == pytest.approx(-398.0) and base[:, 2].min() == 0.0
    assert np.abs(link1[:, 1]).max() == pytest.approx(341.0)
    assert link2[:, 2].min() == pytest.approx(475.0 - 160.4, abs=0.5)
    assert flange[:, 0].min() < 955.0 < flange[:, 0].max()


def test_every_vertex_stays_inside_its_links_capsules_with_the_margin(robot, vertices):
    counts = outside_counts(robot, vertices, _postures(robot))
    assert [c for c, _ in counts] == [0] * 7, counts
    worst = max(w for _, w in counts)
    assert worst <= -MARGIN_MM + 1e-6, f"the tightest vertex is {-worst:.1f} mm inside, the file says {MARGIN_MM}"


def test_the_tube_on_axis_4_counts_for_link_4_and_nothing_off_its_axis_does(robot):
    names = [b.name for b in robot.bodies] + [b.name for b in robot.link_bodies]
    members = link_capsules(robot)
    tube = [names[c] for c in members[4]]
    assert "link 3" in tube and "link 4" in tube  # the tube's rear part rides on link 3, on axis 4
    assert all(names[c] in ("link 5", "link 6") for c in members[5] + members[6])  # nothing rides along axes 5, 6
    assert not any(names[c] in ("base", "link 1", "link 2") for c in members[3])


def _with(robot, bodies) -> RobotModel:
    return RobotModel.from_dh("IRB1400 test", robot.dh, [[3, 2, -1.0]], robot.joint_limits_deg, robot.max_speed_deg_s,
                              robot.bodies, bodies, ())


def test_the_check_tells_a_capsule_too_small_or_on_the_wrong_link(robot, vertices):
    """Not vacuous: link 1's capsules 15 mm thinner (more than the margin) leave vertices out; so does the
    tube's rear capsule put on link 2 (axis 3 would turn link 4 away from it)."""
    joints = _postures(robot, 300)
    thinner = [FrameBody(b.name, b.link, b.start_mm, b.end_mm, b.radius_mm - 15.0 if b.link == 1 else b.radius_mm)
               for b in robot.link_bodies]
    assert outside_counts(_with(robot, thinner), vertices[:2], joints)[1][0] > 0
    moved = [FrameBody(b.name, 2 if b.link == 3 and b.start_mm[0] < 0 else b.link, b.start_mm, b.end_mm, b.radius_mm)
             for b in robot.link_bodies]  # the tube's rear capsule, from link 3 to link 2
    assert outside_counts(_with(robot, moved), vertices[:5], joints[:20])[4][0] > 0


def test_the_robot_file_states_the_source_the_command_and_the_margin():
    text = (ROBOTS_DIR / "irb1400.yaml").read_text(encoding="utf-8")
    assert "python benchmarks/arm_bodies/fit.py --write" in text and "4rtur1t0/ARTE" in text and "LGPL-3.0" in text
    assert f"MARGIN of {MARGIN_MM:g} mm" in text
