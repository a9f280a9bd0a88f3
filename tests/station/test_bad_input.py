"""Bad input never gives a traceback, a hang or a half-written file: one line on stderr starting with
``handeye CMD: error:``, exit status 1, and nothing lost.

The classes: files that are not UTF-8, folders and named pipes where a file is expected, files too
large to be an input, values that cannot be lengths or joint angles, posture indices outside the
NNN.yaml naming, solvers failing inside numpy, and output places that cannot be written (a path
under a regular file, permission denied, a full disk). The tests run as root in CI, and root ignores
file permissions: "permission denied" is produced in-process by making the OS call raise it, and
the subprocess test writes under a regular file, which fails for root too.
"""

from __future__ import annotations

import errno
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from handeye.base import files
from handeye.base.errors import CalibrationError, OutputError, SessionError
from handeye.base.files import make_folder, read_text_file, write_text_atomic
from handeye.calibration.session import create_session, read_session, write_posture
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.drivers.camera.errors import StereoModelError
from handeye.drivers.camera.stereo import load_stereo_model, nominal_xb3_model, save_stereo_model
from handeye.station.cli import main

from helpers import scene

NOT_UTF8 = b"format: handeye-session/1\nnote: caf\xe9 \xff\n"


# --------------------------------------------------------------------------- helpers


def one_line_error(capsys, argv, pattern: str) -> str:
    """Run ``handeye argv`` in-process: exit 1, exactly one stderr line ``handeye CMD: error: ...`` matching."""
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert code == 1, err
    assert "Traceback" not in err
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"handeye {argv[0]}: error: "), lines[0]
    assert re.search(pattern, lines[0]), lines[0]
    return lines[0]


@pytest.fixture
def session(tmp_path):
    """A good 8-posture eye-in-hand session with corner points (mm)."""
    path = tmp_path / "session"
    data = sample_session(scene(8), NoiseConfig(sigma_cam_mm=0.5, seed=3))
    create_session(path, data)
    for posture in data.postures:
        write_posture(path, posture)
    return path


def edit_posture(session: Path, index: int, edit) -> None:
    file = session / "postures" / f"{index:03d}.yaml"
    data = yaml.safe_load(file.read_text())
    edit(data)
    file.write_text(yaml.safe_dump(data))


@pytest.fixture
def no_hang():
    """Fail (instead of hanging) when a reader blocks on a named pipe: SIGALRM after 10 s."""
    def timeout(signum, frame):
        raise TimeoutError("the reader blocked: a named pipe was opened for reading")

    previous = signal.signal(signal.SIGALRM, timeout)
    signal.alarm(10)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


def fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def stereo_file(tmp_path) -> Path:
    path = tmp_path / "stereo.yaml"
    save_stereo_model(path, nominal_xb3_model())
    return path


def images(tmp_path) -> tuple[Path, Path]:
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    left.write_bytes(b"\x89PNG")
    right.write_bytes(b"\x89PNG")
    return left, right


# --------------------------------------------------------------------------- what each command reads

def _session_yaml(session, tmp_path, content):
    target = session / "session.yaml"
    target.unlink()
    return target, ["calibrate", session]


def _posture(session, tmp_path, content):
    target = session / "postures" / "003.yaml"
    target.unlink()
    return target, ["calibrate", session]


def _config(session, tmp_path, content):
    return tmp_path / "station.yaml", ["capture", "--config", tmp_path / "station.yaml", "--session", tmp_path / "new"]


def _thresholds(session, tmp_path, content):
    return tmp_path / "quality.yaml", ["calibrate", session, "--thresholds", tmp_path / "quality.yaml"]


def _import_source(session, tmp_path, content):
    return tmp_path / "poses.csv", ["import", tmp_path / "poses.csv", "-o", tmp_path / "imported", "--format", "plain"]


def _stereo(session, tmp_path, content):
    left, right = images(tmp_path)
    return tmp_path / "head.yaml", ["triangulate", "--left", left, "--right", right, "--stereo", tmp_path / "head.yaml"]


