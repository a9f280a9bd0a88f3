"""Hand-eye logs in the structures other tools write (XML-like state lines, section headers, comment
headers, folders of per-posture files with decoys beside them), generated from a known station.

Each writer takes a :class:`layout_logs.Station` and a seed (the words, element and attribute
names, conventions and decoys are drawn from it) and returns the paths to import; the test then
checks that the import recovers the station's poses and its mount X.
"""

from __future__ import annotations

import json

import numpy as np

from handeye.calibration.solve import calibrate_session
from handeye.geometry.transforms import invert_transforms
from layout_logs import encode

#: Attribute names of a 6-number pose (position, then Euler angles) as controllers write them.
POSE_ATTRIBUTES = (tuple("XYZABC"), ("x", "y", "z", "rx", "ry", "rz"), ("X", "Y", "Z", "W", "P", "R"))
ROBOT_HEADERS = ("Robot TCP Position:", "Flange pose", "TCP in base frame:", "Tool pose [mm]:")
CAMERA_HEADERS = ("Camera Position in Marker Coordinate Space:", "Marker pose in camera:", "Board in camera frame")


def _num(v: float) -> str:
    return f"{v:.6f}"


def matrix_lines(m, indent: str = "") -> list:
    """A 4x4 matrix printed over four lines."""
    return [indent + " ".join(_num(v) for v in row) for row in np.asarray(m, float).reshape(4, 4)]


def state_log(folder, st, seed: int, robot_matrix: bool = False) -> list:
    """A controller state log: per posture an XML-like element carrying the flange pose as attributes
    (Euler angles, KUKA or Fanuc), joint values as another element (not a pose), non-numeric
    attributes, and the board printed as a 4x4 matrix under a section header (camera in marker or
    marker in camera); with ``robot_matrix`` the flange also as a matrix under its own header."""
    rng = np.random.default_rng(seed)
    names = POSE_ATTRIBUTES[rng.integers(len(POSE_ATTRIBUTES))]
    kind = "fanuc" if names[3] == "W" else str(rng.choice(("kuka", "fanuc")))
    unit = "m" if rng.uniform() < 0.3 else "mm"
    robot = encode(st.tool0, kind, unit, False)
    invert = bool(rng.uniform() < 0.5)
    camera = invert_transforms(st.target) if invert else st.target
    element = str(rng.choice(("Position", "TCP", "RobotPos", "Pose")))
    header = CAMERA_HEADERS[0] if invert else CAMERA_HEADERS[1 + rng.integers(2)]
    lines = [f"Controller state log, seed {seed}", ""]
    for k, (pose, cam) in enumerate(zip(robot, camera)):
        lines.append(f'<RobotState Seq="{k}" Mode="AUTO" Time="2024-05-0{1 + k % 9}T12:00:{k:02d}">')
        lines.append(f"  <{element} " + " ".join(f'{n}="{v:.5f}"' for n, v in zip(names, pose)) + " />")
        joints = " ".join(f'A{j + 1}="{v:.3f}"' for j, v in enumerate(st.joints[k]))
        lines.append(f"  <Joints {joints} />")
        lines.append("</RobotState>")
        if robot_matrix:
            tool0 = st.tool0[k].copy()
            tool0[:3, 3] /= 1000.0 if unit == "m" else 1.0
            lines += [ROBOT_HEADERS[rng.integers(len(ROBOT_HEADERS))]] + matrix_lines(tool0, "  ")
        c = cam.copy()
        c[:3, 3] /= 1000.0 if unit == "m" else 1.0
        lines += [header] + matrix_lines(c, "  ") + [""]
    path = folder / f"state{seed}.log"
    path.write_text("\n".join(lines) + "\n")
    return [path]


def recovers_x(session, st, tol_mm: float = 2.0, tol_deg: float = 0.3) -> bool:
    """The session, solved, gives the station's mount X (within ``tol_mm`` and ``tol_deg``)."""
    x = calibrate_session(session).x
    d_t = float(np.linalg.norm(x[:3, 3] - st.x[:3, 3]))
    cos = (np.trace(x[:3, :3].T @ st.x[:3, :3]) - 1) / 2
    return d_t < tol_mm and float(np.degrees(np.arccos(np.clip(cos, -1, 1)))) < tol_deg and session.setup == st.setup


def dump_json(path, data) -> None:
    path.write_text(json.dumps(data, indent=1))


