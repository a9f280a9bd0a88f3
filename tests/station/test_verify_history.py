"""The verify history survives damage and concurrent writers (issue 42, finding 6).

A damaged record (a time that is no date, a size that is text, a line that is not JSON, a last line
cut short) is skipped and counted with its line number, and never costs a check its verdict or its
report; processes appending at once keep every record."""

from __future__ import annotations

import json
import multiprocessing

import pytest

from handeye.station.cli import main
from handeye.station.verify.history import append_record, history_lines, load_history, read_history, trend_png

GOOD = {"time": "2026-01-02T03:04:05", "kind": "verify", "station": "mock", "session": "/x/base", "verdict": "ok",
        "cause": "none", "joint": None, "translation_mm": 0.01, "rotation_deg": 0.001, "p_value": 0.5, "postures": 5}


def _with(**change) -> str:
    return json.dumps({**GOOD, **change})


DAMAGED = {
    "time is a word": _with(time="yesterday"),
    "time is a number": _with(time=5),
    "time missing": json.dumps({k: v for k, v in GOOD.items() if k != "time"}),
    "size is text": _with(translation_mm="1.2 mm"),
    "size is infinite": _with(rotation_deg=1e999).replace("Infinity", "1e999"),
    "verdict is a number": _with(verdict=3),
    "joint is text": _with(joint="three"),
    "unknown kind": _with(kind="calibration"),
    "a list": "[1, 2, 3]",
    "not JSON": "{time: 2026",
}


@pytest.mark.parametrize("line", DAMAGED.values(), ids=DAMAGED.keys())
def test_a_damaged_record_is_skipped_and_counted_with_its_line(tmp_path, line):
    path = tmp_path / "history.jsonl"
    path.write_text("\n".join([json.dumps(GOOD), line, _with(time="2026-01-03T00:00:00", verdict="drift")]) + "\n")
    history = load_history(path)
    assert [r["time"] for r in history.records] == ["2026-01-02T03:04:05", "2026-01-03T00:00:00"]
    assert [n for n, _ in history.skipped] == [2]
    assert "skipped 1 damaged record" in history.skipped_line() and "line 2" in history.skipped_line()
    assert len(history_lines(history.records)) == 2
    assert trend_png(history.records, 0.2, 0.02).startswith(b"\x89PNG")


def test_a_last_line_cut_short_is_named_not_dropped_silently(tmp_path):
    path = tmp_path / "history.jsonl"
    path.write_text(json.dumps(GOOD) + "\n" + _with(time="2026-01-03T00:00:00")[:40])
    history = load_history(path)
    assert len(history.records) == 1 and history.skipped[0][0] == 2 and "cut short" in history.skipped[0][1]
    append_record(path, {**GOOD, "time": "2026-01-04T00:00:00"})  # the next append starts a line of its own
    history = load_history(path)
    assert [r["time"] for r in history.records] == ["2026-01-02T03:04:05", "2026-01-04T00:00:00"]
    assert [n for n, _ in history.skipped] == [2]


def test_times_with_a_zone_and_without_plot_together(tmp_path):
    records = [GOOD, {**GOOD, "time": "2026-01-03T00:00:00Z"}, {**GOOD, "time": "2026-01-04T00:00:00+02:00"}]
    assert trend_png(records, 0.2, 0.02).startswith(b"\x89PNG")


def _append_many(path: str, worker: int, count: int) -> None:
    for i in range(count):
        append_record(path, {**GOOD, "session": f"w{worker}", "n": i})


def test_processes_appending_at_once_keep_every_record(tmp_path):
    path = tmp_path / "history.jsonl"
    context = multiprocessing.get_context("spawn" if multiprocessing.get_start_method() != "fork" else "fork")
    workers = [context.Process(target=_append_many, args=(str(path), w, 20)) for w in range(4)]
    for p in workers:
        p.start()
    for p in workers:
        p.join(120)
    assert all(p.exitcode == 0 for p in workers)
    records = read_history(path)
    assert len(records) == 80 and not load_history(path).skipped
    for w in range(4):
        assert [r["n"] for r in records if r["session"] == f"w{w}"] == list(range(20))


BASE_YAML = "controller: {protocol: mock}\ncamera: {backend: mock}\nplan: {postures: 14}\n"


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    root = tmp_path_factory.mktemp("history")
    config = root / "mock.yaml"
    config.write_text(BASE_YAML)
    session = root / "base"
    assert main(["capture", "--config", str(config), "--session", str(session), "--yes"]) == 0
    assert main(["writeback", str(session), "--config", str(config)]) == 0
    return root, session


def test_a_damaged_history_keeps_the_drift_exit_and_the_report(station, capsys):
    root, session = station
    history = root / "history.jsonl"
    history.write_text("\n".join([json.dumps(GOOD), DAMAGED["time is a word"], DAMAGED["time is a number"]]) + "\n")
    drift = root / "drift.yaml"
    drift.write_text(BASE_YAML + "mock:\n  faults: {camera_shift_mm: [0.9, -0.8, 0.6]}\n")
    capsys.readouterr()
    page = root / "check.html"
    code = main(["verify", "--config", str(drift), "--against", str(session), "--report", str(page)])
    err = capsys.readouterr().err
    assert code == 3, err
    assert "skipped 2 damaged records" in err and "line 2" in err and "line 3" in err and "Traceback" not in err
    text = page.read_text()
    assert "data:image/png;base64," in text and "skipped 2 damaged records" in text
    assert len(read_history(history)) == 2  # the old sound record and this check's
    assert history.read_text().splitlines()[1:3] == [DAMAGED["time is a word"], DAMAGED["time is a number"]]


def test_history_names_a_record_cut_short(station, capsys):
    root, session = station
    history = root / "history.jsonl"
    history.write_text(json.dumps(GOOD) + "\n" + json.dumps(GOOD)[:30])
    capsys.readouterr()
    assert main(["verify", "--mock", "--against", str(session), "--history"]) == 0
    out, err = capsys.readouterr()
    assert len([line for line in out.splitlines() if line.startswith("  20")]) == 1
    assert "skipped 1 damaged record" in err and "line 2: cut short" in err
