"""Issue 11: any hand-eye log imports as it was written; its conventions are inferred from the data.

Logs are written here in other tools' conventions (every Euler convention, quaternion orders,
rotation vectors, matrices, every inversion of either pose set, metres or millimetres, both
set-ups), from noisy synthetic stations and from the real sets of ../shared/datasets. Each must
import unchanged to the poses it was written from, or be refused in one line naming the flag that
decides; with that flag it must import right. No test may end with a wrong pose and exit 0.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from handeye.base.errors import SessionError
from handeye.station.importers import detect_format, read_any
from pose_logs import (EULER_SEQUENCES, FANUC, KUKA, MATRIX16, ROS_RPY, ROTVEC, RVEC_TVEC, WXYZ, XYZW, PoseConvention,
                       Truth, encode, same_poses, table_text, write_yaml)

FLAGS = ("--robot-pose", "--camera-pose", "--setup", "--euler", "--units", "--quaternion-order")


@pytest.fixture(scope="module")
def eih():
    return Truth("eye_in_hand")


@pytest.fixture(scope="module")
def eth():
    return Truth("eye_to_hand")


def truth_of(name, eih, eth):
    return eih if name == "eih" else eth


def write_log(path, truth, robot=KUKA, camera=ROTVEC, robot_unit="mm", camera_unit="m", invert_robot=False,
              invert_camera=False, **table):
    path.write_text(table_text(encode(truth.tool0, robot, robot_unit, invert_robot),
                               encode(truth.target, camera, camera_unit, invert_camera), **table))
    return path


def read_or_refusal(path, **options):
    """The session, or the refusal's message (one line naming a flag)."""
    try:
        return read_any(path, **options)
    except SessionError as exc:
        message = str(exc)
        assert "\n" not in message
        assert any(flag in message for flag in FLAGS), message
        return message


def _flag_options(message: str, truth_setup: str, robot_inverted: bool, camera_inverted: bool) -> dict:
    """The options a user would add after a refusal naming flags: the first flag named, set right."""
    for flag in FLAGS:
        if flag in message:
            break
    if flag == "--setup":
        return {"setup": truth_setup}
    if flag == "--robot-pose":
        return {"robot_pose": "base_in_flange" if robot_inverted else "flange_in_base"}
    if flag == "--camera-pose":
        return {"camera_pose": "camera_in_target" if camera_inverted else "target_in_camera"}
    raise AssertionError(f"unexpected flag in {message}")


# --------------------------------------------------------------------------- every convention, every inversion


@pytest.mark.parametrize("sequence", EULER_SEQUENCES)
def test_every_euler_convention_imports_unchanged(tmp_path, eih, eth, sequence):
    """24 conventions x degrees and radians, robot side (mm) and camera side (m), both set-ups."""
    for degrees, truth in ((True, eih), (False, eth)):
        euler = PoseConvention("euler", sequence=sequence, degrees=degrees)
        robot_side = write_log(tmp_path / f"r{degrees}.csv", truth, robot=euler, camera=ROTVEC)
        session = read_any(robot_side)
        assert session.extra["import"]["format"] == "log"
        assert same_poses(session, truth.tool0, truth.target) and session.setup == truth.setup
        words = session.extra["import"]["conventions"]["robot"]
        axes = "rotating axes" if sequence.isupper() else "static axes"
        assert f"Euler {sequence.upper()} {axes} in {'degrees' if degrees else 'radians'}" in words
        camera_side = write_log(tmp_path / f"c{degrees}.csv", truth, robot=WXYZ, camera=euler, camera_unit="mm")
        session = read_any(camera_side)
        assert same_poses(session, truth.tool0, truth.target) and session.setup == truth.setup


@pytest.mark.parametrize("setup, invert_robot, invert_camera",
                         list(itertools.product(("eih", "eth"), (False, True), (False, True))))
def test_every_inversion_in_both_setups(tmp_path, eih, eth, setup, invert_robot, invert_camera):
    truth = truth_of(setup, eih, eth)
    path = write_log(tmp_path / "log.txt", truth, invert_robot=invert_robot, invert_camera=invert_camera, sep=" ")
    session = read_any(path)
    assert same_poses(session, truth.tool0, truth.target) and session.setup == truth.setup
    conventions = session.extra["import"]["conventions"]
    assert conventions["robot"].startswith(
        f"robot poses read as {'base in flange' if invert_robot else 'flange in base'}, position in mm, Euler ZYX")
    assert conventions["camera"].startswith(
        f"camera poses read as {'camera in target' if invert_camera else 'target in camera'}, position in m converted "
        f"to mm, rotation vector")