READERS = {
    "session.yaml": (_session_yaml, "session file"),
    "posture file": (_posture, "posture file"),
    "station config": (_config, "station configuration"),
    "thresholds": (_thresholds, "thresholds file"),
    "import source": (_import_source, "input file"),
    "stereo model": (_stereo, "stereo model"),
}


@pytest.mark.parametrize("name", READERS)
def test_non_utf8_files_name_the_byte_and_say_save_as_utf8(name, session, tmp_path, capsys):
    setup, what = READERS[name]
    target, argv = setup(session, tmp_path, NOT_UTF8)
    target.write_bytes(NOT_UTF8)
    offset = NOT_UTF8.index(b"\xe9")
    one_line_error(capsys, argv, rf"{what} .*{target.name} is not UTF-8 text \(byte 0xe9 at offset {offset}\): "
                                 r"save it as UTF-8$")
    assert not (tmp_path / "new").exists() and not (tmp_path / "imported").exists()


@pytest.mark.parametrize("name", READERS)
def test_a_folder_where_a_file_is_expected(name, session, tmp_path, capsys):
    setup, what = READERS[name]
    target, argv = setup(session, tmp_path, None)
    target.mkdir()
    one_line_error(capsys, argv, rf"{what} .*{target.name} is a folder, not a file; give the file itself$")


@pytest.mark.parametrize("name", READERS)
def test_a_named_pipe_is_refused_without_blocking(name, session, tmp_path, capsys, no_hang):
    setup, what = READERS[name]
    target, argv = setup(session, tmp_path, None)
    fifo(target)
    one_line_error(capsys, argv, rf"{what} .*{target.name} is a named pipe \(FIFO\), not a regular file; "
                                 r"give a regular file$")


@pytest.mark.parametrize("name", ["session.yaml", "station config", "thresholds", "import source"])
def test_files_over_64_mb_are_refused(name, session, tmp_path, capsys):
    setup, what = READERS[name]
    target, argv = setup(session, tmp_path, None)
    with open(target, "wb") as handle:  # sparse: costs no disk
        handle.truncate(65 * 2**20)
    one_line_error(capsys, argv, rf"{what} .*{target.name} is 65 MB; files over 64 MB are refused: is it the right "
                                 r"file\?$")


def test_import_detection_refuses_a_named_pipe(tmp_path, capsys, no_hang):
    one_line_error(capsys, ["import", fifo(tmp_path / "poses.json"), "-o", tmp_path / "out"],
                   r"input file .*poses.json is a named pipe \(FIFO\)")


def test_load_stereo_model_refuses_a_folder_a_pipe_and_non_utf8(tmp_path, no_hang):
    (tmp_path / "folder.yaml").mkdir()
    with pytest.raises(StereoModelError, match="is a folder, not a file"):
        load_stereo_model(tmp_path / "folder.yaml")
    with pytest.raises(StereoModelError, match=r"named pipe \(FIFO\)"):
        load_stereo_model(fifo(tmp_path / "pipe.yaml"))
    good = stereo_file(tmp_path).read_bytes()
    (tmp_path / "latin1.yaml").write_bytes(good.replace(b"%YAML:1.0\n", b"%YAML:1.0\n# Kamera f\xfcr Zelle 3\n"))
    with pytest.raises(StereoModelError, match=r"latin1.yaml is not UTF-8 text \(byte 0xfc at offset 20\)"):
        load_stereo_model(tmp_path / "latin1.yaml")
    assert load_stereo_model(tmp_path / "stereo.yaml").image_size == (1280, 960)


DAMAGED_BASE64 = ("%YAML:1.0\n---\nT1_0: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n"
                  "   data: [ 1.0, 0.0, 0.0,!!binary AAAA -1.0, 0.2, 0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0 ]\n")


