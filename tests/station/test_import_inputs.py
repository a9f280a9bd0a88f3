"""What ``handeye import`` does with inputs that are not a log of poses (issue 25, finding 7).

- a camodocal folder holds the tool's own result beside its pose pairs: the import reads the pairs
  and names the result file it skipped, it does not fail on it;
- an empty or binary file is refused in one line that says so (not "pass --format");
- a large file whose first bytes already show it is not a log is refused from its head.
"""

from __future__ import annotations

import os
import shutil

import pytest

from handeye.base.errors import SessionError
from handeye.station import cli
from handeye.station.importers import detect_format, read_any

from helpers import shared_dataset

CAMODOCAL_RESULT = """%YAML:1.0
---
ArmTipToMarkerTagTransform: !!opencv-matrix
   rows: 4
   cols: 4
   dt: d
   data: [ 1., 0., 0., 0.01, 0., 1., 0., 0.02, 0., 0., 1., 0.03, 0., 0., 0., 1. ]
"""


@pytest.fixture
def camodocal_folder(tmp_path):
    """The camodocal example as the tool leaves it: its pose pairs and its result, side by side."""
    source = shared_dataset("camodocal-ar-tag")
    folder = tmp_path / "camodocal"
    folder.mkdir()
    shutil.copy(source / "TransformPairsInput.yml", folder)
    shutil.copy(source / "CalibratedTransform.yml", folder)
    return folder


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_camodocal_folder_skips_the_tools_result(camodocal_folder, tmp_path, capsys):
    assert detect_format(camodocal_folder) == "opencv"
    session = read_any(camodocal_folder)
    assert len(session.postures) == 42
    notes = " ".join(session.extra["import"]["notes"])
    assert "CalibratedTransform.yml" in notes and "skipped" in notes and "ArmTipToMarkerTagTransform" in notes
    code, out, err = run_cli(capsys, "import", camodocal_folder, "-o", tmp_path / "s")
    assert code == 0, err
    assert "postures: 42" in out and "CalibratedTransform.yml" in out


def test_camodocal_result_named_with_the_pairs_and_given_format(camodocal_folder, tmp_path, capsys):
    files = [camodocal_folder / "TransformPairsInput.yml", camodocal_folder / "CalibratedTransform.yml"]
    assert len(read_any(files).postures) == 42
    assert len(read_any(camodocal_folder, "opencv").postures) == 42
    # the variant that writes eeTeye and the solver's costs
    (camodocal_folder / "CalibratedTransform.yml").write_text(
        CAMODOCAL_RESULT.replace("ArmTipToMarkerTagTransform", "eeTeye") + "initial_cost: 1.5\nfinal_cost: 0.5\n")
    assert len(read_any(camodocal_folder).postures) == 42


def test_camodocal_folder_with_pairs_written_twice(camodocal_folder):
    shutil.copy(camodocal_folder / "TransformPairsInput.yml", camodocal_folder / "TransformPairsOutput.yml")
    session = read_any(camodocal_folder)
    assert len(session.postures) == 42
    assert "same pairs" in " ".join(session.extra["import"]["notes"])
    text = (camodocal_folder / "TransformPairsOutput.yml").read_text()
    (camodocal_folder / "TransformPairsOutput.yml").write_text(text.replace("frameCount: 42", "frameCount: 41"))
    with pytest.raises(SessionError, match="TransformPairsInput.yml and TransformPairsOutput.yml both hold"):
        read_any(camodocal_folder)


@pytest.mark.parametrize("fmt", [None, "log", "plain", "moveit", "opencv", "easy_handeye"])
def test_empty_file_says_it_is_empty(tmp_path, fmt):
    path = tmp_path / "poses.csv"
    path.write_bytes(b"")
    with pytest.raises(SessionError) as info:
        read_any(path, fmt)
    message = str(info.value)
    assert "is empty" in message and "--format" not in message and "\n" not in message


@pytest.mark.parametrize("head, words", [
    (b"\x89PNG\r\n\x1a\n" + bytes(200), "a PNG image"),
    (b"PK\x03\x04" + bytes(200), "a ZIP archive"),
    (b"\x00\x01\x02garbage" + bytes(200), "binary"),
])
@pytest.mark.parametrize("fmt", [None, "log", "plain"])
def test_binary_file_says_it_is_binary(tmp_path, fmt, head, words):
    path = tmp_path / "poses.txt"
    path.write_bytes(head)
    with pytest.raises(SessionError) as info:
        read_any(path, fmt)
    message = str(info.value)
    assert words in message and "not a text log" in message and "--format" not in message


def test_cli_empty_and_binary(tmp_path, capsys):
    empty = tmp_path / "e.csv"
    empty.write_bytes(b"")
    code, _, err = run_cli(capsys, "import", empty, "-o", tmp_path / "s")
    assert code == 1 and err.count("\n") == 1 and "is empty" in err and "pass --format" not in err


@pytest.fixture
def bytes_read(monkeypatch):
    """Counts every byte the package reads through ``os.fdopen`` handles (calibration.files)."""
    import handeye.base.files as files

    total = [0]
    real = files.os.fdopen

    class Counting:
        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.__exit__(*exc)

        def read(self, *args):
            data = self.handle.read(*args)
            total[0] += len(data)
            return data

    monkeypatch.setattr(files.os, "fdopen", lambda *a, **k: Counting(real(*a, **k)))
    return total


BIG = 50 * 2**20


@pytest.mark.parametrize("fmt", [None, "log", "plain", "moveit", "opencv", "easy_handeye", "stream"])
def test_big_binary_file_is_refused_from_its_head(tmp_path, bytes_read, fmt):
    path = tmp_path / "big.csv"
    with open(path, "wb") as handle:
        handle.write(b"\x00\x07\x1b junk that no log starts with\n")
        handle.truncate(BIG)  # sparse: 50 MB without writing them
    paths = [path, path] if fmt == "stream" else path
    with pytest.raises(SessionError, match="binary"):
        read_any(paths, fmt)
    assert 0 < bytes_read[0] < 2**20


@pytest.mark.parametrize("fmt", [None, "log", "plain"])
def test_big_text_without_numbers_is_refused_from_its_head(tmp_path, bytes_read, fmt):
    path = tmp_path / "big.json"
    with open(path, "w") as handle:
        handle.write("this is not a log of poses\n")
        line = "no numbers here at all, only words and more words\n"
        handle.write(line * (4 * 2**20 // len(line)))
    with pytest.raises(SessionError, match="no number"):
        read_any(path, fmt)
    assert 0 < bytes_read[0] < 2**20
    assert os.path.getsize(path) > 4 * 2**20 - 100