@pytest.mark.parametrize("robot, camera", [
    (MATRIX16, MATRIX16), (PoseConvention("matrix", "column", width=16), PoseConvention("matrix", "row", width=12)),
    (PoseConvention("matrix", "column", width=12), XYZW), (WXYZ, XYZW),
    (PoseConvention("quaternion", "wxyz", rotation_first=True, width=7), RVEC_TVEC),
    (PoseConvention("quaternion", "xyzw", rotation_first=True, width=7), MATRIX16),
    (ROTVEC, ROTVEC), (FANUC, ROS_RPY),
])
def test_pose_forms(tmp_path, eih, robot, camera):
    path = write_log(tmp_path / "log.csv", eih, robot=robot, camera=camera)
    session = read_any(path)
    assert same_poses(session, eih.tool0, eih.target)


@pytest.mark.parametrize("vendor, convention, unit", [
    ("kuka", KUKA, "mm"), ("fanuc", FANUC, "mm"), ("ur", ROTVEC, "m"), ("ros", ROS_RPY, "m"), ("ros", XYZW, "m"),
    ("abb", WXYZ, "mm"), ("abb", KUKA, "mm"), ("visp", ROTVEC, "m"), ("opencv", RVEC_TVEC, "m"),
])
def test_vendor_conventions_by_name_and_inferred(tmp_path, eih, vendor, convention, unit):
    """The robot side in a vendor's convention: read right by its name (--euler VENDOR) and without it."""
    from handeye.station.importers.conventions import parse_rotation_spec

    assert convention.key in [c.key for c in parse_rotation_spec(vendor)[convention.width]]
    path = write_log(tmp_path / "log.csv", eih, robot=convention, robot_unit=unit, camera=XYZW, camera_unit="m")
    for options in ({"euler": f"robot:{vendor}"}, {}):
        session = read_any(path, **options)
        assert same_poses(session, eih.tool0, eih.target)


# --------------------------------------------------------------------------- layouts of text, JSON, YAML


def test_text_layouts(tmp_path, eih):
    r, c = encode(eih.tool0, KUKA), encode(eih.target, XYZW, "m")
    header = ["x", "y", "z", "a", "b", "c", "cam_x", "cam_y", "cam_z", "qx", "qy", "qz", "qw"]
    texts = {
        "header.csv": table_text(r, c, header=header),
        "index.tsv": table_text(r, c, sep="\t", index=True),
        "spaces.txt": table_text(r, c, sep="   ", comment="robot x y z a b c, then the camera"),
        "semicolons.csv": table_text(r, c, sep=";").replace(".", ","),
        "camera_first.csv": table_text(c, r, header=header[6:] + header[:6]),
        "blocks.txt": "# robot poses\n" + table_text(r) + "\n# camera poses (marker in camera)\n" + table_text(c),
    }
    for name, text in texts.items():
        (tmp_path / name).write_text(text)
        session = read_any(tmp_path / name)
        assert detect_format(tmp_path / name) == "log"
        assert same_poses(session, eih.tool0, eih.target), name
    # two files: the camera file named as such, given first
    (tmp_path / "pair").mkdir()
    (tmp_path / "pair" / "marker_poses.csv").write_text(table_text(c))
    (tmp_path / "pair" / "robot_poses.csv").write_text(table_text(r))
    session = read_any([tmp_path / "pair" / "marker_poses.csv", tmp_path / "pair" / "robot_poses.csv"])
    assert same_poses(session, eih.tool0, eih.target)
    assert same_poses(read_any(tmp_path / "pair"), eih.tool0, eih.target)


def test_matrices_over_several_lines(tmp_path, eih):
    rows = []
    for a, b in zip(eih.tool0, eih.target):
        rows.append("posture:")
        rows += [" ".join(f"{v:.15g}" for v in line) for line in a]
        rows += [" ".join(f"{v:.15g}" for v in line) for line in b[:3]]  # 3x4, no bottom row
    (tmp_path / "pairs.txt").write_text("\n".join(rows) + "\n")
    assert same_poses(read_any(tmp_path / "pairs.txt"), eih.tool0, eih.target)
    blocks = ["robot (flange in base):"] + [" ".join(f"{v:.15g}" for v in line) for a in eih.tool0 for line in a]
    blocks += ["camera (target in camera):"] + [" ".join(f"{v:.15g}" for v in line) for b in eih.target for line in b]
    (tmp_path / "blocks.txt").write_text("\n".join(blocks) + "\n")
    assert same_poses(read_any(tmp_path / "blocks.txt"), eih.tool0, eih.target)


