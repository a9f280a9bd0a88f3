"""Synthetic hand-eye logs written in the layouts other tools use, with random words, separators and decoys.

:func:`station` draws a station in milliseconds (no inverse kinematics: the camera views are
sampled about the board and the flange follows from the mount), and :func:`write_log` writes it in
one of :data:`LAYOUTS`, with random tag words and case, separators, orders, units, rotation
conventions, pose directions and decoys (comment lines, a result matrix, joint lists, extra
columns). The import must give back the truth or refuse naming a flag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.geometry.transforms import invert_transforms

LAYOUTS = ("tag_rows", "p_and_c", "matrix_rows", "matrix_sections", "two_files", "image_rows", "extra_columns")
ROBOT_TAGS = ("hand", "robot", "tcp", "flange", "Robot Pose", "ROBOT", "arm")
CAMERA_TAGS = ("eye", "camera", "cam", "marker", "Camera", "EYE", "target")
NEUTRAL_TAGS = ("alpha", "beta", "set a", "set b", "gamma", "delta")
SEPARATORS = (",", " ", "\t", "; ", " | ")


@dataclass
class Station:
    """True poses: ``tool0 (n, 4, 4)`` flange in base, ``target (n, 4, 4)`` board in camera (mm), the mount."""

    setup: str
    tool0: np.ndarray
    target: np.ndarray
    x: np.ndarray
    joints: np.ndarray


def _pose(rotation: np.ndarray, translation) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rotation, translation
    return m


def _views(rng, n: int, board2world: np.ndarray) -> np.ndarray:
    """Camera poses (camera in world) looking at the board centre from its printed side."""
    out = []
    centre = board2world[:3, 3]
    normal = -board2world[:3, 2]  # target z points into the board, away from the camera
    for _ in range(n):
        tilt = np.radians(35.0) * np.sqrt(rng.uniform())
        az = rng.uniform(0, 2 * np.pi)
        axis = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis)
        axis = Rotation.from_rotvec(az * normal).apply(axis)
        direction = Rotation.from_rotvec(tilt * axis).apply(normal)
        position = centre + rng.uniform(600, 1200) * direction + rng.normal(0, 40, 3)
        z = centre + rng.normal(0, 60, 3) - position
        z /= np.linalg.norm(z)
        x = np.cross([0.0, 0.0, 1.0], z)
        x /= np.linalg.norm(x)
        r = np.stack([x, np.cross(z, x), z], axis=1) @ Rotation.from_rotvec([0, 0, rng.uniform(-0.7, 0.7)]).as_matrix()
        out.append(_pose(r, position))
    return np.array(out)


def station(seed: int, n: int = 12, setup: str | None = None, sigma_mm: float = 0.3) -> Station:
    """A noisy station of ``n`` postures (board poses with ``sigma_mm`` and 0.05 deg of noise)."""
    rng = np.random.default_rng(seed)
    setup = setup or ("eye_in_hand" if rng.uniform() < 0.6 else "eye_to_hand")
    if setup == "eye_in_hand":
        x = _pose(Rotation.from_rotvec(rng.normal(0, 0.3, 3)).as_matrix(), rng.uniform(-150, 150, 3))
        board = _pose(Rotation.from_euler("xyz", [180, 0, rng.uniform(-30, 30)], degrees=True).as_matrix(),
                      [rng.uniform(700, 1000), rng.uniform(-200, 200), rng.uniform(0, 200)])
        cams = _views(rng, n, board)
        tool0 = cams @ invert_transforms(x)
        target = invert_transforms(cams) @ board
    else:
        x = _pose(Rotation.from_euler("xyz", [-120, 0, 90 + rng.uniform(-20, 20)], degrees=True).as_matrix(),
                  [rng.uniform(1500, 1900), rng.uniform(-800, 800), rng.uniform(1000, 1400)])
        on_flange = _pose(Rotation.from_rotvec(rng.normal(0, 0.2, 3)).as_matrix(), [0, 0, rng.uniform(40, 90)])
        cam_in_board = _views(rng, n, np.eye(4))  # cameras on the board's -z side: z into the board
        board_in_cam = invert_transforms(cam_in_board)
        target = board_in_cam
        tool0 = x @ board_in_cam @ invert_transforms(on_flange)
        # keep the flange at a plausible distance from the base: the camera looks at the work zone
    noise = np.array([_pose(Rotation.from_rotvec(rng.normal(0, np.radians(0.05), 3)).as_matrix(),
                            rng.normal(0, sigma_mm, 3)) for _ in range(n)])
    joints = rng.uniform(-120, 120, (n, 6))
    return Station(setup, tool0, target @ noise, x, joints)


def encode(poses, kind: str, unit: str, invert: bool) -> np.ndarray:
    """Rows ``(n, width)`` of ``poses`` (mm) written as ``kind`` (kuka, fanuc, rotvec, wxyz, xyzw, m16, m12)."""
    poses = invert_transforms(poses) if invert else np.array(poses, float)
    t = poses[:, :3, 3] / (1000.0 if unit == "m" else 1.0)
    r = Rotation.from_matrix(poses[:, :3, :3])
    if kind == "kuka":
        return np.hstack([t, r.as_euler("ZYX", degrees=True)])
    if kind == "fanuc":
        return np.hstack([t, r.as_euler("xyz", degrees=True)])
    if kind == "rotvec":
        return np.hstack([t, r.as_rotvec()])
    if kind in ("wxyz", "xyzw"):
        return np.hstack([t, r.as_quat(scalar_first=kind == "wxyz")])
    m = poses.copy()
    m[:, :3, 3] = t
    return m.reshape(len(m), 16) if kind == "m16" else m[:, :3, :].reshape(len(m), 12)


def _num(v: float) -> str:
    return f"{v:.10g}"


def _row(values, sep: str) -> str:
    return sep.join(_num(v) for v in values)


def _matrix_lines(values, sep: str, rows: int) -> list:
    m = np.asarray(values, float).reshape(-1, 4)
    if rows == 4 and len(m) == 3:
        m = np.vstack([m, [0, 0, 0, 1]])
    return [_row(r, sep) for r in m[:rows]]


@dataclass
class Written:
    """What was written: the paths to import, and what the truth is (for the test's comparison)."""

    paths: list
    layout: str
    words: str


def _tags(rng, named: bool) -> tuple:
    if named:
        a, b = ROBOT_TAGS[rng.integers(len(ROBOT_TAGS))], CAMERA_TAGS[rng.integers(len(CAMERA_TAGS))]
    else:
        a, b = rng.choice(NEUTRAL_TAGS, 2, replace=False)
    return str(a), str(b)


def write_log(folder, st: Station, layout: str, seed: int) -> Written:
    """Write ``st`` in ``layout`` with random words, separators, conventions and decoys."""
    rng = np.random.default_rng(seed)
    sep = SEPARATORS[rng.integers(len(SEPARATORS))]
    unit = "m" if rng.uniform() < 0.4 else "mm"
    inv_r, inv_c = bool(rng.uniform() < 0.25), bool(rng.uniform() < 0.25)
    six, seven = ("kuka", "fanuc", "rotvec"), ("wxyz", "xyzw")
    lines = [f"# hand-eye log written by tool {rng.integers(100)}"] if rng.uniform() < 0.7 else []
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"log{seed}.txt"
    if layout == "tag_rows":
        kr, kc = rng.choice(six + seven), rng.choice(six + seven + ("m16",))
        rob, cam = encode(st.tool0, kr, unit, inv_r), encode(st.target, kc, unit, inv_c)
        ta, tb = _tags(rng, rng.uniform() < 0.5)
        colon = ":" if rng.uniform() < 0.5 else ""
        rows_a = [f"{ta}{colon}{sep}{_row(v, sep)}" for v in rob]
        rows_b = [f"{tb}{colon}{sep}{_row(v, sep)}" for v in cam]
        if rng.uniform() < 0.5:
            body = [x for pair in zip(rows_a, rows_b) for x in pair]
        else:
            body = rows_a + rows_b
        if rng.uniform() < 0.5:  # decoy: joint lists under their own tag
            body += [f"joints{sep}{_row(j, sep)}" for j in st.joints]
        lines += body
        words = f"{ta}/{tb} {kr}/{kc}"
    elif layout == "p_and_c":
        kr = rng.choice(six)
        rob, cam = encode(st.tool0, kr, unit, inv_r), encode(st.target, "m12", unit, inv_c)
        p, c = ("P", "C") if rng.uniform() < 0.5 else ("p", "c")
        for a, b in zip(rob, cam):
            lines.append(f"{p} {_row(a, ' ')}")
            lines += [f"{c} {line}" for line in _matrix_lines(b, " ", 3)]
        words = f"P/C {kr}"
    elif layout in ("matrix_rows", "matrix_sections"):
        rows = int(rng.choice((3, 4)))
        rob, cam = encode(st.tool0, "m16", unit, inv_r), encode(st.target, "m16", unit, inv_c)
        blank = rng.uniform() < 0.5
        if layout == "matrix_rows":
            for a, b in zip(rob, cam):
                for m in (a, b):
                    lines += _matrix_lines(m, sep, rows) + ([""] if blank else [])
        else:
            for name, block in (("# robot poses" if rng.uniform() < 0.5 else "# list 1", rob),
                                ("# camera poses" if rng.uniform() < 0.5 else "# list 2", cam)):
                lines += [name] if rng.uniform() < 0.5 else []
                lines.append(str(len(block)))
                for m in block:
                    lines += _matrix_lines(m, sep, rows) + ([""] if blank else [])
        if rng.uniform() < 0.5:  # decoy: the tool's own result matrix
            lines += ["# result", *_matrix_lines(np.eye(4).ravel(), sep, 4)]
        words = f"{rows}-row matrices"
    elif layout == "two_files":
        kr, kc = rng.choice(six + seven), rng.choice(six + seven + ("m16",))
        names = ["poses_1.txt", "poses_2.txt"]
        files = [folder / f"s{seed}" / n for n in names]
        files[0].parent.mkdir(parents=True, exist_ok=True)
        order = rng.uniform() < 0.5
        for f, (poses, kind, inv) in zip(files, ((st.tool0, kr, inv_r), (st.target, kc, inv_c))[:: 1 if order else -1]):
            f.write_text("\n".join(lines + [_row(v, sep) for v in encode(poses, kind, unit, inv)]) + "\n")
        return Written([files[0].parent], layout, f"{kr}/{kc} robot {'first' if order else 'second'}")
    elif layout == "image_rows":
        kr = rng.choice(six + seven)
        rob = encode(st.tool0, kr, unit, inv_r)
        cam = invert_transforms(st.target) if inv_c else st.target
        sub = folder / f"s{seed}"
        sub.mkdir(parents=True, exist_ok=True)
        (sub / "robot_poses.txt").write_text("\n".join(_row(v, sep) for v in rob) + "\n")
        calib = []
        for k, m in enumerate(cam):
            k_matrix = [1210.5, 0, 640.2, 0, 1208.7, 480.9, 0, 0, 1]
            t = m[:3, 3] / (1000.0 if unit == "m" else 1.0)
            dist = rng.normal(0, 0.05, 5)
            calib.append(" ".join([f"image{k}.png"] + [_num(v) for v in (*k_matrix, *m[:3, :3].ravel(), *t, *dist)]))
        (sub / "calibration.txt").write_text("\n".join(["# image fx 0 cx 0 fy cy 0 0 1 R t k"] + calib) + "\n")
        return Written([sub / "robot_poses.txt", sub / "calibration.txt"], layout, f"images {kr}")
    else:  # extra_columns: index, robot pose, camera pose, then joints as decoy columns
        kr, kc = rng.choice(six + seven), rng.choice(seven + ("m16",))
        rob, cam = encode(st.tool0, kr, unit, inv_r), encode(st.target, kc, unit, inv_c)
        for k, (a, b, j) in enumerate(zip(rob, cam, st.joints)):
            lines.append(sep.join([str(k)] + [_num(v) for v in (*a, *b, *j[:3])]))
        words = f"{kr}/{kc} + 3 extra"
    path.write_text("\n".join(lines) + "\n")
    return Written([path], layout, words)


def same_as_truth(session, st: Station, tol_mm: float = 0.05, tol_rot: float = 1e-4) -> bool:
    """The session holds the station's poses (flange in base, board in camera) and its set-up."""
    a = np.array([p.tool0_in_base for p in session.postures])
    b = np.array([p.target_in_camera for p in session.postures])
    if a.shape != st.tool0.shape or session.setup != st.setup:
        return False
    return all(np.max(np.abs(p[:, :3, :3] - q[:, :3, :3])) < tol_rot and np.max(np.abs(p[:, :3, 3] - q[:, :3, 3])) < tol_mm
               for p, q in ((a, st.tool0), (b, st.target)))
