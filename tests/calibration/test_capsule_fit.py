"""The capsule fit (``robot.capsule_fit``) and the mesh reader (``robot.arm_meshes``) of issue 41."""

import numpy as np
import pytest

from handeye.robot.arm_meshes import read_ascii_stl, read_vertex_table, write_vertex_table
from handeye.robot.capsule_fit import capsule_volume, fit_capsule, fit_capsules, grown


def _cylinder(centre, axis, radius, length, count=400, seed=0) -> np.ndarray:
    """Points on a cylinder's surface and end faces, ``(count, 3)``."""
    rng = np.random.default_rng(seed)
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    angle = rng.uniform(0, 2 * np.pi, count)
    s = rng.uniform(-length / 2, length / 2, count)
    rho = np.where(rng.random(count) < 0.8, radius, radius * np.sqrt(rng.random(count)))
    s = np.where(rho < radius, np.sign(s) * length / 2, s)  # the inner points on the end faces
    return np.asarray(centre) + s[:, None] * axis + rho[:, None] * (np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * v)


def test_one_capsule_holds_a_cylinder_tightly_along_its_axis():
    points = _cylinder((100, -50, 300), (1, 2, 0.5), 40.0, 400.0)
    capsule = fit_capsule(points)
    assert capsule.contains(points).all()
    direction = (capsule.end - capsule.start) / np.linalg.norm(capsule.end - capsule.start)
    assert abs(direction @ (np.array([1, 2, 0.5]) / np.linalg.norm([1, 2, 0.5]))) > 0.99
    assert 40.0 <= capsule.radius <= 60.0
    assert capsule_volume(np.linalg.norm(capsule.end - capsule.start), capsule.radius) < 1.6 * np.pi * 40 ** 2 * 400


def test_two_parts_get_two_capsules_and_the_same_points_the_same_capsules():
    points = np.vstack([_cylinder((0, 0, 0), (1, 0, 0), 30, 300, seed=1), _cylinder((0, 400, 200), (0, 0, 1), 50, 200, seed=2)])
    first, again = fit_capsules(points, 2), fit_capsules(points, 2)
    assert sorted(len(m) for _, m in first) == [400, 400]
    assert all(c.contains(points[m]).all() for c, m in first)
    assert all(np.array_equal(a.start, b.start) and a.radius == b.radius for (a, _), (b, _) in zip(first, again))


def test_a_capsule_on_a_line_keeps_its_axis_on_it():
    points = _cylinder((0, 0, 1195), (1, 0, 0), 90, 800, seed=3)
    capsule = fit_capsule(points, line=((0, 0, 1195), (1, 0, 0)))
    assert np.allclose(capsule.start[1:], [0, 1195]) and np.allclose(capsule.end[1:], [0, 1195])
    assert capsule.contains(points).all()


def test_grown_rounds_the_ends_and_keeps_every_point_the_margin_inside():
    points = _cylinder((10.3, 20.7, 30.1), (0, 1, 1), 25.0, 150.0, seed=4)
    capsule = grown(fit_capsule(points), points, 10.0)
    assert np.array_equal(capsule.start, np.round(capsule.start)) and capsule.radius == int(capsule.radius)
    assert (capsule.distances(points) <= capsule.radius - 10.0 + 1e-9).all()


def test_the_slack_measures_how_far_a_capsule_reaches_beyond_the_box_and_keeps_every_point_inside():
    from handeye.robot.capsule_fit import Capsule, _overshoot

    capsule = Capsule(np.array([0.0, 0.0, 0.0]), np.array([100.0, 0.0, 0.0]), 20.0)
    box = (np.array([-10.0, -20.0, -30.0]), np.array([100.0, 25.0, 20.0]))
    assert _overshoot(capsule, box) == pytest.approx(10.0 + 20.0)  # 10 mm behind x -10, 20 mm beyond x 100
    assert _overshoot(capsule, None) == 0.0
    points = np.vstack([_cylinder((0, 0, 0), (1, 0, 0), 20, 300, seed=5), _cylinder((150, 0, 150), (0, 0, 1), 20, 300, seed=6)])
    for c, members in fit_capsules(points, 2, slack_mm=10.0):
        assert c.contains(points[members]).all()


def test_the_stl_reader_takes_ascii_and_refuses_binary(tmp_path):
    text = ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\nvertex 0 0.1 0\nendloop\nendfacet\n"
            "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\nvertex 0 0 0.2\nendloop\nendfacet\nendsolid t\n")
    (tmp_path / "a.stl").write_text(text)
    assert np.allclose(read_ascii_stl(tmp_path / "a.stl", 1000.0), [[0, 0, 0], [0, 0, 200], [0, 100, 0], [100, 0, 0]])
    (tmp_path / "b.stl").write_bytes(b"\x00" * 84)
    with pytest.raises(ValueError, match="only ASCII STL"):
        read_ascii_stl(tmp_path / "b.stl")