def test_json_and_yaml_of_any_nesting(tmp_path, eih, eth):
    a, b = eih.tool0, eih.target
    m_a, m_b = a.copy(), b.copy()
    m_a[:, :3, 3] /= 1000.0
    m_b[:, :3, 3] /= 1000.0

    def ros_pose(t):
        q = [float(v) for v in encode(t[None], XYZW, "m")[0]]
        return {"position": dict(zip("xyz", q[:3])), "orientation": dict(zip("xyzw", q[3:]))}

    documents = {
        "pairs.json": [[x.tolist(), y.tolist()] for x, y in zip(m_a, m_b)],
        "lists.json": {"meta": {"robot": "IRB1400"}, "robot_poses": encode(a, KUKA).tolist(),
                       "camera_poses": encode(b, ROTVEC, "m").tolist()},
        "ros.yaml": {"samples": [{"tool_pose": ros_pose(x), "marker_pose": ros_pose(y)} for x, y in zip(a, b)]},
        "kuka.yaml": {"poses": [{"id": k, "robot": dict(zip(["x", "y", "z", "a", "b", "c"], map(float, encode(x[None], KUKA)[0]))),
                                 "camera": {"rvec": encode(y[None], ROTVEC, "m")[0, 3:].tolist(),
                                            "tvec": encode(y[None], ROTVEC, "m")[0, :3].tolist()}}
                                for k, (x, y) in enumerate(zip(a, b))]},
        "numbered.yaml": {**{f"T_base_ee_{k}": {"rows": 4, "cols": 4, "data": x.ravel().tolist()} for k, x in enumerate(m_a)},
                          **{f"T_cam_target_{k}": {"rows": 4, "cols": 4, "data": y.ravel().tolist()}
                             for k, y in enumerate(m_b)}},
    }
    for name, document in documents.items():
        path = tmp_path / name
        if name.endswith(".json"):
            path.write_text(json.dumps(document))
        else:
            write_yaml(path, document)
        assert detect_format(path) == ("moveit" if name == "pairs.json" else "log"), name
        session = read_any(path)
        assert same_poses(session, a, b), name
        assert same_poses(read_any(path, format="log"), a, b), name


# --------------------------------------------------------------------------- the real sets in other forms

REAL = {
    "moveit-calibration": "pose_samples.json",
    "camodocal-ar-tag": "TransformPairsInput.yml",
    "visp-eye-in-hand": None,
    "ethz-robot-arm": None,
    "visp-apps-eye-in-hand": None,
}


@pytest.fixture(scope="module")
def real_poses():
    from helpers import shared_dataset

    out = {}
    for name, file in REAL.items():
        folder = shared_dataset(name)
        session = read_any(folder / file if file else folder)
        out[name] = (np.array([p.tool0_in_base for p in session.postures]),
                     np.array([p.target_in_camera for p in session.postures]), session.setup)
    return out


@pytest.mark.parametrize("name", list(REAL))
def test_real_sets_in_every_inversion_import_right_or_name_the_flag(tmp_path, real_poses, name):
    """Each real set written as a headerless CSV (KUKA robot, rotation-vector camera), with every
    inversion: imported to the same poses, or refused naming a flag that then reads it right."""
    tool0, target, setup = real_poses[name]
    truth = type("T", (), {"tool0": tool0, "target": target})
    outcomes = []
    for invert_robot, invert_camera in itertools.product((False, True), repeat=2):
        path = write_log(tmp_path / f"{name}_{invert_robot}_{invert_camera}.csv", truth, invert_robot=invert_robot,
                         invert_camera=invert_camera)
        got = read_or_refusal(path)
        if isinstance(got, str):
            got = read_any(path, **_flag_options(got, setup, invert_robot, invert_camera))
            outcomes.append("refused")
        else:
            outcomes.append("inferred")
        assert same_poses(got, tool0, target) and got.setup == setup, (invert_robot, invert_camera)
    if name != "ethz-robot-arm":  # the ETH target is seen head-on from a narrow cone: the only set that needs a flag
        assert outcomes == ["inferred"] * 4


