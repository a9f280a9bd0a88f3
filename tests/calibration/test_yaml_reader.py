"""One YAML reader for every file: a key written twice is refused with both lines; ``1e30`` is a number.

PyYAML keeps the last of two equal keys without a word, so a station file with a second ``cell:``
section used to plan "clear of the cell" with the first section's keep-out box gone.
"""

import json
from pathlib import Path

import pytest

from handeye.base.errors import SessionError
from handeye.base.files import parse_yaml
from handeye.calibration.session import read_session
from handeye.station.cli import main
from handeye.station.config.station import EXAMPLE_FILE, ConfigError, load_config
from handeye.station.importers.common import parse_json

BLOCKING_BOX = "cell:\n  volumes:\n    - {type: box, min_mm: [600, -300, 0], max_mm: [900, 300, 800]}\n"
SECOND_CELL = "cell:\n  margin_mm: 40\n"


def _station_text(*sections: str) -> str:
    return "controller:\n  protocol: socket\ncamera:\n  backend: xb3\n" + "".join(sections)


def test_a_second_cell_section_is_refused_naming_the_key_and_both_lines(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text(_station_text(BLOCKING_BOX, SECOND_CELL))
    with pytest.raises(ConfigError, match=r"the key cell is written twice \(lines 5 and 8\)"):
        load_config(path)


def test_a_second_controller_section_is_not_reported_as_a_missing_protocol(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text(_station_text("controller:\n  host: 10.0.0.5\n"))
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert "controller is written twice (lines 1 and 5)" in str(caught.value)
    assert "missing" not in str(caught.value)


@pytest.mark.parametrize("text, key, lines", [
    ("a: 1\nb: 2\na: 3\n", "a", "(lines 1 and 3)"),
    ("cell:\n  volumes:\n    - type: box\n      min_mm: [0, 0, 0]\n      min_mm: [1, 1, 1]\n",
     "cell.volumes[0].min_mm", "(lines 4 and 5)"),
    ("plan:\n  postures: {count: 30, count: 20}\n", "plan.postures.count", "on line 2"),
    ("- {x: 1}\n- {y: 2, y: 3}\n", "[1].y", "on line 2"),
    ("1: a\n1.0: b\n", "1.0", "(lines 1 and 2)"),
])
def test_a_duplicated_key_at_any_depth_is_named_with_both_lines(text, key, lines):
    with pytest.raises(SessionError) as caught:
        parse_yaml(text, "file.yaml")
    message = str(caught.value)
    assert f"the key {key} is written twice {lines}" in message and "\n" not in message


def test_keys_brought_by_a_merge_may_be_overridden():
    data = parse_yaml("base: &b {x: 1, y: 2}\nmine:\n  <<: *b\n  x: 5\n", "file.yaml")
    assert data["mine"] == {"x": 5, "y": 2}


@pytest.mark.parametrize("text, value", [
    ("1e30", 1e30), ("-2E-4", -2e-4), ("1.5e3", 1500.0), (".5e1", 5.0), ("+3e0", 3.0),
    ("1.0e+30", 1e30), ("12", 12), ("'1e30'", "1e30"), ("1e", "1e"), ("e5", "e5"),
])
def test_numbers_in_exponent_form_are_numbers(text, value):
    read = parse_yaml(f"v: {text}\n", "file.yaml")["v"]
    assert read == value and type(read) is type(value)


def test_a_config_number_in_exponent_form_is_checked_as_a_number(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text(_station_text().replace("protocol: socket\n", "protocol: socket\n  timeout_s: 1e30\n"))
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert "controller.timeout_s must be between" in str(caught.value)
    assert "must be a number" not in str(caught.value)
    path.write_text(_station_text().replace("protocol: socket\n", "protocol: socket\n  timeout_s: 2.5e0\n"))
    assert load_config(path).controller.timeout_s == 2.5


def test_the_cli_refuses_a_station_file_with_two_cell_sections_in_one_line(tmp_path, capsys):
    path = tmp_path / "station.yaml"
    path.write_text(EXAMPLE_FILE.read_text() + "\n" + SECOND_CELL)
    status = main(["capture", "--config", str(path), "--session", str(tmp_path / "s"), "--plan-only"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1 and len(err) == 1 and "the key cell is written twice" in err[0]
    assert not (tmp_path / "s").exists()


def test_a_session_file_with_a_duplicated_key_is_refused(tmp_path):
    assert main(["simulate", "-o", str(tmp_path / "s"), "--postures", "6"]) == 0
    posture = sorted((tmp_path / "s" / "postures").glob("*.yaml"))[2]
    posture.write_text(posture.read_text() + "\ntool0_in_base: [1, 2, 3]\n")
    with pytest.raises(SessionError, match=r"written twice \(lines \d+ and \d+\)"):
        read_session(tmp_path / "s")


def test_a_json_log_with_a_duplicated_key_is_refused_with_both_lines():
    text = json.dumps({"poses": [{"x": 1}]}, indent=1).replace('"x": 1', '"x": 1,\n "x": 2')
    with pytest.raises(SessionError, match=r"the key poses\[0\]\.x is written twice \(lines 4 and 5\)"):
        parse_json(text, "log.json")


def test_the_shipped_yaml_files_have_no_duplicated_keys():
    repo = Path(__file__).resolve().parents[2]
    files = [p for room in ("base", "geometry", "robot", "calibration", "drivers", "station", "rapid", "mocks") for p in (repo / "src" / "handeye" / room).rglob("*.yaml")]
    assert len(files) >= 5
    for path in files:
        parse_yaml(path.read_text(encoding="utf-8"), path)
