"""`handeye import`: every format on synthetic files with a known truth and on the shared real sets,
the oddity checks of calibration.diagnostics, and the command line (one-line errors, exit codes)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from helpers import shared_dataset
from handeye.calibration import diagnostics
from handeye.base.errors import SessionError
from handeye.calibration.session import read_session
from handeye.calibration.solve import calibrate_session
from handeye.calibration.synthetic import NoiseConfig, SceneConfig, make_scene, sample_session
from handeye.calibration.compact_points import compact_points_from_corners
from handeye.geometry.transforms import invert_transforms, rotation_error_deg
from handeye.station import cli
from handeye.station.importers import (
    FORMAT_NAMES,
    detect_format,
    read_any,
    read_easy_handeye,
    read_moveit,
    read_opencv,
    read_plain,
    read_stream,
    read_visp,
)

# --------------------------------------------------------------------------- synthetic truth


class Truth:
    """Noise-free poses of a synthetic scene (mm) and its true X."""

    def __init__(self, setup: str, postures: int = 12, seed: int = 3):
        self.scene = make_scene(SceneConfig(postures=postures, setup=setup, seed=seed))
        self.setup = setup
        self.tool0 = self.scene.tool02base()
        self.target = self.scene.target2cam()
        self.x = self.scene.x_true
        self.board = self.scene.board

    @property
    def n(self) -> int:
        return len(self.tool0)


@pytest.fixture(scope="module")
def eih():
    return Truth("eye_in_hand")


@pytest.fixture(scope="module")
def eth():
    return Truth("eye_to_hand")


def _metres(poses):
    out = np.array(poses, dtype=float)
    out[..., :3, 3] /= 1000.0
    return out


def assert_poses_equal(session, tool0, target, tol=1e-6):
    got_a = np.array([p.tool0_in_base for p in session.postures])
    got_b = np.array([p.target_in_camera for p in session.postures])
    assert got_a.shape == np.shape(tool0)
    assert np.max(np.abs(got_a - tool0)) < tol
    assert np.max(np.abs(got_b - target)) < tol


def assert_solves_to_truth(session, truth):
    result = calibrate_session(session, "mcb")
    assert np.max(np.abs(result.x[:3, 3] - truth.x[:3, 3])) < 1e-5
    assert rotation_error_deg(result.x, truth.x) < 1e-6


# --------------------------------------------------------------------------- writers (format specs)


def write_moveit(path, tool0, target):
    data = [[a.tolist(), b.tolist()] for a, b in zip(_metres(tool0), _metres(target))]
    path.write_text(json.dumps(data))
    return path


def _pose_vector_yaml(t):
    v = np.concatenate([t[:3, 3], Rotation.from_matrix(t[:3, :3]).as_rotvec()])
    return "rows: 6\ncols: 1\ndata:\n" + "".join(f"  - [{float(x)!r}]\n" for x in v)


def write_visp(folder, tool0, target, robot_name="pose_fPe_{}.yaml"):
    folder.mkdir(parents=True, exist_ok=True)
    for k, (a, b) in enumerate(zip(_metres(tool0), _metres(target)), start=1):
        (folder / robot_name.format(k)).write_text(_pose_vector_yaml(a))
        (folder / f"pose_cPo_{k}.yaml").write_text(_pose_vector_yaml(b))
    return folder


def write_opencv(path, tool0, target):
    import cv2

    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("frameCount", len(tool0))
    for k, (a, b) in enumerate(zip(_metres(tool0), _metres(target))):
        fs.write(f"T1_{k}", a)
        fs.write(f"T2_{k}", b)
    fs.release()
    return path


def _xyzw(t):
    return Rotation.from_matrix(t[:3, :3]).as_quat()  # scalar last


def _wxyz(t):
    q = _xyzw(t)
    return np.array([q[3], q[0], q[1], q[2]])


def write_plain_csv(path, tool0, target, numbered=False, order="wxyz"):
    if numbered:
        header = ("index,tool0_x,tool0_y,tool0_z,tool0_q1,tool0_q2,tool0_q3,tool0_q4,"
                  "target_x,target_y,target_z,target_q1,target_q2,target_q3,target_q4,comment")
    else:
        header = ("index,tool0_x,tool0_y,tool0_z,tool0_qw,tool0_qx,tool0_qy,tool0_qz,"
                  "target_x,target_y,target_z,target_qw,target_qx,target_qy,target_qz")
    quat = _wxyz if order == "wxyz" else _xyzw
    rows = ["# flange pose in base and board pose in camera, mm", header]
    for k, (a, b) in enumerate(zip(tool0, target)):
        values = [k, *a[:3, 3], *quat(a), *b[:3, 3], *quat(b)]
        rows.append(",".join(repr(float(v)) if i else str(v) for i, v in enumerate(values)) + (",note" if numbered else ""))
    path.write_text("\n".join(rows) + "\n")
    return path


def write_plain_json(path, tool0, target, setup=None):
    postures = []
    for k, (a, b) in enumerate(zip(tool0, target)):
        postures.append({
            "index": k,
            "tool0_in_base": {"position": a[:3, 3].tolist(), "quaternion": _wxyz(a).tolist()},
            "target_in_camera": {"matrix": b.tolist()},
        })
    data = {"units": "mm", "target": {"corners": [13, 8], "square_mm": 30.0}, "postures": postures}
    if setup:
        data["setup"] = setup
    path.write_text(json.dumps(data, indent=1))
    return path


def write_easy_handeye(path, tool0, target, kind="eye_in_hand"):
    def tf(t):
        q = _xyzw(t)
        return {"translation": dict(zip("xyz", map(float, t[:3, 3]))), "rotation": dict(zip("xyzw", map(float, q)))}

    robot = _metres(tool0) if kind == "eye_in_hand" else invert_transforms(_metres(tool0))
    data = {"parameters": {"name": "test", "calibration_type": kind},
            "samples": [{"robot": tf(a), "tracking": tf(b)} for a, b in zip(robot, _metres(target))]}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _slerp_poses(a, b, s):
    """Poses between a and b (s in [0, 1]), straight line and slerp."""
    from scipy.spatial.transform import Slerp

    rot = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([a[:3, :3], b[:3, :3]])))(s).as_matrix()
    out = np.tile(np.eye(4), (len(s), 1, 1))
    out[:, :3, :3] = rot
    out[:, :3, 3] = (1 - s)[:, None] * a[:3, 3] + s[:, None] * b[:3, 3]
    return out


def make_streams(truth, folder, rest_s=0.6, move_s=0.4, t0=1487321563.0, camera_offset_s=0.0037):
    """Robot at 50 Hz holding each posture ``rest_s`` then moving ``move_s`` to the next; camera at
    30 Hz seeing the board as the moving robot would (ETH layout: camera in target, scalar last, m)."""
    period = rest_s + move_s
    end = truth.n * period - move_s

    def robot_at(t):
        k = np.minimum((t // period).astype(int), truth.n - 1)
        phase = t - k * period
        out = truth.tool0[k].copy()
        moving = (phase > rest_s) & (k < truth.n - 1)
        for i in np.flatnonzero(moving):
            s = (phase[i] - rest_s) / move_s
            out[i] = _slerp_poses(truth.tool0[k[i]], truth.tool0[k[i] + 1], np.array([s]))[0]
        return out

    robot_t = np.arange(0.0, end, 0.02)
    camera_t = np.arange(camera_offset_s, end, 1 / 30)
    robot = robot_at(robot_t)
    cam_robot = robot_at(camera_t)
    # eye-in-hand: board fixed in base; target2cam = (tool0 X)^-1 target2base
    target2cam = invert_transforms(cam_robot @ truth.x) @ truth.scene.target2fixed
    camera_in_target = _metres(invert_transforms(target2cam))
    folder.mkdir(parents=True, exist_ok=True)

    def dump(name, stamps, poses):
        lines = [", ".join(repr(float(v)) for v in (t0 + t, *p[:3, 3], *_xyzw(p))) for t, p in zip(stamps, poses)]
        (folder / name).write_text("\n".join(lines) + "\n")
        return folder / name

    hand = dump("run_base_link_hinge.csv", robot_t, _metres(robot))
    cam = dump("run_target_ir.csv", camera_t, camera_in_target)
    return hand, cam


# --------------------------------------------------------------------------- round trips


def test_format_names_match_the_command():
    from handeye.station.commands import import_

    assert tuple(import_.FORMAT_NAMES) == tuple(FORMAT_NAMES)


def test_moveit_round_trip(tmp_path, eth):
    path = write_moveit(tmp_path / "pose_samples.json", eth.tool0, eth.target)
    assert detect_format(path) == "moveit"
    session = read_moveit(path)
    assert session.setup == "eye_to_hand"
    assert session.extra["import"]["units"]["robot"] == "m"
    assert_poses_equal(session, eth.tool0, eth.target)
    assert_solves_to_truth(session, eth)


def test_moveit_eye_in_hand_data_is_detected(tmp_path, eih):
    path = write_moveit(tmp_path / "pose_samples.json", eih.tool0, eih.target)
    session = read_moveit(path)
    assert session.setup == "eye_in_hand"  # the data decide, not the format's default
    assert "detected from the data" in session.extra["import"]["setup_how"]
    assert_solves_to_truth(session, eih)


def test_visp_round_trip(tmp_path, eih):
    folder = write_visp(tmp_path / "visp", eih.tool0, eih.target)
    assert detect_format(folder) == "visp"
    session = read_visp(folder)
    assert session.setup == "eye_in_hand"
    assert_poses_equal(session, eih.tool0, eih.target)
    assert_solves_to_truth(session, eih)


def test_visp_robot_named_rpe_and_unpaired_files(tmp_path, eih):
    folder = write_visp(tmp_path / "apps", eih.tool0, eih.target, robot_name="franka_pose_rPe_{}.yaml")
    (folder / f"franka_pose_rPe_{eih.n + 1}.yaml").write_text(_pose_vector_yaml(_metres(eih.tool0)[0]))
    session = read_visp(folder)
    assert len(session.postures) == eih.n
    dropped = session.extra["import"]["dropped"]
    assert dropped[0]["count"] == 1 and "without a board pose" in dropped[0]["reason"]
    assert_poses_equal(session, eih.tool0, eih.target)


def test_opencv_round_trip(tmp_path, eth):
    path = write_opencv(tmp_path / "TransformPairsInput.yml", eth.tool0, eth.target)
    assert detect_format(path) == "opencv"
    session = read_opencv(path)
    assert session.setup == "eye_to_hand"
    assert_poses_equal(session, eth.tool0, eth.target)
    assert_solves_to_truth(session, eth)


def test_plain_csv_round_trip(tmp_path, eih):
    path = write_plain_csv(tmp_path / "poses.csv", eih.tool0, eih.target)
    assert detect_format(path) == "plain"
    session = read_plain(path)
    assert session.extra["import"]["units"]["robot"] == "mm"
    assert_poses_equal(session, eih.tool0, eih.target)
    assert_solves_to_truth(session, eih)


def test_plain_csv_numbered_quaternions_follow_the_order_option(tmp_path, eih):
    path = write_plain_csv(tmp_path / "poses.csv", eih.tool0, eih.target, numbered=True, order="xyzw")
    session = read_plain(path, quaternion_order="xyzw")
    assert_poses_equal(session, eih.tool0, eih.target)
    assert "comment" in " ".join(session.extra["import"]["notes"])
    # read with the wrong order, the rotations no longer agree: the checks say so
    wrong = read_plain(path, quaternion_order="wxyz", setup="eye_in_hand")
    a = [p.tool0_in_base for p in wrong.postures]
    b = [p.target_in_camera for p in wrong.postures]
    kinds = [f.kind for f in diagnostics.diagnose(a, b, wrong.setup)]
    assert kinds == ["model_mismatch"]


def _swap_quaternion_order(poses):
    """Rotations rebuilt from their (x, y, z, w) quaternion read as (w, x, y, z)."""
    out = np.array(poses, dtype=float)
    q = Rotation.from_matrix(out[:, :3, :3]).as_quat()
    out[:, :3, :3] = Rotation.from_quat(q, scalar_first=True).as_matrix()
    return out


def test_one_side_in_the_wrong_quaternion_order_is_a_convention_finding(eih):
    # a quaternion order swap keeps every relative angle (it permutes quaternion components, an
    # orthogonal map), so the angle gaps stay small; the set-up fit and the translations catch it
    swapped = _swap_quaternion_order(eih.target)
    gaps = diagnostics.posture_angle_gaps(diagnostics.relative_angle_gaps(eih.tool0, swapped))
    assert gaps.max() < 1e-6
    findings = diagnostics.diagnose(eih.tool0, swapped, "eye_in_hand")
    assert [f.kind for f in findings] == ["rotation_convention"]
    assert "quaternion order" in findings[0].message


def test_rotation_convention_errors_on_one_side(eih):
    # a rotation vector read as Euler angles: the relative angles no longer agree at all
    target = eih.target.copy()
    rotvec = Rotation.from_matrix(target[:, :3, :3]).as_rotvec()
    target[:, :3, :3] = Rotation.from_euler("xyz", rotvec).as_matrix()
    findings = diagnostics.diagnose(eih.tool0, target, "eye_in_hand")
    assert [f.kind for f in findings] == ["rotation_convention"]
    assert findings[0].values["typical_gap_deg"] > 5.0
    # a wrong Euler order changes these near-nominal board rotations by a few degrees only: the
    # angle gaps stay moderate, the translations do not fit
    target = eih.target.copy()
    euler = Rotation.from_matrix(target[:, :3, :3]).as_euler("xyz")
    target[:, :3, :3] = Rotation.from_euler("zyx", euler).as_matrix()
    findings = diagnostics.diagnose(eih.tool0, target, "eye_in_hand")
    assert [f.kind for f in findings] == ["model_mismatch"]


def test_plain_json_round_trip(tmp_path, eth):
    path = write_plain_json(tmp_path / "poses.json", eth.tool0, eth.target, setup="eye_to_hand")
    assert detect_format(path) == "plain"
    session = read_plain(path)
    assert session.setup == "eye_to_hand"
    assert session.extra["import"]["setup_how"] == "declared in the file"
    assert session.target.corners == (13, 8) and session.target.square_mm == 30.0
    assert_poses_equal(session, eth.tool0, eth.target)
    assert_solves_to_truth(session, eth)


@pytest.mark.parametrize("kind", ["eye_in_hand", "eye_on_base"])
def test_easy_handeye_round_trip(tmp_path, eih, eth, kind):
    truth = eih if kind == "eye_in_hand" else eth
    path = write_easy_handeye(tmp_path / "calib.samples", truth.tool0, truth.target, kind)
    assert detect_format(path) == "easy_handeye"
    session = read_easy_handeye(path)
    assert session.setup == truth.setup
    assert_poses_equal(session, truth.tool0, truth.target)
    assert_solves_to_truth(session, truth)


def test_stream_pairs_rest_samples_exactly(tmp_path, eih):
    hand, cam = make_streams(eih, tmp_path / "eth")
    assert detect_format([hand, cam]) == "stream"
    assert detect_format(tmp_path / "eth") == "stream"
    session = read_stream([cam, hand], max_postures=0, rest_mm_s=0.5, rest_deg_s=0.05)  # order found by name
    a = np.array([p.tool0_in_base for p in session.postures])
    b = np.array([p.target_in_camera for p in session.postures])
    # every kept pair is one of the true postures, exactly, and every posture is represented
    match = np.argmin(np.linalg.norm(a[:, None, :3, 3] - eih.tool0[None, :, :3, 3], axis=2), axis=1)
    assert set(match) == set(range(eih.n))
    assert np.max(np.abs(a - eih.tool0[match])) < 1e-6
    assert np.max(np.abs(b - eih.target[match])) < 1e-6
    reasons = [d["reason"] for d in session.extra["import"]["dropped"]]
    assert any("hand moving" in r for r in reasons)


def test_stream_decimation_keeps_the_slowest_pair_per_window(tmp_path, eih):
    hand, cam = make_streams(eih, tmp_path / "eth")
    session = read_stream([hand, cam], max_postures=eih.n)
    assert len(session.postures) <= eih.n
    a = np.array([p.tool0_in_base for p in session.postures])
    # each kept pair is taken with the hand at rest: it equals a true posture
    distance = np.min(np.linalg.norm(a[:, None, :3, 3] - eih.tool0[None, :, :3, 3], axis=2), axis=1)
    assert np.max(distance) < 1e-6
    result = calibrate_session(session, "mcb")
    assert np.max(np.abs(result.x[:3, 3] - eih.x[:3, 3])) < 1e-4


def test_stream_tolerance_drops_far_pairs(tmp_path, eih):
    hand, cam = make_streams(eih, tmp_path / "eth")
    lines = hand.read_text().splitlines()
    hand.write_text("\n".join(lines[: len(lines) // 2]) + "\n")  # the robot stream stops half way
    session = read_stream([hand, cam], max_postures=0, tolerance_s=0.015)
    dropped = {d["reason"]: d["count"] for d in session.extra["import"]["dropped"]}
    assert dropped["no robot sample within 15 ms"] > 100
    stamps = [p.extra["source"] for p in session.postures]
    assert all("ms apart" in s for s in stamps)


def test_units_option_overrides_detection(tmp_path, eih):
    path = write_plain_csv(tmp_path / "poses.csv", eih.tool0, eih.target)
    session = read_plain(path, units="m")  # wrong on purpose: values of hundreds declared metres
    assert any("looks like mm" in n for n in session.extra["import"]["warnings"])
    a = [p.tool0_in_base for p in session.postures]
    b = [p.target_in_camera for p in session.postures]
    findings = diagnostics.diagnose(a, b, session.setup)
    assert any(f.kind == "units" and "millimetres read as metres" in f.message for f in findings)


def test_mixed_units_between_files_are_detected_per_side(tmp_path, eih):
    path = write_plain_csv(tmp_path / "poses.csv", eih.tool0, _metres(eih.target))
    session = read_plain(path)
    units = session.extra["import"]["units"]
    assert (units["robot"], units["camera"]) == ("mm", "m")
    assert_poses_equal(session, eih.tool0, eih.target)


# --------------------------------------------------------------------------- the written session


def test_import_writes_a_session_that_reads_back(tmp_path, eth):
    from handeye.station.import_session import ImportOptions, import_to_session

    src = write_moveit(tmp_path / "pose_samples.json", eth.tool0, eth.target)
    out = tmp_path / "session"
    outcome = import_to_session(ImportOptions(sources=(str(src),), output=str(out)))
    assert outcome.findings == []
    back = read_session(out)
    assert back.setup == "eye_to_hand"
    assert back.extra["import"]["format"] == "moveit"
    assert_poses_equal(back, eth.tool0, eth.target)
    assert back.postures[3].extra["source"] == "entry 3"
    assert_solves_to_truth(back, eth)


# --------------------------------------------------------------------------- diagnostics


def _noisy_poses(truth, sigma_cam=1.0, seed=1):
    session = sample_session(truth.scene, NoiseConfig(sigma_cam_mm=sigma_cam, camera_model="gaussian", seed=seed))
    points = np.array([p.points_mm for p in session.postures])
    return truth.tool0.copy(), compact_points_from_corners(points, truth.board).target2cam


@pytest.mark.parametrize("which", ["eih", "eth"])
def test_consistent_data_give_no_findings(which, eih, eth):
    truth = eih if which == "eih" else eth
    assert diagnostics.diagnose(truth.tool0, truth.target, truth.setup) == []
    a, b = _noisy_poses(truth)
    assert diagnostics.diagnose(a, b, truth.setup) == []


def test_angle_and_pitch_do_not_depend_on_the_setup(eih):
    """Why the set-up check uses rotation axes: the angle and the screw pitch of A_ij are the same
    for T_i^-1 T_j (eye-in-hand) and T_i T_j^-1 (eye-to-hand)."""
    a, b = eih.tool0, eih.target
    inv = invert_transforms(a)
    assert np.allclose(diagnostics.relative_angle_gaps(a, b), diagnostics.relative_angle_gaps(inv, b), equal_nan=True)
    assert diagnostics.screw_pitch_scale(a, b) == pytest.approx(diagnostics.screw_pitch_scale(inv, b), rel=1e-9)


def test_duplicate_and_stale_postures(eih):
    a = np.concatenate([eih.tool0, eih.tool0[3:4]])
    b = np.concatenate([eih.target, eih.target[3:4]])
    findings = diagnostics.find_duplicates(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("duplicate_posture", (3, eih.n))]
    b2 = eih.target.copy()
    b2[5] = b2[4]  # the camera frame did not update while the robot moved
    findings = diagnostics.find_duplicates(eih.tool0, b2)
    assert [(f.kind, f.postures) for f in findings] == [("stale_target", (4, 5))]


def test_flipped_board_is_named(eih):
    a, b = _noisy_poses(eih)
    nx, ny = eih.board.corners
    s = eih.board.square_mm
    flip = np.eye(4)
    flip[:3, :3] = np.diag([-1.0, -1.0, 1.0])
    flip[:3, 3] = [(nx - 1) * s, (ny - 1) * s, 0.0]  # origin at the opposite corner
    b[7] = b[7] @ flip
    findings = diagnostics.find_inconsistent_postures(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("flipped_target", (7,))]
    assert findings[0].values["median_gap_deg"] > 10 * findings[0].values["typical_gap_deg"]


def test_gross_outlier_is_not_called_flipped(eih):
    a, b = _noisy_poses(eih)
    b[2, :3, :3] = Rotation.from_rotvec([0.0, 0.25, 0.0]).as_matrix() @ b[2, :3, :3]  # 14 deg off
    findings = diagnostics.find_inconsistent_postures(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("inconsistent_posture", (2,))]


def test_metres_among_millimetres(eih):
    a = eih.tool0.copy()
    a[4, :3, 3] /= 1000.0
    findings = diagnostics.find_unit_problems(a, eih.target)
    assert [(f.kind, f.postures) for f in findings] == [("units", (4,))]
    b = _metres(eih.target)  # camera in m, robot in mm
    findings = diagnostics.find_unit_problems(eih.tool0, b)
    assert len(findings) == 1 and "metres read as millimetres" in findings[0].message
    assert diagnostics.screw_pitch_scale(eih.tool0, b) == pytest.approx(1000.0, rel=1e-6)
    assert diagnostics.screw_pitch_scale(eih.tool0, eih.target) == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("which", ["eih", "eth"])
def test_swapped_setup_is_reported(which, eih, eth):
    truth = eih if which == "eih" else eth
    wrong = "eye_to_hand" if truth.setup == "eye_in_hand" else "eye_in_hand"
    a, b = _noisy_poses(truth)
    findings = diagnostics.diagnose(a, b, wrong)
    assert [f.kind for f in findings] == ["setup"]
    assert findings[0].values["better"] == truth.setup
    residuals = diagnostics.setup_rotation_residuals(a, b)
    assert residuals[truth.setup] < 0.5 < 5.0 < residuals[wrong]


def test_diagnose_session_uses_corner_points(eih):
    session = sample_session(eih.scene, NoiseConfig(sigma_cam_mm=0.5, seed=2))
    assert diagnostics.diagnose_session(session) == []
    session.setup = "eye_to_hand"
    assert [f.kind for f in diagnostics.diagnose_session(session)] == ["setup"]


# --------------------------------------------------------------------------- real data sets

MOVEIT_REF_T_MM = np.array([659.0, -249.0, 830.0])
MOVEIT_REF_EULER_XYZ = (0.230, -2.540, 1.950)
VISP_REF_T_MM = np.array([53.46, -9.52, -45.10])
VISP_REF_THETA_U = (-0.02347, -0.07939, 1.57459)


def test_moveit_set():
    path = shared_dataset("moveit-calibration") / "pose_samples.json"
    session = read_any(path)
    record = session.extra["import"]
    assert record["format"] == "moveit" and len(session.postures) == 50
    assert session.setup == "eye_to_hand" and record["units"]["robot"] == "m"
    result = calibrate_session(session, "mcb")
    assert np.all(np.isfinite(result.x))
    reference = Rotation.from_euler("XYZ", MOVEIT_REF_EULER_XYZ).as_matrix()
    # the published camera pose is MoveIt's own estimate, not truth: a few mm and a fraction of a degree
    assert np.linalg.norm(result.x[:3, 3] - MOVEIT_REF_T_MM) < 5.0
    assert rotation_error_deg(result.x[:3, :3], reference) < 1.0
    assert diagnostics.diagnose_session(session) == []


def test_visp_set():
    session = read_any(shared_dataset("visp-eye-in-hand"))
    assert session.extra["import"]["format"] == "visp" and len(session.postures) == 8
    assert session.setup == "eye_in_hand"
    result = calibrate_session(session, "mcb")
    reference = Rotation.from_rotvec(VISP_REF_THETA_U).as_matrix()
    assert np.linalg.norm(result.x[:3, 3] - VISP_REF_T_MM) < 5.0
    assert rotation_error_deg(result.x[:3, :3], reference) < 1.5


def test_camodocal_set_outliers_and_duplicate():
    session = read_any(shared_dataset("camodocal-ar-tag") / "TransformPairsInput.yml")
    assert session.extra["import"]["format"] == "opencv" and len(session.postures) == 42
    assert session.setup == "eye_to_hand"
    a = np.array([p.tool0_in_base for p in session.postures])
    b = np.array([p.target_in_camera for p in session.postures])
    gaps = diagnostics.posture_angle_gaps(diagnostics.relative_angle_gaps(a, b))
    others = np.delete(gaps, [21, 36])
    # the figures: 5-6 deg for postures 21 and 36 against about 1-2 deg for the others
    assert 5.0 <= gaps[21] <= 6.5 and 5.0 <= gaps[36] <= 6.5
    assert others.max() < 2.0 and 0.8 < np.median(others) < 1.5
    findings = diagnostics.diagnose_session(session)
    kinds = {(f.kind, f.postures) for f in findings}
    assert kinds == {("inconsistent_posture", (21,)), ("inconsistent_posture", (36,)),
                     ("duplicate_posture", (28, 29))}
    assert np.all(np.isfinite(calibrate_session(session, "mcb").x))


def test_ethz_streams():
    folder = shared_dataset("ethz-robot-arm")
    session = read_any(folder)
    record = session.extra["import"]
    assert record["format"] == "stream" and session.setup == "eye_in_hand"
    assert len(session.postures) == 40
    offsets = [float(p.extra["source"].split(", ")[1].split(" ms")[0]) for p in session.postures]
    assert max(offsets) <= 30.0
    result = calibrate_session(session, "mcb")
    assert np.all(np.isfinite(result.x))
    # the camera sits on the hand: tens of mm from the hinge frame, not metres
    assert np.linalg.norm(result.x[:3, 3]) < 200.0
    at_rest = read_any(folder, rest_mm_s=20.0, max_postures=30)
    assert 3 <= len(at_rest.postures) <= 30


# --------------------------------------------------------------------------- malformed files


def _one_line_error(fn, *args, match, **kwargs):
    with pytest.raises(SessionError, match=match) as info:
        fn(*args, **kwargs)
    assert "\n" not in str(info.value)
    return str(info.value)


def test_malformed_moveit(tmp_path, eth):
    path = tmp_path / "bad.json"
    path.write_text('[[[[1, 0, 0, 0], [0, 1, 0, 0]\n  oops')
    _one_line_error(read_moveit, path, match=r"bad.json: not valid JSON \(line 2")
    data = [[a.tolist(), b.tolist()] for a, b in zip(_metres(eth.tool0), _metres(eth.target))]
    data[4][1] = data[4][1][:3]
    path.write_text(json.dumps(data))
    message = _one_line_error(read_moveit, path, match=r"entry 4: T_cam_target must be a 4x4 matrix")
    assert "--skip-invalid" in message
    session = read_moveit(path, skip_invalid=True)
    assert len(session.postures) == eth.n - 1
    assert session.extra["import"]["dropped"][0]["examples"] == ["entry 4"]
    data[4][1] = (np.eye(4) * 2).tolist()
    path.write_text(json.dumps(data))
    _one_line_error(read_moveit, path, match=r"entry 4: T_cam_target bottom row|entry 4: T_cam_target rotation part")


def test_malformed_visp(tmp_path, eih):
    folder = write_visp(tmp_path / "v", eih.tool0, eih.target)
    (folder / "pose_cPo_3.yaml").write_text("rows: 6\ncols: 1\ndata:\n  - [0.1\n  - [0.2]\n")
    _one_line_error(read_visp, folder, match=r"pose_cPo_3.yaml: not valid YAML \(line \d+\)")
    (folder / "pose_cPo_3.yaml").write_text("rows: 6\ncols: 1\ndata:\n  - [0.1]\n")
    _one_line_error(read_visp, folder, match=r"pose_cPo_3.yaml: data must hold six numbers")


def test_malformed_opencv(tmp_path, eth):
    path = write_opencv(tmp_path / "pairs.yml", eth.tool0, eth.target)
    text = path.read_text().splitlines()
    row = next(i for i, line in enumerate(text) if "data:" in line)
    text[row] = text[row].replace(",", "", 1)
    path.write_text("\n".join(text) + "\n")
    _one_line_error(read_opencv, path, match=rf"pairs.yml: not a readable OpenCV FileStorage file \(line {row + 1}")
    path.write_text("%YAML:1.0\nframeCount: 0\n")
    _one_line_error(read_opencv, path, match=r"no T1_<i> / T2_<i> matrices")


def test_malformed_stream_and_plain(tmp_path, eih):
    hand, cam = make_streams(eih, tmp_path / "eth")
    lines = cam.read_text().splitlines()
    lines[6] = lines[6].rsplit(",", 1)[0]
    cam.write_text("\n".join(lines) + "\n")
    _one_line_error(read_stream, [hand, cam], match=r"target_ir.csv: line 7: expected 8 values")
    session = read_stream([hand, cam], skip_invalid=True, max_postures=0)
    dropped = {d["reason"]: d["examples"] for d in session.extra["import"]["dropped"]}
    assert dropped["invalid: expected 8 values"] == ["line 7"]
    lines[6] = lines[5].replace("0.", "0.x", 1)
    cam.write_text("\n".join(lines) + "\n")
    _one_line_error(read_stream, [hand, cam], match=r"line 7: not a number")
    path = write_plain_csv(tmp_path / "p.csv", eih.tool0, eih.target)
    text = path.read_text().replace("target_qz", "target_q_z")
    path.write_text(text)
    _one_line_error(read_plain, path, match=r"p.csv: line 2: header lacks target_qz")
    text = "\n".join(path.read_text().replace("target_q_z", "target_qz").splitlines()[:5] + ["3,1,2,3,1,0,0,0,1,2,3,2,0,0,0"])
    path.write_text(text + "\n")
    _one_line_error(read_plain, path, match=r"line 6: target pose: quaternion \(wxyz\) has norm 2")


def test_unknown_content_and_misapplied_options(tmp_path, eth):
    path = tmp_path / "notes.txt"
    path.write_text("hello\n")
    _one_line_error(detect_format, path, match=r"cannot tell the format from its content; pass --format")
    src = write_moveit(tmp_path / "pose_samples.json", eth.tool0, eth.target)
    _one_line_error(read_any, src, match=r"--tolerance-s does not apply to moveit files", tolerance_s=0.02)
    _one_line_error(read_any, tmp_path / "missing.json", match=r"missing.json: no such file")


# --------------------------------------------------------------------------- command line


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_cli_import_and_refuse_overwrite(tmp_path, capsys, eth):
    src = write_opencv(tmp_path / "pairs.yml", eth.tool0, eth.target)
    out = tmp_path / "s"
    code, stdout, stderr = run_cli(capsys, "import", src, "-o", out)
    assert code == 0 and stderr == ""
    assert "format:   opencv, detected" in stdout
    assert f"postures: {eth.n} from {eth.n} entries" in stdout
    assert f"next: handeye calibrate {out}" in stdout
    before = (out / "postures" / "000.yaml").read_text()
    code, stdout, stderr = run_cli(capsys, "import", src, "-o", out)
    assert code == 1 and stdout == ""
    assert stderr.count("\n") == 1 and "already holds a session" in stderr and "--overwrite" in stderr
    assert (out / "postures" / "000.yaml").read_text() == before
    (out / "truth.yaml").write_text("camera_pose: {}\n")  # as if a simulated session had been there
    code, stdout, stderr = run_cli(capsys, "import", src, "-o", out, "--overwrite", "--setup", "eye_in_hand")
    assert code == 0
    assert "setup:    eye_in_hand, given" in stdout
    assert "removed:  truth.yaml of the replaced session" in stdout and not (out / "truth.yaml").exists()
    assert stderr.startswith("handeye import: warning: --setup eye_in_hand: the poses do not fit it (angle gap")
    assert "while eye_to_hand, robot flange in base" in stderr and "read as given" in stderr
    assert read_session(out).setup == "eye_in_hand"


def test_cli_errors_are_one_line(tmp_path, capsys, eth):
    bad = tmp_path / "pose_samples.json"
    bad.write_text("[[[[1, 2]]], ")
    out = tmp_path / "s"
    code, stdout, stderr = run_cli(capsys, "import", bad, "-o", out, "--format", "moveit")
    assert code == 1 and stderr.count("\n") == 1 and "not valid JSON" in stderr and "Traceback" not in stderr
    assert not out.exists()  # nothing created for a bad input
    code, _, stderr = run_cli(capsys, "import", tmp_path / "nothing.yml", "-o", out)
    assert code == 1 and stderr.count("\n") == 1 and "no such file" in stderr
    src = write_moveit(tmp_path / "ok.json", eth.tool0, eth.target)
    code, _, stderr = run_cli(capsys, "import", src, "-o", out, "--max-postures", "10")
    assert code == 2 and "--max-postures does not apply to moveit files" in stderr  # usage errors exit 2
    code, _, stderr = run_cli(capsys, "import", src, "-o", out, "--square-mm", "30")
    assert code == 2 and "--square-mm needs --board" in stderr


def test_cli_warnings_for_odd_data(tmp_path, capsys, eih):
    a = np.concatenate([eih.tool0, eih.tool0[2:3]])
    b = np.concatenate([eih.target, eih.target[2:3]])
    src = write_plain_csv(tmp_path / "p.csv", a, b)
    code, stdout, stderr = run_cli(capsys, "import", src, "-o", tmp_path / "s", "--board", "13x8", "--square-mm", "30")
    assert code == 0
    assert "target:   13x8 inner corners, 30 mm squares" in stdout
    warnings = stderr.strip().splitlines()
    assert len(warnings) == 1 and f"postures 2 and {eih.n}: the same robot pose" in warnings[0]


def test_help_lists_import(capsys):
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    assert "import" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        cli.main(["import", "--help"])
    text = capsys.readouterr().out
    assert "pose_samples.json" in text and "Examples:" in text


# --------------------------------------------------------------------------- board poses from images (ViSP apps)


def render_board(target2cam, corners, square_mm, k, size, px_per_mm=4.0, margin_mm=15.0):
    """A grey image of a chessboard whose conventions frame sits at ``target2cam`` (mm).

    Square (i, j) (i along x) is black when i + j is even, so the x = 0 edge has black corner
    squares; the first inner corner is the target origin.
    """
    import cv2

    nx, ny = corners
    sx, sy = nx + 1, ny + 1
    width_mm, height_mm = sx * square_mm + 2 * margin_mm, sy * square_mm + 2 * margin_mm
    tex = np.full((int(height_mm * px_per_mm), int(width_mm * px_per_mm)), 255, np.uint8)
    for i in range(sx):
        for j in range(sy):
            if (i + j) % 2 == 0:
                x0, y0 = (margin_mm + i * square_mm) * px_per_mm, (margin_mm + j * square_mm) * px_per_mm
                tex[int(round(y0)):int(round(y0 + square_mm * px_per_mm)), int(round(x0)):int(round(x0 + square_mm * px_per_mm))] = 0
    # texture pixel -> target frame (mm, z = 0), origin at the first inner corner
    offset = margin_mm + square_mm
    half = 0.5 / px_per_mm  # the square edges drawn at integer indices lie half a pixel before the centres
    a = np.array([[1 / px_per_mm, 0, half - offset], [0, 1 / px_per_mm, half - offset], [0, 0, 1.0]])
    rt = np.column_stack([target2cam[:3, 0], target2cam[:3, 1], target2cam[:3, 3]])
    h = k @ rt @ a
    # render at 3x and shrink: area averaging instead of aliasing
    up = np.diag([3.0, 3.0, 1.0]) @ np.array([[1, 0, 1.0 / 3], [0, 1, 1.0 / 3], [0, 0, 1]])
    big = cv2.warpPerspective(tex, up @ h, (3 * size[0], 3 * size[1]), flags=cv2.INTER_LINEAR, borderValue=110)
    return cv2.resize(big, size, interpolation=cv2.INTER_AREA)


def _camera_xml(path, k):
    path.write_text(f"""<?xml version="1.0"?>