def commented_log(folder, st, seed: int) -> list:
    """Tagged rows (``P`` + a 6-number pose, three ``C`` rows of a 3x4 matrix, or two tags of 6/7
    numbers) under comment lines naming the columns, with colons (``# P: X Y Z A B C``) or without."""
    rng = np.random.default_rng(seed)
    kind = str(rng.choice(("kuka", "fanuc")))
    unit = "m" if rng.uniform() < 0.3 else "mm"
    robot = encode(st.tool0, kind, unit, False)
    colon = ":" if rng.uniform() < 0.7 else ""
    lines = [f"# recorded: 2024-05-0{1 + seed % 9} 12:00", f"# units{colon} {unit}, angles: deg"]
    names = "X Y Z A B C" if kind == "kuka" else "X Y Z W P R"
    if rng.uniform() < 0.5:
        camera = encode(st.target, "m12", unit, False)
        tags = ("P", "C") if rng.uniform() < 0.5 else ("pose", "cam")
        lines += [f"# {tags[0]}{colon} {names}", f"# {tags[1]}{colon} r11 r12 r13 tx (three rows: the marker in the camera)"]
        for a, b in zip(robot, camera):
            lines.append(f"{tags[0]} " + " ".join(_num(v) for v in a))
            lines += [f"{tags[1]} " + " ".join(_num(v) for v in b[4 * i:4 * i + 4]) for i in range(3)]
    else:
        camera = encode(st.target, "wxyz", unit, False)
        lines += [f"# robot{colon} {names}", f"# marker{colon} x y z qw qx qy qz"]
        for a, b in zip(robot, camera):
            lines += ["robot " + " ".join(_num(v) for v in a), "marker " + " ".join(_num(v) for v in b)]
    path = folder / f"commented{seed}.txt"
    path.write_text("\n".join(lines) + "\n")
    return [path]


def _png(path) -> None:
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))


def side_files_folder(folder, st, seed: int) -> list:
    """A folder holding one text file per side, the tool's own result (one 4x4 matrix, in a ``.txt``
    or ``.yaml``) and a settings ``.ini``: the folder imports, the result and settings are skipped."""
    from layout_logs import encode as enc

    rng = np.random.default_rng(seed)
    sub = folder / f"run{seed}"
    sub.mkdir(parents=True, exist_ok=True)
    kind_r, kind_c = str(rng.choice(("kuka", "wxyz", "m16"))), str(rng.choice(("rotvec", "xyzw", "m16")))
    names = (("robot_poses.txt", "camera_poses.txt"), ("tcp.csv", "marker.csv"), ("hand.txt", "eye.txt"))[seed % 3]
    sep = "," if names[0].endswith(".csv") else " "
    for name, values in zip(names, (enc(st.tool0, kind_r, "mm", False), enc(st.target, kind_c, "mm", False))):
        (sub / name).write_text("\n".join(sep.join(_num(v) for v in row) for row in values) + "\n")
    if rng.uniform() < 0.5:
        (sub / "result.txt").write_text("# hand-eye result\n" + "\n".join(matrix_lines(st.x)) + "\n")
    else:
        (sub / "calibration_result.yaml").write_text(
            "camera_to_tool: " + json.dumps(np.round(st.x, 6).tolist()) + "\nresidual_mm: 0.42\n")
    (sub / "settings.ini").write_text("[capture]\nexposure=12000\npostures=12\nspeed=100\n")
    return [sub]


def posture_files_folder(folder, st, seed: int) -> list:
    """A capture tool's folder: one JSON (or YAML) per posture holding the flange pose as a 4x4 stored
    row-major (flat 16 or nested), the board pose as OpenCV ``rvec`` / ``tvec`` nested 3x1 lists
    (``[[x], [y], [z]]``), joint values beside them (not a pose), an image per posture, the tool's
    result and a settings file."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    sub = folder / f"capture{seed}"
    sub.mkdir(parents=True, exist_ok=True)
    yaml_files = seed % 3 == 2
    flat = rng.uniform() < 0.5
    robot_key = str(rng.choice(("robot_pose", "T_base_tcp", "pose", "flange")))
    for k in range(st.tool0.shape[0]):
        m = st.tool0[k]
        rvec = Rotation.from_matrix(st.target[k][:3, :3]).as_rotvec()
        doc = {"id": k, "stamp": 1700000000.0 + 3.5 * k,
               robot_key: (m.ravel().tolist() if flat else m.tolist()),
               "board": {"rvec": [[float(v)] for v in rvec], "tvec": [[float(v)] for v in st.target[k][:3, 3]]},
               "joints": [float(v) for v in st.joints[k]], "corners_found": 88}
        stem = f"pose_{k:03d}" if seed % 2 else f"{k:03d}"
        if yaml_files:
            import yaml

            (sub / f"{stem}.yaml").write_text(yaml.safe_dump(doc))
        else:
            dump_json(sub / f"{stem}.json", doc)
        _png(sub / f"{stem}.png")
    dump_json(sub / "handeye_result.json", {"cam2gripper": np.round(st.x, 6).tolist(), "rms": 0.3})
    (sub / "settings.ini").write_text("[camera]\nserial=1234\n")
    return [sub]