def test_a_real_set_keeps_its_pose_through_the_log_reader(tmp_path, real_poses):
    """MoveIt's set written as ROS would (RPY radians and xyzw quaternions, metres): the same camera pose."""
    from handeye.calibration.solve import calibrate_session

    tool0, target, _ = real_poses["moveit-calibration"]
    native = calibrate_session(read_any(__import__("helpers").shared_dataset("moveit-calibration") / "pose_samples.json"),
                               "mcb")
    truth = type("T", (), {"tool0": tool0, "target": target})
    path = write_log(tmp_path / "ros.csv", truth, robot=ROS_RPY, robot_unit="m", camera=XYZW, invert_camera=True)
    result = calibrate_session(read_any(path), "mcb")
    assert np.max(np.abs(result.x - native.x)) < 1e-6


# --------------------------------------------------------------------------- wrong readings: never a wrong pose


def run_cli(capsys, *argv):
    from handeye.station import cli

    code = cli.main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def import_then_calibrate(capsys, tmp_path, source, *flags):
    """``handeye import`` then ``handeye calibrate --json``: (import exit, calibrate exit, ``(parent, X)`` or None,
    stderr lines)."""
    out = tmp_path / f"s{len(list(tmp_path.iterdir()))}"
    code, _, err = run_cli(capsys, "import", *([source] if not isinstance(source, list) else source), "-o", out, *flags)
    lines = err.strip().splitlines()
    if code != 0:
        assert code == 1 and len(lines) == 1 and "Traceback" not in err, err
        return code, None, None, lines
    result = tmp_path / f"{out.name}.json"
    code2, _, err2 = run_cli(capsys, "calibrate", out, "--method", "mcb", "--json", result, "--quiet")
    if code2 != 0:
        assert code2 == 1 and err2.count("\n") == 1 and "Traceback" not in err2, err2
        return code, code2, None, lines + [err2.strip()]
    pose = json.loads(result.read_text())["camera_pose"]
    from handeye.geometry.transforms import transform_from_pose

    return code, code2, (pose["parent"], transform_from_pose(pose["position_mm"], pose["quaternion_wxyz"])), lines


def same_pose(one, two) -> bool:
    """Two ``(parent, 4x4)`` camera poses are the same: the same parent frame, every entry within 1e-6."""
    return one[0] == two[0] and float(np.max(np.abs(one[1] - two[1]))) < 1e-6


WRONG_FLAGS = [  # (the unit the log is written in, the wrong flags)
    ("m", ("--robot-pose", "base_in_flange")),
    ("m", ("--camera-pose", "camera_in_target")),
    ("m", ("--setup", "{other}")),
    ("m", ("--robot-pose", "base_in_flange", "--camera-pose", "camera_in_target")),  # the exact twin: both inverted
    ("m", ("--setup", "{other}", "--camera-pose", "camera_in_target")),  # the other exact twin
    ("m", ("--setup", "{other}", "--robot-pose", "base_in_flange")),
    ("m", ("--euler", "robot:XYZ")),  # a wrong Euler order
    ("m", ("--euler", "robot:ZYX:rad")),  # degrees read as radians
    ("m", ("--units", "mm")),  # metres given as millimetres
    ("mm", ("--units", "m")),  # millimetres given as metres
]


@pytest.mark.parametrize("which", ["eih", "eth"])
def test_deliberately_wrong_readings_never_give_a_wrong_pose(tmp_path, capsys, eih, eth, which):
    """Every wrong flag: import warns with the numbers (or refuses), and then calibrate either refuses in
    one line or returns the same pose as the right reading; never exit 0 with another pose."""
    truth = truth_of(which, eih, eth)
    other = "eye_to_hand" if truth.setup == "eye_in_hand" else "eye_in_hand"
    sources, right = {}, {}
    for unit in ("m", "mm"):
        sources[unit] = write_log(tmp_path / f"log_{unit}.csv", truth, robot_unit=unit, camera_unit=unit)
        code, code2, right[unit], _ = import_then_calibrate(capsys, tmp_path, sources[unit])
        assert (code, code2) == (0, 0)
    assert same_pose(right["m"], right["mm"])
    for unit, flags in WRONG_FLAGS:
        flags = [f.format(other=other) for f in flags]
        code, code2, x, lines = import_then_calibrate(capsys, tmp_path, sources[unit], *flags)
        if code == 0 and code2 == 0:
            assert same_pose(x, right[unit]), (flags, lines)
        else:
            assert lines and any(flag in lines[-1] for flag in FLAGS + ("--units m", "metres", "units")), (flags, lines)
        if code == 0:
            assert any(flags[0] in line and "warning" in line for line in lines), (flags, lines)


