"""Numbering the distinct sessions an import's readings give (``readings.mark_outcomes``): the same
numbers as comparing every reading with every outcome pose by pose, with a number of full comparisons
that grows with the readings, not with their square (a log read under hundreds of conventions once took
minutes here)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from handeye.station.importers import readings as rd


def _poses(rng, n):
    out = np.tile(np.eye(4), (n, 1, 1))
    out[:, :3, :3] = Rotation.random(n, random_state=rng).as_matrix()
    out[:, :3, 3] = rng.uniform(-500, 500, (n, 3))
    return out


def _reading(k, setup):
    return rd.Reading(robot=k, camera=k, robot_pose="flange_in_base", camera_pose="target_in_camera", setup=setup,
                      units=("mm", "mm"), gap_deg=0.1, axis_deg=0.2, translation=0.01, flange_object="camera",
                      flange_offset_mm=100.0, fixed_distance_mm=800.0, view_spread_deg=20.0, view_front=True,
                      consistent=True)


def _brute_force(outcomes_in, tol_deg):
    """The rule written plainly: each outcome against every earlier distinct one, pose by pose."""
    found, numbers = [], []
    for outcome in outcomes_in:
        k = next((k for k, o in enumerate(found) if rd.same_outcome(o, outcome, tol_deg, 0.5)), None)
        if k is None:
            found.append(outcome)
            k = len(found) - 1
        numbers.append(k)
    return numbers


def _case(rng, distinct, repeats, n=12):
    """``distinct`` random outcomes; ``repeats`` readings that repeat one of them within the noise, or
    agree with one on the probe poses (first, middle, last) but differ in another pose."""
    base = [(_poses(rng, n), _poses(rng, n), rng.choice(["eye_in_hand", "eye_to_hand"])) for _ in range(distinct)]
    outcomes = list(base)
    for _ in range(repeats):
        a, b, setup = base[rng.integers(distinct)]
        a, b = a.copy(), b.copy()
        a[:, :3, 3] += rng.normal(0, 0.05, (n, 3))
        if rng.random() < 0.3:
            b[1, :3, 3] += 5.0  # not a probe pose: only the full comparison tells them apart
        outcomes.insert(rng.integers(len(outcomes) + 1), (a, b, setup))
    return outcomes


def test_outcomes_are_numbered_as_the_plain_rule_and_the_work_grows_linearly(monkeypatch):
    rng = np.random.default_rng(7)
    counts = {}
    for distinct in (100, 400):
        outcomes = _case(rng, distinct, distinct // 4)
        expected = _brute_force(outcomes, 0.1)
        readings = [_reading(k, o[2]) for k, o in enumerate(outcomes)]
        monkeypatch.setattr(rd, "pose_outcome", lambda robot, camera, r: outcomes[r.robot][:2])
        calls = []
        real = rd.same_outcome
        monkeypatch.setattr(rd, "same_outcome", lambda *a: calls.append(1) or real(*a))
        rd.mark_outcomes(None, None, readings, 12)
        monkeypatch.setattr(rd, "same_outcome", real)
        assert [r.outcome for r in readings] == expected
        assert len(set(expected)) > 0.9 * distinct  # the case really has that many distinct outcomes
        counts[distinct] = len(calls)
    # the plain rule compares about distinct^2 / 2 pairs: 5,000 and 80,000 here
    assert counts[400] < 3 * len(_case(np.random.default_rng(0), 400, 100))
    assert counts[400] < 6 * counts[100]


def test_an_outcome_with_nan_is_still_compared_in_full():
    rng = np.random.default_rng(3)
    a, b = _poses(rng, 5), _poses(rng, 5)
    probes = rd.OutcomeProbes(0.1, 0.5)
    probes.add((a, b, "eye_in_hand"))
    other = _poses(rng, 5)
    assert probes.candidates((other, b, "eye_in_hand")) == []
    other[2, 0, 3] = np.nan
    assert probes.candidates((other, b, "eye_in_hand")) == [0]
    assert probes.candidates((a, b, "eye_to_hand")) == []


def test_a_repeat_across_a_cell_boundary_is_found():
    """The grid's cells are the translation tolerance wide: a pose 0.4 mm away in the next cell (and in
    the next cell on all three axes at once) is still a candidate, one 0.6 mm away is not."""
    rng = np.random.default_rng(5)
    a, b = _poses(rng, 5), _poses(rng, 5)
    a[0, :3, 3] = [100.45, -0.05, 20.45]  # cells (200, -1, 40) of 0.5 mm
    probes = rd.OutcomeProbes(0.1, 0.5)
    probes.add((a, b, "eye_in_hand"))
    for shift, expected in (([0.1, 0.0, 0.0], [0]), ([0.2, 0.2, 0.2], [0]), ([0.6, 0.0, 0.0], [])):
        moved = a.copy()
        moved[0, :3, 3] += shift
        assert probes.candidates((moved, b, "eye_in_hand")) == expected, shift