<root>
  <camera>
    <name>Camera</name>
    <image_width>1280</image_width>
    <image_height>960</image_height>
    <model>
      <type>perspectiveProjWithDistortion</type>
      <px>{k[0, 0]}</px>
      <py>{k[1, 1]}</py>
      <u0>{k[0, 2]}</u0>
      <v0>{k[1, 2]}</v0>
      <kud>0</kud>
      <kdu>0</kdu>
    </model>
  </camera>
</root>
""")


@pytest.mark.parametrize("roll_deg", [0.0, 90.0, 180.0, 270.0])
def test_board_pose_from_an_image_keeps_the_conventions_frame(tmp_path, roll_deg):
    import cv2

    from handeye.geometry.board import BoardGeometry
    from handeye.station.importers.visp_images import CameraIntrinsics, measure_board_pose

    k = np.array([[600.0, 0, 320.0], [0, 600.0, 240.0], [0, 0, 1]])
    board = BoardGeometry((9, 6), 23.6)
    centre = np.array([4 * 23.6, 2.5 * 23.6, 0.0])
    pose = np.eye(4)
    pose[:3, :3] = (Rotation.from_euler("xyz", [15.0, -10.0, 0.0], degrees=True)
                    * Rotation.from_euler("z", roll_deg, degrees=True)).as_matrix()
    pose[:3, 3] = np.array([10.0, -5.0, 420.0]) - pose[:3, :3] @ centre  # board centre 420 mm ahead
    image = render_board(pose, (9, 6), 23.6, k, (640, 480))
    cv2.imwrite(str(tmp_path / "x_image-1.png"), image)
    result = measure_board_pose(tmp_path / "x_image-1.png", board, CameraIntrinsics(600.0, 600.0, 320.0, 240.0))
    assert result["rms_px"] < 0.3
    assert np.linalg.norm(result["pose"][:3, 3] - pose[:3, 3]) < 2.0
    assert rotation_error_deg(result["pose"], pose) < 0.5


def test_reversed_corner_order_is_turned_back(tmp_path):
    import cv2

    from handeye.station.importers.visp_images import canonical_corner_order

    k = np.array([[600.0, 0, 320.0], [0, 600.0, 240.0], [0, 0, 1]])
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_euler("xyz", [10.0, 5.0, 30.0], degrees=True).as_matrix()
    pose[:3, 3] = [-90.0, -60.0, 420.0]
    image = render_board(pose, (9, 6), 23.6, k, (640, 480))
    found, corners = cv2.findChessboardCorners(image, (9, 6))
    assert found
    corners = corners.reshape(-1, 2)
    same, turned = canonical_corner_order(image, corners, (9, 6))
    assert not turned and np.array_equal(same, corners)
    back, turned = canonical_corner_order(image, corners[::-1], (9, 6))  # the 180-deg ambiguous order
    assert turned and np.allclose(back, corners)
    # a 180-deg symmetric board (odd x odd squares) is left as detected
    sym, turned = canonical_corner_order(image, corners[:48], (8, 6))
    assert not turned


def test_visp_app_folder_with_images_end_to_end(tmp_path, eih):
    """Robot poses + rendered images of the scene's 13x8 board: the measured board poses and the
    solved camera mount match the truth."""
    import cv2

    from handeye.robot.views import NOMINAL_XB3_LEFT as cam

    k = np.array([[cam.f_px, 0, cam.cx], [0, cam.f_px, cam.cy], [0, 0, 1.0]])
    folder = tmp_path / "app"
    folder.mkdir()
    for i, (a, b) in enumerate(zip(eih.tool0, eih.target), start=1):
        (folder / f"robot_pose_rPe_{i}.yaml").write_text(_pose_vector_yaml(_metres(a[None])[0]))
        image = render_board(b, eih.board.corners, eih.board.square_mm, k, (cam.width, cam.height), px_per_mm=3.0)
        cv2.imwrite(str(folder / f"robot_image-{i}.png"), image)
    _camera_xml(folder / "robot_camera.xml", k)
    (folder / "chessboard-data.txt").write_text("Chessboard\n13 x 8\nsquare size: 0.030 m\n")
    session = read_any(folder)
    assert session.extra["import"]["format"] == "visp" and len(session.postures) == eih.n
    assert session.target.corners == (13, 8) and session.target.square_mm == pytest.approx(30.0)
    b = np.array([p.target_in_camera for p in session.postures])
    assert np.max(np.linalg.norm(b[:, :3, 3] - eih.target[:, :3, 3], axis=1)) < 3.0  # at 0.7-1.2 m
    assert np.max(rotation_error_deg(b, eih.target)) < 0.5
    result = calibrate_session(session, "mcb")
    assert np.linalg.norm(result.x[:3, 3] - eih.x[:3, 3]) < 5.0
    assert rotation_error_deg(result.x, eih.x) < 0.5


def test_visp_apps_set_board_poses_from_images():
    session = read_any(shared_dataset("visp-apps-eye-in-hand"))
    record = session.extra["import"]
    assert len(session.postures) == 8 and session.setup == "eye_in_hand"
    assert record["board_measurement"]["max_rms_px"] < 1.0
    assert session.target.corners == (9, 6) and session.target.square_mm == pytest.approx(23.6)
    result = calibrate_session(session, "mcb")
    assert np.all(np.isfinite(result.x)) and np.linalg.norm(result.x[:3, 3]) < 200.0
    assert diagnostics.diagnose_session(session) == []


# --------------------------------------------------------------------------- never a traceback


def test_truncated_and_garbled_files_give_session_errors_only(tmp_path, eih):
    """Every reader, fed its own valid file cut short at many places or with bytes flipped, either
    reads it or raises SessionError: no other exception escapes."""
    a, b = eih.tool0[:5], eih.target[:5]
    hand, cam = make_streams(eih, tmp_path / "eth")
    sources = {
        "moveit": write_moveit(tmp_path / "m.json", a, b),
        "opencv": write_opencv(tmp_path / "o.yml", a, b),
        "plain_csv": write_plain_csv(tmp_path / "p.csv", a, b),
        "plain_json": write_plain_json(tmp_path / "p.json", a, b),
        "easy_handeye": write_easy_handeye(tmp_path / "e.samples", a, b),
        "visp": write_visp(tmp_path / "v", a, b) / "pose_cPo_2.yaml",
        "stream": cam,
    }
    readers = {
        "moveit": lambda p: read_moveit(p), "opencv": lambda p: read_opencv(p), "plain_csv": lambda p: read_plain(p),
        "plain_json": lambda p: read_plain(p), "easy_handeye": lambda p: read_easy_handeye(p),
        "visp": lambda p: read_visp(p.parent), "stream": lambda p: read_stream([hand, p], max_postures=0),
    }
    rng = np.random.default_rng(0)
    for name, path in sources.items():
        original = path.read_bytes()
        variants = [original[:cut] for cut in np.linspace(0, len(original) - 1, 12).astype(int)]
        for _ in range(8):
            garbled = bytearray(original)
            for position in rng.integers(0, len(garbled), 3):
                garbled[position] = int(rng.choice(list(b"x,:[]{}-\n\x00\xff9")))
            variants.append(bytes(garbled))
        for variant in variants:
            path.write_bytes(variant)
            try:
                readers[name](path)
            except SessionError as exc:
                assert "\n" not in str(exc), (name, str(exc))
        path.write_bytes(original)
