"""Cost linear in the posture count (issue 25, finding 2): pairwise checks on a bounded set of pairs,
streams decimated and said so, more postures than a session holds refused in one line.

Nothing here runs a large session (``benchmarks/scale/bench_scale.py`` measures 10,000 postures): each
test makes a cheap call whose memory or number of pairs would grow with ``n^2`` on the old code.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.calibration import diagnostics
from handeye.calibration.eiv import board_pose_angle_gaps_deg
from handeye.base.errors import SessionError
from handeye.calibration.invariants import ALL_PAIRS_UP_TO, bounded_pairs, pair_indices
from handeye.calibration.session import Posture, Session, write_posture, write_postures
from handeye.calibration.solve import check_motion, problem_from_session
from handeye.geometry.transforms import invert_transforms, transform_from_rotation_translation
from handeye.station import cli
from handeye.station.importers import read_stream

CAM2TOOL0 = transform_from_rotation_translation(Rotation.from_euler("xyz", [3, -2, 91], degrees=True).as_matrix(),
                                                np.array([42.0, -75.0, 118.0]))
TARGET2BASE = transform_from_rotation_translation(Rotation.from_euler("xyz", [180, 0, 4], degrees=True).as_matrix(),
                                                  np.array([1050.0, 80.0, 150.0]))


def station(n: int, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """``n`` consistent (tool0_in_base, target_in_camera) pairs, mm, drawn directly (no kinematics)."""
    rng = np.random.default_rng(seed)
    tilt = Rotation.from_rotvec(np.column_stack([rng.uniform(-0.4, 0.4, (n, 2)), rng.uniform(-1.5, 1.5, n)]))
    position = np.column_stack([rng.uniform(-120, 120, (n, 2)), rng.uniform(450, 900, n)])
    target2cam = transform_from_rotation_translation(tilt.as_matrix(), position)
    return TARGET2BASE @ invert_transforms(target2cam) @ invert_transforms(CAM2TOOL0), target2cam


def peak_mb(call) -> tuple[object, float]:
    """``call()`` and the peak memory (MB) numpy and Python allocated meanwhile."""
    tracemalloc.start()
    try:
        out = call()
        return out, tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def test_pair_sample_does_not_build_every_pair():
    pairs, peak = peak_mb(lambda: pair_indices(300_000, 2000))  # 4.5e10 pairs: the old code built them all
    assert pairs.shape == (2000, 2)
    assert np.all(pairs[:, 0] < pairs[:, 1]) and pairs.min() >= 0 and pairs.max() < 300_000
    assert peak < 50
    assert np.array_equal(pairs, pair_indices(300_000, 2000))  # seeded: reproducible
    # the sample of a small set is what it was: the same draw from the list of every pair
    i, j = np.triu_indices(120, k=1)
    keep = np.sort(np.random.default_rng(0).choice(len(i), size=2000, replace=False))
    assert np.array_equal(pair_indices(120, 2000), np.stack([i, j], axis=1)[keep])


def test_bounded_pairs_every_pair_when_small_linear_when_large():
    assert np.array_equal(bounded_pairs(100), pair_indices(100))
    for n in (5_000, 40_000):
        pairs = bounded_pairs(n)
        assert len(pairs) <= 11 * n
        assert np.all(pairs[:, 0] < pairs[:, 1])
        assert len(np.unique(pairs[:, 0] * n + pairs[:, 1])) == len(pairs)
        assert np.all(np.bincount(pairs.ravel(), minlength=n) >= 2)  # every posture takes part
        assert np.all(np.isin(np.arange(n - 1) * n + np.arange(1, n), pairs[:, 0] * n + pairs[:, 1]))  # neighbours


def test_diagnostics_use_a_bounded_number_of_pairs():
    a, b = station(1500)
    fit = diagnostics.hand_eye_fit(a, b, "eye_in_hand")
    assert 0 < fit["pairs"] <= ALL_PAIRS_UP_TO + 1500  # all pairs: 1,124,250
    assert fit["rotation_deg"] < 0.01


def test_diagnose_memory_is_linear_and_duplicates_far_apart_are_still_found():
    a, b = station(1500)
    a[1400], b[1400] = a[3], b[3]  # the same sample again, far apart in time
    findings, peak = peak_mb(lambda: diagnostics.diagnose(a, b, "eye_in_hand"))
    assert [(f.kind, f.postures) for f in findings] == [("duplicate_posture", (3, 1400))]
    assert peak < 150


def test_start_angle_gaps_do_not_build_an_n_by_n_table():
    a, b = station(3000)
    gaps, peak = peak_mb(lambda: board_pose_angle_gaps_deg(a, b))
    assert gaps.shape == (3000,) and np.all(gaps < 1e-6)
    assert peak < 40  # one (3000, 3000) table of floats is 72 MB


def test_motion_check_memory_is_linear():
    a, b = station(3000)
    session = Session("eye_in_hand", None, None, [Posture(k, tool0_in_base=a[k], target_in_camera=b[k]) for k in range(3000)])
    problem = problem_from_session(session, check_consistency=False)
    _, peak = peak_mb(lambda: check_motion(problem))
    assert peak < 150


def write_stream(folder, rows: int):
    """Robot and camera CSV streams (ETH layout, metres, quaternion x y z w) of ``rows`` samples at 250 Hz."""
    a, b = station(rows)
    t = np.arange(rows) / 250.0
    columns = []
    for poses in (a, invert_transforms(b)):  # the camera stream holds the camera in the target
        columns.append(np.column_stack([t, poses[:, :3, 3] / 1000.0, Rotation.from_matrix(poses[:, :3, :3]).as_quat()]))
    robot, camera = folder / "hand_base.csv", folder / "camera_target.csv"
    np.savetxt(robot, columns[0], delimiter=",", fmt="%.10g")
    np.savetxt(camera, columns[1], delimiter=",", fmt="%.10g")
    return robot, camera


def test_stream_decimation_is_said(tmp_path, capsys):
    robot, camera = write_stream(tmp_path, 2000)
    code = cli.main(["import", str(robot), str(camera), "-o", str(tmp_path / "s"), "--max-postures", "30"])
    out = capsys.readouterr().out
    assert code == 0
    assert "decimated: stream of 2000 rows (2000 pairs within the stamp tolerance) decimated to 30 postures by keeping " \
           "the slowest pair in each of 30 time windows" in out
    assert "pairwise on all 435 posture pairs" in out


def test_more_postures_than_a_session_holds_are_refused_in_one_line(tmp_path, capsys):
    robot, camera = write_stream(tmp_path, 10_001)
    with pytest.raises(SessionError, match="10001 pose pairs, more than the 10000 postures a session holds"):
        read_stream([robot, camera], max_postures=0)
    code = cli.main(["import", str(robot), str(camera), "-o", str(tmp_path / "s"), "--max-postures", "0"])
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert "--max-postures N" in err and "Traceback" not in err
    assert not (tmp_path / "s").exists()


def test_postures_written_in_one_batch_are_the_files_written_one_by_one(tmp_path):
    a, b = station(20)
    postures = [Posture(k, tool0_in_base=a[k], target_in_camera=b[k], extra={"source": f"row {k}"}) for k in range(20)]
    for p in postures:
        write_posture(tmp_path / "one", p)
    write_postures(tmp_path / "batch", postures)
    for p in postures:
        name = f"postures/{p.index:03d}.yaml"
        assert (tmp_path / "batch" / name).read_bytes() == (tmp_path / "one" / name).read_bytes()
    assert not list((tmp_path / "batch").rglob("*.tmp"))
