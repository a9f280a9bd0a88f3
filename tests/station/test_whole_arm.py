"""The whole arm in the cell and against itself (issue 21), checked by a geometry of the test's own.

The benchmark cell (a cabinet beside the base where the upper arm swings, a post the upper arm passes, the
board's stand, the floor): a 30-posture plan keeps every link and every carried body out of every volume
by the margin, at the postures and along every move; random postures where the camera meets the arm
(found by this file's geometry) are all refused by the planner's check and none is planned.

The test's geometry is written here and shares no code with the planner's: its own forward kinematics
(standard DH matrices of the robot file's table, not the quaternion chain), its own capsules (the robot
file's numbers written again), dense samples instead of spheres, its own signed distances and
point-segment distances, and the carried boxes' faces sampled every 10 mm.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.station.cell.plan import CellCheck

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks" / "whole_arm"))
from bench_whole_arm import BOARD, CELL, plan_once  # noqa: E402  (the benchmark's own cell)
from helpers import joint_path  # noqa: E402

ROBOT = load_robot("IRB1400")
MARGIN, STEP = 30.0, 10.0  # the CellCheck defaults the benchmark plans with

# ---------------------------------------------------------------------------------------- own geometry
#: IRB 1400 standard DH (d, a, alpha deg, theta offset deg); the serial angle of axis 3 is a3 - a2.
DH = np.array([[475, 150, -90, 0], [0, 600, 0, -90], [0, 120, -90, 0], [720, 0, 90, 0], [0, 0, -90, 0], [85, 0, 0, 180]],
              float)
#: Capsules (name, part, start, end in base at home, radius): part 0 the base, i the link axis i turns (the
#: robot file's link_bodies, fitted to the meshes' surface in issue 41, then its wrist bodies between chain points).
CAPSULES = [
    ("base", 0, (62, -122, 94), (-195, -29, 94), 165.0),
    ("base", 0, (-233, -175, 103), (-122, -180, 43), 114.0),
    ("base", 0, (-298, -153, 77), (-324, 133, 97), 133.0),
    ("base", 0, (-217, 146, 95), (-3, 123, 71), 135.0),
    ("base", 0, (186, -26, 43), (66, 144, 60), 109.0),
    ("link 1", 1, (-96, 4, 228), (156, -5, 228), 166.0),
    ("link 1", 1, (3, 218, 310), (-93, 128, 388), 161.0),
    ("link 1", 1, (-5, -205, 318), (25, -172, 303), 169.0),
    ("link 1", 1, (124, 154, 415), (151, 147, 498), 157.0),
    ("link 1", 1, (147, -133, 466), (111, -128, 500), 163.0),
    ("link 2", 2, (206, -1, 410), (139, 3, 570), 126.0),
    ("link 2", 2, (135, 4, 592), (187, 1, 764), 122.0),
    ("link 2", 2, (181, 0, 852), (138, 0, 1067), 88.0),
    ("link 3", 3, (165, -93, 1109), (152, -80, 1262), 113.0),
    ("link 3", 3, (48, 46, 1061), (45, -40, 1061), 117.0),
    ("link 3", 3, (151, 25, 1238), (175, 74, 1108), 113.0),
    ("link 3", 3, (289, -8, 1185), (298, -117, 1174), 105.0),
    ("link 3", 3, (-106, 0, 1195), (670, 0, 1195), 110.0),  # the upper arm's tube, on axis 4
    ("link 4", 4, (670, 0, 1195), (824, 0, 1195), 110.0),
    ("link 5", 5, (898, 0, 1195), (870, 0, 1195), 61.0),
    ("link 6", 6, (955, 0, 1195), (955, 0, 1195), 36.0),
    ("link 4", 4, (150, 0, 1195), (870, 0, 1195), 70.0),
    ("link 5", 5, (870, 0, 1195), (870, 0, 1195), 75.0),
    ("link 6", 6, (870, 0, 1195), (955, 0, 1195), 45.0),
]
#: What the flange carries (tool0): the XB3 and its bracket, as the station's default cell.carried.
CARRIED = {"camera": ((-136.0, 11.0, 58.0), (-94.0, 288.0, 100.0)), "bracket": ((-140.0, -45.0, 0.0), (45.0, 45.0, 58.0))}
#: The robot file's self-collision pairs, written again.
LINK_PAIRS = [("link 4", "base"), ("link 4", "link 1"), ("link 5", "base"), ("link 5", "link 1"), ("link 5", "link 2"),
              ("link 6", "base"), ("link 6", "link 1"), ("link 6", "link 2"), ("link 3", "base")]
CAMERA_MEETS = ("base", "link 1", "link 2", "link 3")


def _dh(theta: np.ndarray, row) -> np.ndarray:
    d, a, alpha = row[0], row[1], np.radians(row[2])
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    out = np.zeros(theta.shape + (4, 4))
    out[..., 0, :] = np.stack([ct, -st * ca, st * sa, a * ct], -1)
    out[..., 1, :] = np.stack([st, ct * ca, -ct * sa, a * st], -1)
    out[..., 2, :] = np.broadcast_to([0.0, sa, ca, d], theta.shape + (4,))
    out[..., 3, 3] = 1.0
    return out


def frames(joints) -> np.ndarray:
    """``(n, 7, 4, 4)``: the base and the frame of each link (standard DH), controller angles in deg."""
    q = np.radians(np.atleast_2d(np.asarray(joints, float))).copy()
    q[:, 2] -= q[:, 1]
    out = [np.broadcast_to(np.eye(4), (len(q), 4, 4))]
    for i in range(6):
        out.append(out[-1] @ _dh(q[:, i] + np.radians(DH[i, 3]), DH[i]))
    return np.stack(out, axis=1)


HOME = frames(np.zeros(6))[0]


def capsule_axes(joints, spacing: float = 10.0) -> list:
    """``[(name, points (n, m, 3), radius)]``: each capsule's axis sampled at most ``spacing`` apart."""
    f = frames(joints)
    out = []
    for name, part, a, b, r in CAPSULES:
        moved = f[:, part] @ np.linalg.inv(HOME[part])
        a, b = np.asarray(a, float), np.asarray(b, float)
        t = np.linspace(0, 1, max(2, int(np.ceil(np.linalg.norm(b - a) / spacing)) + 1))[:, None]
        local = a + t * (b - a)
        out.append((name, np.einsum("nij,mj->nmi", moved[:, :3, :3], local) + moved[:, None, :3, 3], r))
    return out