def test_a_flag_the_data_contradict_is_a_warning_with_the_numbers(tmp_path, capsys, eih):
    source = write_log(tmp_path / "log.csv", eih)
    code, out, err = run_cli(capsys, "import", source, "-o", tmp_path / "s", "--camera-pose", "camera_in_target")
    assert code == 0
    warning = err.splitlines()[0]
    # with the board poses inverted the data fit only the eye-to-hand twin, where the board is behind the camera
    assert warning.startswith("handeye import: warning: --camera-pose camera_in_target: eye_to_hand, robot flange in "
                              "base (Euler ZYX rotating deg, mm), camera camera in target (rotation vector, m) is "
                              "implausible: the board is in front of the camera only as target in camera (board directions "
                              "spread ")
    assert "robot poses read as flange in base" in out and "camera poses read as camera in target" in out  # as told
    code, _, err = run_cli(capsys, "calibrate", tmp_path / "s")
    assert code == 1 and err.startswith("handeye calibrate: error: the board is behind the camera")
    code, _, err = run_cli(capsys, "import", source, "-o", tmp_path / "s2", "--setup", "eye_to_hand")
    assert code == 0 and err.startswith("handeye import: warning: --setup eye_to_hand: the poses do not fit it (angle gap")
    assert "axis misfit" in err and "while eye_in_hand, robot flange in base" in err
    code, _, err = run_cli(capsys, "calibrate", tmp_path / "s2")
    assert code == 1 and err.startswith("handeye calibrate: error: the robot and board poses fit no rigid camera mount")


def test_import_states_the_conventions_and_the_session_keeps_them(tmp_path, capsys, eih):
    from handeye.calibration.session import read_session

    source = write_log(tmp_path / "log.csv", eih, invert_camera=True)
    code, out, err = run_cli(capsys, "import", source, "-o", tmp_path / "s")
    assert code == 0 and err == ""
    assert ("robot:    robot poses read as flange in base, position in mm, Euler ZYX rotating axes in degrees"
            in out)
    assert ("camera:   camera poses read as camera in target, position in m converted to mm, rotation vector (axis x "
            "angle, radians)" in out)
    assert "decided:  by the X-free invariants of AX = XB, then plausibility" in out
    table = out[out.index("readings of the poses"):]
    assert "verdict" in table.splitlines()[1] and "chosen" in table and "does not fit" in table
    assert "not plausible: the camera" in table  # the both-inverted twin, told apart by the mount
    record = read_session(tmp_path / "s").extra["import"]
    assert record["conventions"]["camera"].startswith("camera poses read as camera in target")
    assert record["inference"]["candidates"][0]["verdict"] == "chosen"


def test_an_undecidable_log_is_refused_naming_the_flag(tmp_path, capsys, real_poses):
    """The ETH set (a target seen head-on from a narrow cone): camera in target with one set-up fits as
    well as target in camera with the other; nothing in a headerless file says which."""
    tool0, target, _ = real_poses["ethz-robot-arm"]
    truth = type("T", (), {"tool0": tool0, "target": target})
    source = write_log(tmp_path / "eth.csv", truth, invert_camera=True)
    code, out, err = run_cli(capsys, "import", source, "-o", tmp_path / "s")
    assert code == 1 and err.count("\n") == 1
    assert "the data fit 2 readings equally well" in err
    assert "pass --camera-pose or --setup to decide" in err
    assert not (tmp_path / "s").exists()
    # issue 40.4f: one line per reading, with the flags that choose it and the camera mount it gives
    choices = out.splitlines()[1:]
    assert len(choices) == 2 and all("--camera-pose" in c and "--setup" in c for c in choices), out
    eih = next(c for c in choices if "--setup eye_in_hand" in c)
    assert "--camera-pose camera_in_target" in eih and "camera in flange at (" in eih
    assert "camera in base at (" in next(c for c in choices if "--setup eye_to_hand" in c)
    code, out, err = run_cli(capsys, "import", source, "-o", tmp_path / "s", "--setup", "eye_in_hand")
    assert code == 0 and "camera poses read as camera in target" in out and err == ""
    from handeye.calibration.session import read_session
    from handeye.calibration.solve import calibrate_session

    x = calibrate_session(read_session(tmp_path / "s")).x  # the listed mount is the one this reading gives
    listed = [float(v) for v in eih.split("camera in flange at (")[1].split(")")[0].split(",")]
    assert np.linalg.norm(np.array(listed) - x[:3, 3]) < 10.0  # the linear fit: a yardstick, within mm


