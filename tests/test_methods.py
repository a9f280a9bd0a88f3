"""One table of calibration methods: calibrate, the method lists and the command line read it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from handeye.calibration.classic import CLASSIC_METHODS
from handeye.calibration.methods import KINDS, METHODS, Method, get_method, method_names
from handeye.calibration.solve import ALL_METHODS, DEFAULT_METHOD, PAPER_METHODS, calibrate

from helpers import problem as make_problem

CONVENTIONS = ("mc", "mcr", "mct", "mcb", "mco", "tsai", "park", "horaud", "andreff", "daniilidis", "chou", "lu",
               "liang")


def test_the_table_holds_every_method_once_with_its_kind():
    assert set(CONVENTIONS) <= set(METHODS) and DEFAULT_METHOD in METHODS
    assert ALL_METHODS == method_names() and PAPER_METHODS == method_names("paper")
    assert {m.kind for m in METHODS.values()} == set(KINDS)
    assert all(isinstance(m, Method) and m.name == name and m.citation for name, m in METHODS.items())
    assert get_method("TSAI") is METHODS["tsai"] and get_method("nope") is None


def test_classic_rows_hold_the_solvers_of_the_classic_package():
    classic = {name: m for name, m in METHODS.items() if m.kind == "classic"}
    assert {name: m.solver for name, m in classic.items()} == CLASSIC_METHODS
    assert all(m.solver is None for m in METHODS.values() if m.kind != "classic")
    assert all(m.source.endswith(m.citation[-5:-1]) for m in classic.values())  # the year of the full reference


def test_a_classic_result_names_its_reference_from_the_table():
    problem = make_problem(8, sigma_cam=0.5, seed=3)[0]
    assert calibrate(problem, "tsai").details["reference"] == "Tsai & Lenz (1989)."
    assert calibrate(problem, "chou").details["reference"] == "Chou & Kamel (1991), quaternion SVD then translation."


def test_calibrate_solves_with_the_solver_in_the_table(monkeypatch):
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=3)
    calls = []

    def spy(hand, target2cam, pairs=None):
        calls.append(len(hand))
        return CLASSIC_METHODS["park"](hand, target2cam)

    monkeypatch.setitem(METHODS, "park", replace(METHODS["park"], solver=spy))
    result = calibrate(problem, "park")
    assert calls == [8] and np.allclose(result.x, CLASSIC_METHODS["park"](problem.hand, problem.target2cam))


def test_the_command_line_names_every_method():
    from handeye.station.commands.calibrate import EPILOG

    for name in METHODS:
        assert f" {name}" in EPILOG, name


@pytest.mark.parametrize("name", method_names())
def test_every_method_runs_from_its_row(name):
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=5)
    result = calibrate(problem, name, truth if name == "mcy" else None)
    assert result.method == name and np.all(np.isfinite(result.x))