@pytest.mark.parametrize("command", ["import", "triangulate"])
def test_a_damaged_base64_filestorage_does_not_hang_opencv(command, tmp_path):
    """OpenCV's YAML reader loops forever in C++ on this file (no signal reaches Python): run the real
    command with a timeout, so a regression fails instead of hanging the suite."""
    file = tmp_path / "pairs.yml"
    file.write_text(DAMAGED_BASE64)
    if command == "import":
        argv = ["import", file, "-o", tmp_path / "out", "--format", "opencv"]
    else:
        left, right = images(tmp_path)
        argv = ["triangulate", "--left", left, "--right", right, "--stereo", file]
    out = subprocess.run([str(Path(sys.executable).with_name("handeye")), *map(str, argv)], capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 1 and "Traceback" not in out.stderr and out.stderr.count("\n") == 1, out.stderr
    assert re.match(rf"handeye {command}: error: .*pairs.yml: line 7 holds a base64 \(!!binary\) value, which "
                    r"OpenCV's reader can loop forever on; save the file without FileStorage.BASE64", out.stderr)


def test_the_real_command_on_a_named_pipe(tmp_path):
    """The console script itself: one line, exit 1, no traceback, and it returns (no hang)."""
    pipe = fifo(tmp_path / "quality.yaml")
    command = Path(sys.executable).with_name("handeye")
    out = subprocess.run([str(command), "calibrate", str(tmp_path), "--thresholds", str(pipe)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 1
    assert "Traceback" not in out.stderr and out.stderr.count("\n") == 1, out.stderr
    assert out.stderr.startswith("handeye calibrate: error: thresholds file") and "named pipe" in out.stderr


# --------------------------------------------------------------------------- the reading helper itself

def test_read_text_file_explains_utf16_binary_and_accepts_a_bom(tmp_path):
    (tmp_path / "notepad.yaml").write_bytes("a: 1\n".encode("utf-16"))
    with pytest.raises(SessionError, match=r"notepad.yaml is UTF-16 text: save it as UTF-8$"):
        read_text_file(tmp_path / "notepad.yaml", "posture file")
    (tmp_path / "image.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR")
    with pytest.raises(SessionError, match=r"image.yaml is a binary file, not text \(byte 0x89 at offset 0\)"):
        read_text_file(tmp_path / "image.yaml", "posture file")
    (tmp_path / "bom.yaml").write_bytes(b"\xef\xbb\xbfa: 1\n")
    assert read_text_file(tmp_path / "bom.yaml") == "a: 1\n"
    (tmp_path / "late.yaml").write_bytes(b"\xef\xbb\xbfa: \xff\n")
    with pytest.raises(SessionError, match=r"byte 0xff at offset 6"):
        read_text_file(tmp_path / "late.yaml")


def test_read_text_file_permission_missing_and_odd_names(tmp_path, monkeypatch):
    file = tmp_path / "config.yaml"
    file.write_text("a: 1\n")

    def denied(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied", str(file))

    monkeypatch.setattr(files.os, "open", denied)
    with pytest.raises(SessionError, match=r"^cannot read station configuration .*config.yaml: permission denied; "
                                           r"make it readable"):
        read_text_file(file, "station configuration")
    monkeypatch.undo()
    with pytest.raises(SessionError, match=r"^station configuration .*nothere.yaml not found$"):
        read_text_file(tmp_path / "nothere.yaml", "station configuration")
    with pytest.raises(SessionError, match=r"not found \(a part of the path is a file, not a folder\)"):
        read_text_file(file / "below.yaml", "station configuration")
    with pytest.raises(SessionError, match="is not a valid file name"):
        read_text_file(str(tmp_path / "a\0b.yaml"), "station configuration")
    with pytest.raises(SessionError, match="is a device, not a regular file"):
        read_text_file("/dev/zero", "station configuration")


# --------------------------------------------------------------------------- values that cannot be right


@pytest.mark.parametrize("edit, pattern", [
    (lambda d: d["tool0_in_base"]["position_mm"].__setitem__(0, 1e300),
     r"posture 2 \(postures/002.yaml\): tool0_in_base.position_mm holds 1e\+300 at \[0\]; lengths are millimetres "
     r"within ±1e7 mm \(10 km\): is the unit right\?$"),
    (lambda d: d["points_mm"][5].__setitem__(2, -2e7),
     r"posture 2 \(postures/002.yaml\): points_mm holds -2e\+07 at \[5, 2\]; lengths are millimetres"),
    (lambda d: d["joints_deg"].__setitem__(1, 1e4),
     r"posture 2 \(postures/002.yaml\): joints_deg holds 10000 at \[1\]; joint angles are degrees within ±720$"),
    (lambda d: d.update(points_mm=[[1, 2, 3]] * 103 + [[1, True, 3]]),
     r"posture 2 \(postures/002.yaml\): points_mm holds True, not a number$"),
    (lambda d: d["tool0_in_base"].update(position_mm=[1, 2, 10**400]),
     r"tool0_in_base.position_mm holds a number too large for a float$"),
    (lambda d: d.update(index=-3), r"^handeye calibrate: error: postures/002.yaml: index must be 0..9999 "
                                   r"\(the NNN of postures/NNN.yaml\); got -3$"),
    (lambda d: d.update(index=10**12), r"postures/002.yaml: index must be 0..9999 .*; got 1000000000000$"),
])
def test_implausible_values_are_refused_at_read_time_naming_posture_and_key(edit, pattern, session, capsys):
    edit_posture(session, 2, edit)
    one_line_error(capsys, ["calibrate", session], pattern)


#: 9 ** 8 = 43 million references to one list of 9 numbers, in 300 bytes of YAML.
ALIAS_BOMB = "a: &a [1, 2, 3, 4, 5, 6, 7, 8, 9]\n" + "".join(
    f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefg", "bcdefgh"))


@pytest.mark.parametrize("key, pattern", [  # refused by the YAML reader's alias budget (issue 42.8)
    ("points_mm", r"postures/001.yaml: not read as YAML: aliases expand the document beyond \d+ repeated values"),
    ("index", r"postures/001.yaml: not read as YAML: aliases expand the document beyond \d+ repeated values"),
    ("joints_deg", r"postures/001.yaml: not read as YAML: aliases expand the document beyond \d+ repeated values"),
])
def test_a_yaml_alias_bomb_is_refused_without_being_expanded(key, pattern, session, capsys, no_hang):
    file = session / "postures" / "001.yaml"
    data = yaml.safe_load(file.read_text())
    data.pop(key)
    file.write_text(ALIAS_BOMB + yaml.safe_dump(data) + f"{key}: *h\n")
    one_line_error(capsys, ["calibrate", session], pattern)


def test_a_posture_file_without_index_needs_an_nnn_name(session, capsys):
    data = yaml.safe_load((session / "postures" / "001.yaml").read_text())
    del data["index"]
    (session / "postures" / "extra.yaml").write_text(yaml.safe_dump(data))
    one_line_error(capsys, ["calibrate", session],
                   r"postures/extra.yaml: no index, and the file name is not NNN.yaml; add 'index: N' \(0..9999\)$")


def test_a_board_of_absurd_size_is_refused(session, capsys):
    header = yaml.safe_load((session / "session.yaml").read_text())
    header["target"]["square_mm"] = 1e300
    (session / "session.yaml").write_text(yaml.safe_dump(header))
    one_line_error(capsys, ["calibrate", session], r"target.square_mm must be a positive number of mm within ±1e7 mm")


def test_solver_failures_inside_numpy_become_one_line(session, capsys):
    """Every corner at one point: the compact points are NaN and eigh fails deep inside (LinAlgError)."""
    for index in range(8):
        edit_posture(session, index, lambda d: d.update(points_mm=[[0.0, 0.0, 900.0]] * len(d["points_mm"])))
    # at the station such a board is refused before any solve (its corners are not square_mm apart) ...
    one_line_error(capsys, ["calibrate", session, "--method", "tsai"],
                   r"the measured board corners are 0 mm apart but target.square_mm is 30 mm")
    # ... and a solver given it anyway fails in one line, not deep inside numpy
    with np.errstate(all="ignore"):  # problem_from_session divides 0 by 0 on such a board
        problem = problem_from_session(read_session(session), check_units=False)
    with pytest.raises(CalibrationError, match=r"^the tsai solver failed on these data \(.*\); check the session's values"):
        calibrate(problem, "tsai")
    with pytest.raises(CalibrationError, match=r"^the robust solver failed on these data"):
        calibrate(problem, "robust")
    with pytest.raises(CalibrationError, match=r"^the ml solver failed on these data"):
        calibrate(problem)  # the default


def test_a_solver_returning_nan_is_not_a_result(session, monkeypatch):
    from handeye.calibration.classic import tsai

    def nan_solver(hand, target):
        """A stand-in for handeye's own solver that returns NaN (as on degenerate data)."""
        return np.full((4, 4), np.nan)

    monkeypatch.setattr(tsai, "solve_tsai", nan_solver)
    with pytest.raises(CalibrationError, match=r"^the tsai solver found no finite camera pose"):
        calibrate(problem_from_session(read_session(session)), "tsai")


# --------------------------------------------------------------------------- outputs that cannot be written


@pytest.fixture
def a_file(tmp_path) -> Path:
    """A regular file: any path below it cannot be created, not even by root."""
    path = tmp_path / "plain_file"
    path.write_text("I am a file\n")
    return path


def test_calibrate_json_below_a_file_fails_before_solving(session, a_file, capsys):
    one_line_error(capsys, ["calibrate", session, "--json", a_file / "result.json"],
                   r"cannot write .*result.json: .*plain_file is a file, not a folder; choose a writable folder$")


def test_calibrate_json_that_is_a_folder(session, tmp_path, capsys):
    (tmp_path / "out").mkdir()
    one_line_error(capsys, ["calibrate", session, "--json", tmp_path / "out"],
                   r"cannot write .*out: it is a folder; give a file name$")


def test_calibrate_json_permission_denied_leaves_nothing(session, tmp_path, capsys, monkeypatch):
    real_replace = os.replace

    def refuse(src, dst):
        if str(dst).endswith("result.json"):
            raise PermissionError(errno.EACCES, "Permission denied", str(dst))
        return real_replace(src, dst)

    monkeypatch.setattr(files.os, "replace", refuse)
    one_line_error(capsys, ["calibrate", session, "--json", tmp_path / "result.json"],
                   r"cannot write .*result.json: permission denied; choose a writable folder$")
    assert [p.name for p in tmp_path.iterdir() if "result" in p.name] == []  # no temporary file left


@pytest.mark.parametrize("argv", [
    ["simulate", "-o", "{below}/sim", "--postures", "4"],
    ["demo", "--session", "{below}/demo"],
    ["import", "{source}", "-o", "{below}/imported"],
    ["capture", "--mock", "--session", "{below}/capture", "--postures", "3"],
])
def test_output_folders_below_a_file(argv, a_file, tmp_path, capsys):
    source = tmp_path / "poses.json"  # import reads (and checks) everything before it writes
    rotations = Rotation.from_rotvec(np.random.default_rng(1).normal(scale=0.5, size=(6, 3)))
    mount = np.eye(4)
    mount[:3, 3] = [60.0, -40.0, 90.0]  # a consistent scene: the board fixed in the base, the camera on the flange
    board = np.eye(4)
    board[:3, 3] = [1500.0, 0.0, 300.0]
    postures = []
    for k, rotation in enumerate(rotations):
        flange = np.eye(4)
        flange[:3, :3], flange[:3, 3] = rotation.as_matrix(), [800.0, 20.0 * k, 900.0]
        target = np.linalg.inv(flange @ mount) @ board
        postures.append({"tool0_in_base": {"position": flange[:3, 3].tolist(), "quaternion": list(rotation.as_quat(scalar_first=True))},
                         "target_in_camera": {"matrix": target.tolist()}})
    source.write_text(json.dumps({"units": "mm", "setup": "eye_in_hand", "postures": postures}))
    argv = [a.format(below=a_file, source=source) for a in argv]
    line = one_line_error(capsys, argv, r"cannot (create folder|write) .*: .*plain_file is a file, not a folder; "
                                        r"choose a writable folder$")
    assert "Traceback" not in line
    assert a_file.read_text() == "I am a file\n"


def test_simulate_into_a_read_only_folder(tmp_path, capsys, monkeypatch):
    def refuse(self, *args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", refuse)
    one_line_error(capsys, ["simulate", "-o", tmp_path / "sim", "--postures", "4"],
                   r"^handeye simulate: error: cannot create folder .*sim/postures: permission denied; "
                   r"choose a writable folder$")


def test_writeback_backup_into_a_read_only_session_writes_nothing_to_the_robot(tmp_path, capsys, monkeypatch):
    assert main(["simulate", "-o", str(tmp_path / "sim"), "--postures", "12", "--sigma-cam", "0.1"]) == 0
    capsys.readouterr()
    real_mkstemp = files.tempfile.mkstemp

    def refuse(*args, dir=None, **kwargs):
        if Path(dir) == tmp_path / "sim":
            raise PermissionError(errno.EACCES, "Permission denied", str(dir))
        return real_mkstemp(*args, dir=dir, **kwargs)

    monkeypatch.setattr(files.tempfile, "mkstemp", refuse)
    code = main(["writeback", str(tmp_path / "sim"), "--mock", "--force"])
    out, err = capsys.readouterr()
    assert code == 1 and len(err.splitlines()) == 1, err
    assert re.match(r"handeye writeback: error: cannot write .*sim/tooldata_backup_\d{8}-\d{6}.yaml: permission "
                    r"denied; choose a writable folder$", err.strip()), err
    assert "read back" not in out  # the controller was never written
    assert not list((tmp_path / "sim").glob("tooldata_backup_*")) and not (tmp_path / "sim" / "writeback.yaml").exists()


@pytest.mark.parametrize("code, pattern", [
    (errno.EROFS, r"cannot write .*x.yaml: the file system is read-only; choose a writable folder$"),
    (errno.ENOSPC, r"cannot write .*x.yaml: no space left on the device; free some space or choose another disk$"),
])
def test_write_text_atomic_reasons(code, pattern, tmp_path, monkeypatch):
    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(files.os, "fsync", fail)
    with pytest.raises(OutputError, match=pattern):
        write_text_atomic(tmp_path / "x.yaml", "a: 1\n")
    assert list(tmp_path.iterdir()) == []


def test_make_folder_over_a_file(a_file):
    with pytest.raises(OutputError, match=r"^cannot create folder .*plain_file: .*plain_file is a file, not a folder"):
        make_folder(a_file)


def test_the_real_command_writing_below_a_file(session, a_file):
    """The console script: a --json path below a regular file (unwritable for root too)."""
    command = Path(sys.executable).with_name("handeye")
    out = subprocess.run([str(command), "calibrate", str(session), "--json", str(a_file / "r.json")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 1
    assert "Traceback" not in out.stderr and out.stderr.count("\n") == 1, out.stderr
    assert out.stderr.startswith("handeye calibrate: error: cannot write ") and "is a file, not a folder" in out.stderr


# --------------------------------------------------------------------------- the command line's safety net


def test_an_oserror_that_slips_through_is_one_line(monkeypatch, capsys):
    from handeye.station.commands import simulate

    def broken(args):
        raise OSError(errno.EIO, "Input/output error", "/some/file")

    monkeypatch.setattr(simulate, "run", broken)
    one_line_error(capsys, ["simulate", "-o", "x"], r"^handeye simulate: error: input/output error \(/some/file\)$")


def test_broken_pipe_is_still_quiet(monkeypatch, capsys):
    from handeye.station.commands import simulate

    def broken(args):
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")

    monkeypatch.setattr(simulate, "run", broken)
    assert main(["simulate", "-o", "x"]) == 0
    assert capsys.readouterr().err == ""



@pytest.mark.parametrize("key", ["setup", "units", "quaternion_order"])
def test_a_huge_value_is_quoted_briefly_in_the_one_line_error(tmp_path, key):
    """Found by the fuzz test: a list of 600-digit numbers where a word belongs was echoed whole (12,000
    characters); the message quotes it briefly."""
    from handeye.base.errors import HandEyeError
    from handeye.station.importers.plain import read_plain

    data = {"setup": "eye_in_hand", "units": "mm", "quaternion_order": "wxyz", "postures": []}
    data[key] = [10**600] * 3
    path = tmp_path / "in.json"
    path.write_text(json.dumps(data))
    with pytest.raises(HandEyeError) as error:
        read_plain(path)
    message = str(error.value)
    assert key in message and "\n" not in message and len(message) < 300 + len(str(path))