@pytest.mark.parametrize("invert_robot, invert_camera", [(False, False), (False, True), (True, True), (True, False)])
def test_the_issue_cases_in_the_plain_layout_calibrate_to_the_right_pose(tmp_path, capsys, eih, invert_robot,
                                                                         invert_camera):
    """Issue 11's reports, in the plain CSV layout (``target_*`` columns holding camera-in-marker poses,
    both sets inverted, ``tool0_*`` holding base-in-flange): on main they imported with a note or nothing
    and calibrated to a wrong pose with exit 0 (the board pose as the camera pose, a camera 1.14 m from
    the flange, d_org 229 mm). Now the same pose as the right file, or a refusal naming the flag."""
    header = ["index"] + [f"{p}_{c}" for p in ("tool0", "target") for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]
    robot, camera = encode(eih.tool0, WXYZ, invert=invert_robot), encode(eih.target, WXYZ, invert=invert_camera)
    source = tmp_path / "poses.csv"
    source.write_text(table_text(robot, camera, header=header, index=True))
    code, code2, x, lines = import_then_calibrate(capsys, tmp_path, source)
    assert code == 0 and code2 == 0, lines
    right = tmp_path / "right.csv"
    right.write_text(table_text(encode(eih.tool0, WXYZ), encode(eih.target, WXYZ), header=header, index=True))
    _, _, x_right, _ = import_then_calibrate(capsys, tmp_path, right)
    assert same_pose(x, x_right) and x[0] == "tool0"
    assert np.linalg.norm(x[1][:3, 3] - eih.x[:3, 3]) < 3.0  # and that is the true mount, within the noise


def test_random_logs_are_read_right_or_refused_naming_a_flag(tmp_path):
    """Random stations, noise (up to 15 mm, 0.2 deg per joint), posture counts (3 to 30), conventions per
    side, inversions and units: every log is read to the poses it was written from, or refused naming a
    flag; never read wrong."""
    import random

    from handeye.calibration.compact_points import compact_points_from_corners
    from handeye.calibration.synthetic import NoiseConfig, sample_session

    from helpers import scene

    conventions = [KUKA, FANUC, ROS_RPY, ROTVEC, WXYZ, XYZW, MATRIX16, RVEC_TVEC,
                   PoseConvention("euler", sequence="zxz", degrees=True), PoseConvention("euler", sequence="YZY"),
                   PoseConvention("matrix", "column", width=12)]
    rng = random.Random(11)
    counts = {"right": 0, "refused": 0}
    for trial in range(40):
        setup = rng.choice(["eye_in_hand", "eye_to_hand"])
        sc = scene(30, setup, 0)
        noise = NoiseConfig(sigma_cam_mm=rng.choice([0.0, 1.0, 5.0, 15.0]), sigma_rob_deg=rng.choice([0.0, 0.05, 0.2]),
                            seed=trial)
        session = sample_session(sc, noise)
        keep = sorted(rng.sample(range(30), rng.choice([3, 5, 8, 15, 30])))
        tool0 = np.array([session.postures[i].tool0_in_base for i in keep])
        target = compact_points_from_corners(np.array([session.postures[i].points_mm for i in keep]), sc.board).target2cam
        path = tmp_path / f"log{trial}.csv"
        path.write_text(table_text(encode(tool0, rng.choice(conventions), rng.choice(["m", "mm"]), rng.random() < 0.5),
                                   encode(target, rng.choice(conventions), rng.choice(["m", "mm"]), rng.random() < 0.5)))
        got = read_or_refusal(path) if len(keep) > 3 else None
        if len(keep) == 3:  # three postures leave 3 pairs: a refusal may name no flag, only the posture count
            try:
                got = read_any(path)
            except SessionError as exc:
                got = str(exc)
        if isinstance(got, str):
            counts["refused"] += 1
            continue
        assert same_poses(got, tool0, target) and got.setup == setup, (trial, got.extra["import"]["conventions"])
        counts["right"] += 1
    assert counts["right"] >= 30, counts