def test_the_vertex_table_reads_back_what_was_written(tmp_path):
    points = [np.array([[1.004, 2.0, 3.0]]), np.array([[4.0, 5.0, 6.0], [-7.5, 8.25, 9.0]])]
    write_vertex_table(tmp_path / "v.csv", points, ["source: a test", "licence: none"])
    back = read_vertex_table(tmp_path / "v.csv")
    assert [len(b) for b in back] == [1, 2] and np.allclose(back[1], points[1]) and abs(back[0][0, 0] - 1.0) < 0.006


def test_a_facet_between_two_capsules_is_measured_between_its_corners():
    """Two spheres of radius 20 at x = 0 and x = 100, a thin facet from one to the other at y = 15: its
    corners are 5 mm inside, its middle (x 50, 50 mm from both centres) 30 mm outside; cover_facets grows
    the radii until the whole facet is the margin deep."""
    from handeye.robot.capsule_fit import Capsule, cover_facets, facet_depths, surface_gap

    spheres = [Capsule(np.zeros(3), np.zeros(3), 20.0), Capsule(np.array([100.0, 0, 0]), np.array([100.0, 0, 0]), 20.0)]
    facet = np.array([[[0.0, 15.0, 0.0], [100.0, 15.0, 0.0], [0.0, 15.0, 0.1]]])
    assert facet_depths(spheres[:1], facet[:, [0, 2, 2]], 5.0)[0] == pytest.approx(5.0, abs=0.01)  # corners only
    depth = facet_depths(spheres, facet, 5.0)[0]
    true = 20.0 - np.hypot(50.0, 15.0)  # the facet's middle
    assert true - surface_gap(5.0) - 0.5 <= depth <= true + 0.5
    grown_ = cover_facets(spheres, facet, 10.0, 5.0)
    assert facet_depths(grown_, facet, 5.0)[0] >= 10.0
    assert all(g.radius >= s.radius for g, s in zip(grown_, spheres))


def test_the_facet_grid_cuts_every_facet_into_similar_pieces_that_cover_it():
    from handeye.robot.capsule_fit import facet_grid

    facet = np.array([[[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 30.0, 0.0]]])
    points, triangles, owners = facet_grid(facet, 5.0)
    cells = points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(cells[:, 1] - cells[:, 0], cells[:, 2] - cells[:, 0]), axis=1)
    assert len(triangles) == 21 * 21 and (owners == 0).all()  # the longest edge 104.4 mm: 21 steps, 441 pieces
    assert area.sum() == pytest.approx(1500.0) and np.allclose(area, 1500.0 / 441)  # they tile it
    assert np.max(np.linalg.norm(cells - np.roll(cells, 1, axis=1), axis=2)) <= 5.0 + 1e-9


def test_the_surface_fit_holds_a_long_facet_that_the_vertex_fit_leaves():
    """An L of two thin plates, 400 mm each: two capsules on its vertices alone may cut the corner between
    them; the surface fit holds every facet the margin deep (facet_depths), and again gives the same."""
    from handeye.robot.capsule_fit import facet_depths, fit_surface_capsules

    def plate(a, b, c, d):
        return [[a, b, c], [a, c, d]]

    facets = np.array(plate([0, 0, 0], [400, 0, 0], [400, 0, 20], [0, 0, 20]) + plate([0, 0, 0], [0, 400, 0], [0, 400, 20], [0, 0, 20])
                      + plate([400, 0, 0], [0, 400, 0], [0, 400, 20], [400, 0, 20]), float)  # a thin triangle's walls
    capsules, grid = fit_surface_capsules(facets, 2, spacing_mm=5.0)
    held = [grown(c, grid[m], 10.0) for c, m in capsules]
    assert facet_depths(held, facets, 5.0).min() >= 10.0 - 1e-9
    vertex = [grown(c, facets.reshape(-1, 3)[m], 10.0) for c, m in fit_capsules(facets.reshape(-1, 3), 2)]
    assert facet_depths(vertex, facets, 5.0).min() < 0.0  # the corners alone leave a wall's middle out
    again, _ = fit_surface_capsules(facets, 2, spacing_mm=5.0)
    assert all(np.array_equal(a.start, b.start) and a.radius == b.radius for (a, _), (b, _) in zip(capsules, again))
