"""One posture, one number (issue 25, finding 3), and a resumed capture repairs what an interruption
left half done (finding 5).

The number an operator reads for a posture is the number of its file, ``postures/NNN.yaml`` -> NNN:
in the capture's lines, the preview's labels, the RAPID program's comments, calibrate's outlier list,
its JSON and the HTML report.
"""

import json
import re

import numpy as np
import yaml

from handeye.calibration.session import read_session, write_posture
from handeye.station.cli import main


def _capture(capsys, session, postures, *more) -> str:
    code = main(["capture", "--mock", "--session", str(session), "--postures", str(postures), *more])
    out = capsys.readouterr().out
    assert code == 0, out
    return out


def _program_comments(rapid_dir) -> dict:
    """``{k: the comment line above CONST jointtarget jtHePostK}`` of HeMain.mod."""
    lines = (rapid_dir / "HeMain.mod").read_text().splitlines()
    out = {}
    for above, line in zip(lines, lines[1:]):
        match = re.match(r"\s*CONST jointtarget jtHePost(\d+) :=", line)
        if match:
            out[int(match.group(1))] = above.strip()
    return out


def test_the_plan_names_each_posture_by_its_file_number(tmp_path, capsys):
    from handeye.station.cell.preview import posture_labels

    session = tmp_path / "s"
    _capture(capsys, session, 5, "--plan-only")
    comments = _program_comments(session / "rapid")
    assert sorted(comments) == [1, 2, 3, 4, 5]  # the controller's posture k (the link protocol counts from 1)
    for k, comment in comments.items():
        assert comment.startswith("!") and f"posture {k - 1} " in comment and f"postures/{k - 1:03d}.yaml" in comment
    assert posture_labels(5) == ["0", "1", "2", "3", "4"]


def test_capture_calibrate_and_report_name_the_same_posture_the_same(tmp_path, capsys):
    session = tmp_path / "s"
    out = _capture(capsys, session, 17)
    files = {p.index: p for p in read_session(session).postures}
    assert sorted(files) == list(range(17))
    for index, posture in files.items():  # the line printed for each posture names its file's number
        q = posture.extra["quality"]
        assert re.search(rf"ok +posture {index}: {q['corners']} corners at {q['distance_mm']:.0f} mm", out), (index, out)
    assert "skipped" not in out
    bad = files[16]
    bad.points_mm = bad.points_mm + np.array([25.0, 0.0, 0.0])  # posture file 016 corrupted
    write_posture(session, bad)
    result, report = tmp_path / "r.json", tmp_path / "r.html"
    assert main(["calibrate", str(session), "--json", str(result), "--report", str(report)]) == 0
    text = capsys.readouterr().out
    assert json.loads(result.read_text())["outliers"] == [16]
    assert re.search(r"Outlier postures \(excluded from the solution\): 16\b", text)
    assert re.search(r"^ +16 +[0-9.]+ +#+ +<- outlier$", text, re.MULTILINE)  # the residual table
    html = report.read_text()
    assert re.search(r"posture 16: [0-9.]+ mm", html)


# ------------------------------------------------------------------------------------------ resume
def _interrupted_plan(capsys, session, postures=6):
    """A plan as a kill right after ``session.yaml`` leaves it: no preview, no (or half a) program."""
    _capture(capsys, session, postures, "--plan-only")
    (session / "preview.png").unlink()
    for module in (session / "rapid").iterdir():
        if module.name != "HeMain.mod":
            module.unlink()  # killed while writing the modules


def test_a_rerun_draws_the_preview_and_writes_the_program_an_interruption_left_out(tmp_path, capsys):
    session = tmp_path / "s"
    _interrupted_plan(capsys, session)
    out = _capture(capsys, session, 6)  # the same command again
    assert (session / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "preview" in out and "RAPID program" in out
    assert sorted(p.name for p in (session / "rapid").iterdir()) == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
    assert sorted(p.index for p in read_session(session).postures) == list(range(6))
    report = tmp_path / "r.html"
    assert main(["calibrate", str(session), "--report", str(report)]) == 0
    html = report.read_text()
    assert "Capture plan: the cell" in html and "capture plan preview" in html
    (session / "preview.png").unlink()  # lost later: the report says so instead of dropping the section
    assert main(["calibrate", str(session), "--report", str(report)]) == 0
    html = report.read_text()
    assert "Capture plan: the cell" in html and "preview.png is missing" in html


def test_a_plan_only_rerun_repairs_and_points_at_a_preview_that_exists(tmp_path, capsys):
    session = tmp_path / "s"
    _interrupted_plan(capsys, session, 4)
    out = _capture(capsys, session, 4, "--plan-only")
    assert (session / "preview.png").is_file() and (session / "rapid" / "HeSocket.mod").is_file()
    assert "look at" in out


def test_what_cannot_be_rebuilt_is_named_in_one_line(tmp_path, capsys):
    session = tmp_path / "s"
    _interrupted_plan(capsys, session, 4)
    header = yaml.safe_load((session / "session.yaml").read_text())
    del header["capture"]["board_estimate"]  # a record that cannot place the board any more
    (session / "session.yaml").write_text(yaml.safe_dump(header))
    out = _capture(capsys, session, 4, "--plan-only")
    assert not (session / "preview.png").exists()
    missing = [line for line in out.splitlines() if "preview.png" in line]
    assert len(missing) == 1 and "missing" in missing[0] and "board_estimate" in missing[0], out
    assert "look at" not in out  # it does not send the operator to a file that is not there
    assert (session / "rapid" / "HeSocket.mod").is_file()  # what can be rebuilt still is