def _faces(low, high, spacing: float = 10.0) -> np.ndarray:
    axes = [np.linspace(lo, hi, max(2, int(np.ceil((hi - lo) / spacing)) + 1)) for lo, hi in zip(low, high)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid[np.any(np.isclose(grid, low) | np.isclose(grid, high), axis=1)]


def carried_points(joints) -> dict:
    """``{name: (n, m, 3)}``: the carried boxes' faces in base."""
    tool = frames(joints)[:, 6]
    return {name: np.einsum("nij,mj->nmi", tool[:, :3, :3], _faces(*box)) + tool[:, None, :3, 3]
            for name, box in CARRIED.items()}


def _box_sdf(p, low, high):
    low, high = np.asarray(low, float), np.asarray(high, float)
    q = np.abs(p - (low + high) / 2) - (high - low) / 2
    return np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(axis=-1), 0)


def volumes_sdf(board2base) -> dict:
    """``{name: signed distance of points (..., 3)}`` of the benchmark cell, the stand built from the board here."""
    cols, rows = BOARD.corners
    s, m = BOARD.square_mm, CELL.stand_margin_mm
    inv = np.linalg.inv(board2base)

    def stand(p):
        return _box_sdf(p @ inv[:3, :3].T + inv[:3, 3], (-s - m, -s - m, -m), (cols * s + m, rows * s + m,
                                                                                CELL.stand_depth_mm))

    def post(p):
        radial = np.linalg.norm(p[..., :2] - [380.0, -380.0], axis=-1) - 50.0
        axial = np.maximum(0.0 - p[..., 2], p[..., 2] - 1400.0)
        return np.hypot(np.maximum(radial, 0), np.maximum(axial, 0)) + np.minimum(np.maximum(radial, axial), 0)

    return {"floor": lambda p: p[..., 2], "cabinet beside the base": lambda p: _box_sdf(p, (-700, -900, 0), (-100, -420, 1600)),
            "post": post, "board stand": stand}


