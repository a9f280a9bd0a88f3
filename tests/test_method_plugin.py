"""A calibration method from another installed package: the test plug-in (tests/plugin) adds
``kabsch``, an AX = XB solver of its own, through its ``handeye.methods`` entry point only. With it
installed and no change to handeye, ``--method kabsch`` runs, the help lists it, the benchmark solves
it and the report's comparison holds it; without it, the name is refused in one line."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from handeye.calibration.methods import METHODS, comparison_methods, method_names
from handeye.station.cli import main

from helpers import plugin_installed

PLUGIN = Path(__file__).with_name("plugin")


@pytest.fixture
def plugin(monkeypatch):
    """The test plug-in installed (its folder on sys.path); uninstalled again afterwards."""
    with plugin_installed(monkeypatch, PLUGIN, ("handeye_test_plugin", "handeye_test_plugin_method")):
        yield


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A simulated session (truth.yaml beside it): 10 postures, 0.3 mm camera noise."""
    path = tmp_path_factory.mktemp("plugin") / "sim"
    assert main(["simulate", "-o", str(path), "--postures", "10", "--sigma-cam", "0.3", "--seed", "3"]) == 0
    return path


def test_the_plugin_method_is_a_row_of_the_table(plugin):
    assert method_names()[-1] == "kabsch" and METHODS["kabsch"].kind == "classic"
    assert comparison_methods()[-1] == "kabsch" and METHODS["kabsch"].citation == "Test plug-in (2025)"


def test_calibrate_method_plugin_runs_close_to_the_truth(plugin, simulated, tmp_path, capsys):
    out = tmp_path / "kabsch.json"
    assert main(["calibrate", str(simulated), "--method", "kabsch", "--quiet", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["method"] == "kabsch" and data["details"] == {
        "reference": "Test plug-in (2025), rotation axes aligned by SVD, then translation."}
    errors = data["truth_errors"]
    assert errors["rotation_error_deg"] < 0.1 and errors["translation_error_mm"] < 1.0, errors
    with pytest.raises(SystemExit):
        main(["calibrate", "--help"])
    assert "\n  kabsch      Test plug-in (2025), rotation axes aligned by SVD, then translation\n" in capsys.readouterr().out


def test_the_report_compares_the_plugin_method(plugin, simulated, tmp_path, capsys):
    out, report = tmp_path / "r.json", tmp_path / "r.html"
    assert main(["calibrate", str(simulated), "--report", str(report), "--quiet", "--json", str(out)]) == 0
    rows = {row["method"]: row for row in json.loads(out.read_text())["method_comparison"]}
    assert set(rows) == {*comparison_methods(), "ml"} and "kabsch" in rows
    assert rows["kabsch"]["held_out_mm"] is not None and rows["kabsch"]["d_position_mm"] < 2.0
    assert ">kabsch<" in report.read_text()


def test_the_benchmark_solves_the_plugin_method(plugin, tmp_path, capsys):
    from handeye.station.benchmark import BenchmarkOptions, run_benchmark

    options = BenchmarkOptions(sweeps=("postures",), postures_values=(8,), trials=1, opencv=False,
                               methods=("mcb", "kabsch"), plots=False)
    rows = {row["method"]: row for row in run_benchmark(options)}
    assert set(rows) == {"truth", "mcb", "kabsch"} and rows["kabsch"]["rotation_error_deg"] < 0.5
    out = tmp_path / "b"
    assert main(["benchmark", "-o", str(out), "--sweep", "postures", "--postures", "8", "--trials", "1",
                 "--methods", "kabsch", "--no-plots", "--no-opencv"]) == 0
    assert {r["method"] for r in csv.DictReader(open(out / "results.csv"))} == {"truth", "kabsch"}


def test_without_the_plugin_its_method_is_refused_in_one_line(simulated, tmp_path, capsys):
    assert "kabsch" not in method_names() and "kabsch" not in comparison_methods()
    assert main(["calibrate", str(simulated), "--method", "kabsch"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("handeye calibrate: error: unknown method 'kabsch'; choose one of mc, mcr,")
    assert err.count("\n") == 1 and "Traceback" not in err
    assert main(["benchmark", "-o", str(tmp_path / "b"), "--methods", "mcb,kabsch", "--trials", "1"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("handeye benchmark: error: --methods: unknown method 'kabsch'; choose one of mc,")
    assert err.count("\n") == 1 and not (tmp_path / "b").exists()  # refused before anything is written
