"""Other people's plug-ins as they really are: a method, a controller or a name that is wrong.

A package written in this test (a ``.dist-info`` and a module in a temporary folder, on ``sys.path``)
registers, through entry points only, methods that raise, that return what is not a rigid transform,
no solution at all or an uncertainty or cross-validation the report cannot read, a method named like
one of handeye's own, and a controller whose class fails. Each is refused in one line that names the package and what to do; a faulty method in the report's
comparison leaves the report whole and is listed as not compared; the benchmark counts its failures.
handeye's own faults are one line too, their traceback saved to a file.
"""

from __future__ import annotations

import json
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest
from handeye.base.errors import CalibrationError
from handeye.calibration.methods import METHODS, Method
from handeye.calibration.session import read_session
from handeye.calibration.solve import calibrate_session
from handeye.drivers.controller.backends import CONTROLLERS, ControllerBackend
from handeye.station.cli import main

from helpers import plugin_installed

PACKAGE = "handeye-faulty-plugin"
MODULE = "handeye_faulty_plugin"

SOURCE = '''
import numpy as np
from handeye.calibration.methods import Method
from handeye.drivers.controller.backends import ControllerBackend


def _method(name, solver, kind="classic"):
    return Method(name, kind, "Nobody (2026)", name, f"{__name__}:{solver}", in_comparison=True)


def raises(hand, target2cam, pairs=None):
    raise RuntimeError("solver exploded")


def value_error(hand, target2cam, pairs=None):
    raise ValueError("operands could not be broadcast together")


def scaled(hand, target2cam, pairs=None):
    x = np.eye(4)
    x[:3, :3] *= 2.0
    return x


def reflected(hand, target2cam, pairs=None):
    return np.diag([1.0, 1.0, -1.0, 1.0])


def small(hand, target2cam, pairs=None):
    return np.eye(3)


def nan(hand, target2cam, pairs=None):
    return np.full((4, 4), np.nan)


def text(problem, progress=None):
    return "a pose"


def _solution(problem, **judgements):
    from types import SimpleNamespace

    from handeye.calibration.solve import calibrate

    fields = {"outliers": None, "details": {}, "uncertainty": None, "cross_validation": None, **judgements}
    return SimpleNamespace(x=calibrate(problem, "tsai").x, **fields)


def unsure(problem, progress=None):
    return _solution(problem, uncertainty={"translation": 0.1})


def unfolded(problem, progress=None):
    return _solution(problem, cross_validation={"rms_mm": float("nan"), "folds": 5})


BOOM = _method("boom", "raises")
BROADCAST = _method("broadcast", "value_error")
SCALED = _method("scaled", "scaled")
REFLECTED = _method("reflected", "reflected")
SMALL = _method("small", "small")
NAN = _method("nanx", "nan")
TEXT = _method("text", "text", kind="estimator")
UNSURE = _method("unsure", "unsure", kind="estimator")
UNFOLDED = _method("unfolded", "unfolded", kind="estimator")
TSAI = Method("tsai", "classic", "An impostor (2026)", "", f"{__name__}:nan")


class BrokenController:
    def __init__(self, **options):
        raise KeyError("no such option table")


BROKEN = ControllerBackend("broken", f"{__name__}:BrokenController", default_port=11999, help="a link that fails")
'''

ENTRY_POINTS = """
[handeye.methods]
boom = handeye_faulty_plugin:BOOM
broadcast = handeye_faulty_plugin:BROADCAST
scaled = handeye_faulty_plugin:SCALED
reflected = handeye_faulty_plugin:REFLECTED
small = handeye_faulty_plugin:SMALL
nanx = handeye_faulty_plugin:NAN
text = handeye_faulty_plugin:TEXT
unsure = handeye_faulty_plugin:UNSURE
unfolded = handeye_faulty_plugin:UNFOLDED
tsai = handeye_faulty_plugin:TSAI

[handeye.controllers]
broken = handeye_faulty_plugin:BROKEN
"""