def cell_gap(joints, board2base) -> np.ndarray:
    """Least distance ``(n,)`` of any moving link or carried body from any volume."""
    sdf = volumes_sdf(board2base)
    parts = [(points, r) for name, points, r in capsule_axes(joints) if name != "base"]
    parts += [(points, 0.0) for points in carried_points(joints).values()]
    return np.min([[(f(points).min(axis=1) - r) for points, r in parts] for f in sdf.values()], axis=(0, 1))


def _point_segment(p, a, b):
    d = b - a
    t = np.clip(np.sum((p - a) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-12), 0, 1)
    return np.linalg.norm(p - a - t[..., None] * d, axis=-1)


def self_gaps(joints) -> dict:
    """``{(a, b): (n,)}``: the carried bodies against the arm, the robot file's link pairs (dense samples)."""
    axes = capsule_axes(joints)
    carried = carried_points(joints)
    out = {}
    for body, points in carried.items():
        for name, axis, r in axes:
            if name in CAMERA_MEETS:
                ends = axis[:, [0, -1]]
                gap = _point_segment(points, ends[:, None, 0], ends[:, None, 1]).min(axis=1) - r
                out[body, name] = np.minimum(out.get((body, name), np.inf), gap)
    for a, b in LINK_PAIRS:
        for name_a, pa, ra in axes:
            for name_b, pb, rb in axes:
                if (name_a, name_b) == (a, b):
                    gap = np.linalg.norm(pa[:, :, None] - pb[:, None], axis=-1).min(axis=(1, 2)) - ra - rb
                    out[a, b] = np.minimum(out.get((a, b), np.inf), gap)
    return out



# ---------------------------------------------------------------------------------------- the tests
@pytest.fixture(scope="module")
def plan():
    return plan_once(30, 0)[-1]


def test_the_own_kinematics_agree_with_the_robot_model():
    joints = np.random.default_rng(3).uniform(ROBOT.joint_limits_deg[:, 0], ROBOT.joint_limits_deg[:, 1], (50, 6))
    assert np.allclose(frames(joints)[:, 6], ROBOT.forward_transform(joints), atol=1e-6)


def test_the_tube_in_front_of_the_elbow_is_fixed_in_link_3():
    """The tube's capsule lies on axis 4 and is round about it: carried by link 4 (turned by axis 4) or by
    link 3, its axis has the same ends at every posture, whatever axis 4's angle, so it is one body of link 3."""
    ends = np.array([(-106.0, 0.0, 1195.0, 1.0), (670.0, 0.0, 1195.0, 1.0)])
    joints = np.random.default_rng(4).uniform(ROBOT.joint_limits_deg[:, 0], ROBOT.joint_limits_deg[:, 1], (200, 6))
    f = frames(joints)
    on_link_3 = np.einsum("nij,mj->nmi", f[:, 3] @ np.linalg.inv(HOME[3]), ends)
    for q4 in (-150.0, -60.0, 0.0, 45.0, 150.0):
        turned = joints.copy()
        turned[:, 3] = q4
        on_link_4 = np.einsum("nij,mj->nmi", frames(turned)[:, 4] @ np.linalg.inv(HOME[4]), ends)
        assert np.allclose(on_link_4, on_link_3, atol=1e-9)


def test_the_benchmark_plan_keeps_every_body_clear_of_the_cell_and_of_the_arm(plan):
    assert len(plan.joints_deg) == 30
    assert any("cabinet beside the base" in line for line in plan.score.rejections)  # the cell mattered
    assert any("'post'" in line for line in plan.score.rejections)
    at_postures = cell_gap(plan.joints_deg, plan.board2base)
    assert at_postures.min() >= MARGIN, at_postures.min()
    assert min(g.min() for g in self_gaps(plan.joints_deg).values()) >= MARGIN
    path = joint_path(np.vstack([plan.start_joints_deg, plan.joints_deg]), 1.0)  # the start's move included
    along = cell_gap(path, plan.board2base)
    # between its samples the planner's check guarantees the margin less half a step
    assert along.min() >= MARGIN - STEP / 2, along.min()
    assert min(g.min() for g in self_gaps(path).values()) >= MARGIN - STEP / 2


