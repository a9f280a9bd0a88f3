"""One table of calibration methods: calibrate, the method lists and the command line read it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from handeye.calibration import classic, solve
from handeye.calibration.classic import CLASSIC_METHODS
from handeye.base.errors import CalibrationError
from handeye.calibration.methods import (
    KINDS,
    METHODS,
    Method,
    comparison_methods,
    get_method,
    method_names,
    register_method,
)
from handeye.calibration.selection import least_d_org, select_candidate
from handeye.calibration.solve import ALL_METHODS, DEFAULT_METHOD, PAPER_METHODS, calibrate

from helpers import REPO, assessed
from helpers import problem as make_problem

CONVENTIONS = ("mc", "mcr", "mct", "mcb", "mco", "tsai", "park", "horaud", "andreff", "daniilidis", "chou", "lu",
               "liang")
ROOMS = ("base", "geometry", "robot", "calibration", "drivers", "station", "rapid", "mocks")


@pytest.fixture
def extra_method():
    """Register methods in code for one test; the table as it was afterwards."""
    added = []

    def add(method: Method) -> Method:
        added.append(method.name)
        return register_method(method)

    yield add
    for name in added:
        METHODS.unregister(name)


def test_the_table_holds_every_method_once_with_its_kind():
    assert set(CONVENTIONS) <= set(METHODS) and DEFAULT_METHOD in METHODS
    assert ALL_METHODS == method_names() and PAPER_METHODS == method_names("paper")
    assert {m.kind for m in METHODS.values()} == set(KINDS)
    assert all(isinstance(m, Method) and m.name == name and m.citation for name, m in METHODS.items())
    assert get_method("TSAI") is METHODS["tsai"] and get_method("nope") is None


def test_the_default_method_is_defined_once():
    import handeye.calibration.methods as methods

    assert solve.DEFAULT_METHOD is methods.DEFAULT_METHOD == "ml"
    assignments = [f"{path.relative_to(REPO / 'src' / 'handeye')}" for room in ROOMS for path in sorted((REPO / "src" / "handeye" / room).rglob("*.py"))
                   for line in path.read_text().splitlines() if line.startswith("DEFAULT_METHOD =")]
    assert assignments == ["calibration/methods.py"]


def test_classic_rows_hold_the_solvers_of_the_classic_package():
    rows = {name: METHODS[name] for name in method_names("classic")}
    assert {name: m.load() for name, m in rows.items()} == CLASSIC_METHODS
    assert all(CLASSIC_METHODS[name] is getattr(classic, f"solve_{name}") for name in rows)
    assert all(m.source.endswith(m.citation[-5:-1]) for m in rows.values())  # the year of the full reference


def test_a_row_is_checked_when_it_is_made():
    with pytest.raises(ValueError, match="kind 'other' is not one of paper, estimator, classic"):
        Method("x", "other", "Me (2025)", solver="m:f")
    with pytest.raises(ValueError, match="method 'x' of kind classic needs a solver"):
        Method("x", "classic", "Me (2025)")


def test_a_classic_result_names_its_reference_from_the_table():
    problem = make_problem(8, sigma_cam=0.5, seed=3)[0]
    assert calibrate(problem, "tsai").details["reference"] == "Tsai & Lenz (1989)."
    assert calibrate(problem, "chou").details["reference"] == "Chou & Kamel (1991), quaternion SVD then translation."


def test_calibrate_solves_with_the_solver_in_the_table(monkeypatch):
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=3)
    calls = []

    def spy(hand, target2cam, pairs=None):
        calls.append(len(hand))
        return classic.solve_park(hand, target2cam)

    monkeypatch.setitem(METHODS, "park", replace(METHODS["park"], solver=spy))
    result = calibrate(problem, "park")
    assert calls == [8] and np.allclose(result.x, classic.solve_park(problem.hand, problem.target2cam))


def test_a_method_of_each_kind_added_to_the_table_is_dispatched_from_its_row(extra_method):
    # no change to solve.py or selection.py: the row's kind says how its solver is called
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=3)
    extra_method(Method("mco2", "paper", "Me (2025)", "d_org again", least_d_org))
    extra_method(Method("robust2", "estimator", "Me (2025)", "robust again", "handeye.calibration.robust:solve_robust"))
    extra_method(Method("park2", "classic", "Me (2025)", "Park again", classic.solve_park))
    for new, old in (("mco2", "mco"), ("robust2", "robust"), ("park2", "park")):
        ours, theirs = calibrate(problem, new), calibrate(problem, old)
        assert ours.method == new and np.array_equal(ours.x, theirs.x) and ours.outliers == theirs.outliers
        assert ours.residuals_mm == theirs.residuals_mm and ours.residuals_on == theirs.residuals_on
    assert calibrate(problem, "park2").details == {"reference": "Me (2025), Park again."}
    assert method_names()[-3:] == ("mco2", "robust2", "park2") and "mco2" in solve.PAPER_METHODS  # read now


def test_a_selection_criterion_is_named_by_its_row_or_given_as_a_function(extra_method):
    from handeye.calibration.selection import CandidateScorer
    from handeye.calibration.triplets import relative_motions, triplet_candidates

    problem = make_problem(8, sigma_cam=0.5, seed=3)[0]
    motions = relative_motions(problem)
    candidates = triplet_candidates(problem, motions)
    scorer = CandidateScorer(problem.hand, problem.compact.points)
    by_name = select_candidate("mco", candidates, scorer, motions)
    by_function = select_candidate(least_d_org, candidates, scorer, motions)
    assert by_name.index == by_function.index and np.array_equal(by_name.scores, by_function.scores, equal_nan=True)
    extra_method(Method("mco2", "paper", "Me (2025)", "d_org again", least_d_org))
    assert select_candidate("mco2", candidates, scorer, motions).index == by_name.index
    for bad in ("nope", "mc", "tsai"):  # not a row; a paper row without a criterion; not a paper row
        with pytest.raises(ValueError, match=f"unknown selection criterion '{bad}'; use one of mcr, mct, mcb, mco, mcy, mco2$"):
            select_candidate(bad, candidates, scorer, motions)


def test_the_comparison_is_the_rows_marked_for_it(extra_method):
    assert comparison_methods() == ("mc", "mcb", "robust", "tsai", "park", "daniilidis")
    extra_method(Method("park2", "classic", "Me (2025)", "Park again", classic.solve_park, in_comparison=True))
    assert comparison_methods()[-1] == "park2"
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=3)
    rows = assessed(problem, calibrate(problem, "mcb"), methods=comparison_methods()).comparison
    assert {r["method"] for r in rows} == set(comparison_methods())


def test_an_unknown_method_is_refused_in_one_line():
    problem = make_problem(8, sigma_cam=0.5, seed=3)[0]
    with pytest.raises(CalibrationError, match=r"^unknown method 'nope'; choose one of mc, mcr, .*, liang$"):
        calibrate(problem, "NOPE")
    with pytest.raises(CalibrationError, match=r"^mcy needs the true board pose"):
        calibrate(problem, "mcy")


def test_a_solver_that_cannot_be_imported_is_one_line(extra_method):
    problem = make_problem(8, sigma_cam=0.5, seed=3)[0]
    extra_method(Method("gone", "classic", "Me (2025)", solver="handeye_no_such_module:solve"))
    with pytest.raises(CalibrationError, match=r"^the solver of method gone \(handeye_no_such_module:solve\) cannot "
                                               r"be loaded: No module named 'handeye_no_such_module'; reinstall"):
        calibrate(problem, "gone")


def test_the_command_line_names_every_method(extra_method):
    from handeye.station.commands.calibrate import methods_help

    for name in METHODS:
        assert f"\n  {name} " in methods_help(), name
    extra_method(Method("park2", "classic", "Me (2025)", "Park again", classic.solve_park))
    assert "\n  park2       Me (2025), Park again\n" in methods_help()


@pytest.mark.parametrize("name", method_names())
def test_every_method_runs_from_its_row(name):
    problem, truth, _ = make_problem(8, sigma_cam=0.5, seed=5)
    result = calibrate(problem, name, truth if name == "mcy" else None)
    assert result.method == name and np.all(np.isfinite(result.x))