#: The faulty methods, each in the comparison, and what its refusal says.
FAULTS = {
    "boom": "raised RuntimeError: solver exploded",
    "broadcast": "failed (ValueError: operands could not be broadcast together)",
    "scaled": "not a rigid transform: rotation part is not orthonormal (|R^T R - I| = 3)",
    "reflected": "not a rigid transform: rotation part is a reflection",
    "small": "not a rigid transform: must be a 4x4 matrix; got shape 3x3",
    "nanx": "found no finite camera pose",
    "text": "returned a str, not a solution with x, outliers",
    "unsure": "returned an uncertainty that is not translation_mm and rotation_deg, three finite one-sigma values each",
    "unfolded": "returned a cross-validation without folds and rms_mm",
}


@pytest.fixture
def faulty(tmp_path, monkeypatch):
    """The faulty package installed (its folder on sys.path); uninstalled again afterwards."""
    folder = tmp_path / "site"
    info = folder / f"{MODULE}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {PACKAGE}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(textwrap.dedent(ENTRY_POINTS))
    (folder / f"{MODULE}.py").write_text(SOURCE)
    with plugin_installed(monkeypatch, folder, (MODULE,)):
        yield folder


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A simulated session (truth.yaml beside it): 10 postures, 0.3 mm camera noise."""
    path = tmp_path_factory.mktemp("faulty") / "sim"
    assert main(["simulate", "-o", str(path), "--postures", "10", "--sigma-cam", "0.3", "--seed", "5"]) == 0
    return path


def _one_line_error(capsys, command: str) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith(f"handeye {command}: error: ")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("method", sorted(FAULTS))
def test_a_faulty_plugin_method_is_refused_in_one_line_naming_its_package(faulty, simulated, capsys, method):
    assert main(["calibrate", str(simulated), "--method", method]) == 1
    line = _one_line_error(capsys, "calibrate")
    assert f"method {method}, from the installed package {PACKAGE} (entry point {MODULE}:" in line, line
    assert FAULTS[method] in line and "run another --method" in line, line


def test_a_faulty_method_in_the_comparison_leaves_the_report_whole(faulty, simulated, tmp_path, capsys):
    out, report = tmp_path / "r.json", tmp_path / "r.html"
    assert main(["calibrate", str(simulated), "--report", str(report), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    data = json.loads(out.read_text())
    assert set(data["method_comparison_failed"]) == set(FAULTS)
    for method, reason in FAULTS.items():
        assert reason in data["method_comparison_failed"][method]
        assert f"not compared: method {method}, from the installed package {PACKAGE}" in text
    assert {row["method"] for row in data["method_comparison"]}.isdisjoint(FAULTS)
    assert report.read_text().count('data-note="not-compared"') == len(FAULTS)
    chosen = np.array(data["camera_pose"]["position_mm"]) if "camera_pose" in data else None
    truth = data["truth_errors"]
    assert truth["translation_error_mm"] < 1.0 and truth["rotation_error_deg"] < 0.1, truth
    assert chosen is None or np.all(np.isfinite(chosen))


def test_without_faults_the_report_names_none(simulated, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["calibrate", str(simulated), "--report", str(tmp_path / "r.html"), "--quiet", "--json", str(out)]) == 0
    assert "method_comparison_failed" not in json.loads(out.read_text())


def test_the_benchmark_counts_a_plugins_failed_trials(faulty, tmp_path, capsys):
    out = tmp_path / "bench"
    assert main(["benchmark", "-o", str(out), "--sweep", "postures", "--postures", "8", "--trials", "2",
                 "--methods", "tsai,boom", "--no-opencv", "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert "boom: 2 trial(s) not solved" in printed and "tsai:" not in printed
    summary = (out / "summary.md").read_text()
    assert "## Trials a method could not solve" in summary and "| boom | 2 | method boom, from" in summary
    assert "| tsai |" in summary  # the built-in solved every trial and has its medians


def test_a_plugin_named_like_handeyes_own_is_ignored_with_a_warning(faulty, caplog):
    METHODS.refresh()
    assert METHODS.names().count("tsai") == 1 and "boom" in METHODS.names()  # the entry points are read
    assert METHODS["tsai"].citation == "Tsai & Lenz (1989)"
    assert (f"the method 'tsai' of the installed package {PACKAGE} (entry point {MODULE}:TSAI) is ignored: handeye "
            "already has a method of that name") in caplog.text


def test_a_faulty_plugin_controller_is_one_line_naming_its_package(faulty, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    assert main(["robot", "joints", "--protocol", "broken"]) == 1
    line = _one_line_error(capsys, "robot")
    assert f"the installed plug-in package {PACKAGE} failed (KeyError: 'no such option table' at " in line, line
    assert f"pip uninstall {PACKAGE}" in line
    saved = Path(line.split("its traceback is in ")[1].split(":")[0])
    assert saved.parent == tmp_path and "KeyError" in saved.read_text() and "Traceback" in saved.read_text()


def test_handeyes_own_fault_is_one_line_with_the_traceback_saved(tmp_path, monkeypatch, capsys):
    from handeye.station.commands import calibrate as command

    def broken(args):
        return {}["x"]

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(command, "run", broken)
    monkeypatch.delenv("HANDEYE_DEBUG", raising=False)
    assert main(["calibrate", str(tmp_path)]) == 1
    line = _one_line_error(capsys, "calibrate")
    assert "unexpected KeyError: 'x' at " in line and "a fault in handeye, not in your data" in line, line
    assert len(list(tmp_path.glob("handeye-*.traceback.txt"))) == 1
    monkeypatch.setenv("HANDEYE_DEBUG", "1")
    with pytest.raises(KeyError):
        main(["calibrate", str(tmp_path)])


def test_a_traceback_that_cannot_be_saved_is_said_so(tmp_path, monkeypatch, capsys):
    from handeye.station.commands import calibrate as command

    def broken(args):
        return {}["x"]

    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setattr(tempfile, "tempdir", str(blocker))
    monkeypatch.setattr(command, "run", broken)
    monkeypatch.delenv("HANDEYE_DEBUG", raising=False)
    assert main(["calibrate", str(tmp_path)]) == 1
    line = _one_line_error(capsys, "calibrate")
    assert "its traceback could not be saved (run again with HANDEYE_DEBUG=1 to see it)" in line, line


def test_handeyes_own_method_fault_blames_handeye(simulated, monkeypatch):
    from handeye.calibration.classic import tsai

    def buggy(hand, target2cam, pairs=None):
        raise TypeError("unsupported operand")

    monkeypatch.setattr(tsai, "solve_tsai", buggy)
    with pytest.raises(CalibrationError, match="method tsai raised TypeError: unsupported operand: a fault in "
                                               "handeye, not in the data"):
        calibrate_session(read_session(simulated), "tsai")


def test_a_method_registered_in_code_from_outside_is_named_by_its_module(simulated, monkeypatch):
    def first_triplet(theta, inputs):
        return 3  # not a Selection

    monkeypatch.setitem(METHODS, "first", Method("first", "paper", "Me (2026)", "", first_triplet))
    with pytest.raises(CalibrationError, match=f"method first, from the module {__name__} \\(registered in code\\), "
                                               "raised AttributeError"):
        calibrate_session(read_session(simulated), "first")


def test_back_ends_sharing_a_link_module_read_the_folder_as_the_one_asked(tmp_path, monkeypatch):
    from handeye.mocks.controller.sources import program_from_folder
    from handeye.rapid.errors import RapidError

    monkeypatch.setitem(CONTROLLERS, "twin", ControllerBackend(
        "twin", "handeye.drivers.controller.socket_client:SocketController", default_port=11998,
        rapid_link="handeye.rapid.links:HE_SOCKET", help="the socket link under another name"))
    folder = tmp_path / "rapid"
    assert main(["rapid", "generate", "--protocol", "twin", "-o", str(folder)]) == 0
    assert (folder / "HeSocket.mod").is_file()
    assert program_from_folder(folder, "twin").link == "twin"
    assert program_from_folder(folder, "socket").link == "socket"
    assert program_from_folder(folder).link in ("socket", "twin")
    (folder / "HeIo.mod").write_text((folder / "HeSocket.mod").read_text().replace("HeSocket", "HeIo"))
    with pytest.raises(RapidError, match="holds the link modules of"):
        program_from_folder(folder)