def test_random_postures_where_the_camera_meets_the_arm_are_all_refused(plan):
    rng = np.random.default_rng(21)
    joints = rng.uniform(ROBOT.joint_limits_deg[:, 0], ROBOT.joint_limits_deg[:, 1], (1500, 6))
    gaps = self_gaps(joints)
    camera = np.min([gaps["camera", name] for name in CAMERA_MEETS], axis=0)
    meeting = joints[camera < MARGIN]
    # the test's own geometry finds them: 57 where the camera meets link 3 (the housing or the tube in front of
    # it), 71 where it meets the base, 155 in all (seed 21)
    assert np.sum(gaps["camera", "link 3"] < MARGIN) >= 20 and np.sum(gaps["camera", "base"] < MARGIN) >= 20
    guard = CellCheck(CELL).guard(ROBOT, plan.board2base, BOARD)  # the planner's check
    refused = [guard.posture_violation(q) for q in meeting]
    assert all(v is not None for v in refused)
    assert any(v.kind == "self" and v.body == "camera" for v in refused)
    planned = self_gaps(plan.joints_deg)
    assert np.min([planned["camera", name] for name in CAMERA_MEETS]) >= MARGIN  # none planned among them


@pytest.mark.parametrize("body", ["link 3", "base"])
def test_the_self_check_names_the_pair_the_test_geometry_finds_closest(body):
    """Where the camera meets link 3 (or the base), the planner's self-collision check alone refuses every
    posture and names the pair this file's geometry finds closest ("camera against link 3", "bracket
    against link 3", ...) wherever that pair is the closest by more than 10 mm."""
    rng = np.random.default_rng(21)
    joints = rng.uniform(ROBOT.joint_limits_deg[:, 0], ROBOT.joint_limits_deg[:, 1], (1500, 6))
    gaps = self_gaps(joints)
    meeting = np.flatnonzero(gaps["camera", body] < MARGIN)
    pairs = list(gaps)
    table = np.array([gaps[p][meeting] for p in pairs])  # (pairs, postures)
    order = np.sort(table, axis=0)
    guard = CellCheck(type(CELL)((), CELL.carried)).guard(ROBOT)  # the pairs alone
    found = [guard.posture_violation(q) for q in joints[meeting]]
    assert all(v is not None and v.kind == "self" for v in found)
    clear_first = order[1] - order[0] > 10.0
    named = [(v.body, v.volume) for v in found]
    closest = [pairs[k] for k in table.argmin(axis=0)]
    assert np.sum(clear_first) >= 15
    assert all(n == c for n, c, keep in zip(named, closest, clear_first) if keep)
    if body == "link 3":
        assert ("camera", "link 3") in named  # the plan line can say "camera against link 3"


def test_moves_the_check_passes_keep_the_pairs_apart_all_along():
    """Random joint moves around the board: every move the planner's check lets through keeps the camera,
    the bracket and the link pairs apart by the margin less half a step at every dense sample."""
    rng = np.random.default_rng(5)
    centre = np.array([0.0, 10.0, 5.0, 0.0, 80.0, -90.0])
    starts = centre + rng.uniform(-40, 40, (20, 6)) * [1, 0.5, 0.5, 1, 0.6, 1]
    ends = centre + rng.uniform(-40, 40, (20, 6)) * [1, 0.5, 0.5, 1, 0.6, 1]
    guard = CellCheck(type(CELL)((), CELL.carried)).guard(ROBOT)  # the pairs alone
    found = guard.moves_violations(list(zip(starts, ends)))
    clear = [i for i, v in enumerate(found) if v is None]
    assert 5 <= len(clear) < len(found)  # some pass, some are refused
    path = np.concatenate([joint_path(np.vstack([starts[i], ends[i]]), 0.5) for i in clear])
    assert min(g.min() for g in self_gaps(path).values()) >= MARGIN - STEP / 2
