"""Logs as their authors wrote them (issue 40 finding 4): XML-like state lines, section headers,
comment headers naming the columns, folders of per-posture files with the tool's own result and
settings beside them. Every structure is generated from a known station; the import recovers X."""

from __future__ import annotations

import pytest

from handeye.station.importers import read_any
from layout_logs import same_as_truth, station
from structure_logs import commented_log, recovers_x, state_log


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("robot_matrix", [False, True])
def test_a_state_log_with_attribute_poses_and_section_headers(tmp_path, seed, robot_matrix):
    st = station(100 + seed, n=12, setup="eye_in_hand" if seed % 2 == 0 else "eye_to_hand")
    paths = state_log(tmp_path, st, seed, robot_matrix=robot_matrix)
    session = read_any(paths[0])
    assert same_as_truth(session, st, tol_mm=0.01), (seed, session.extra["import"]["notes"])
    assert recovers_x(session, st)


@pytest.mark.parametrize("seed", range(6))
def test_a_comment_header_naming_the_columns_does_not_make_the_log_yaml(tmp_path, seed):
    st = station(200 + seed, n=12, setup="eye_in_hand" if seed % 2 == 0 else "eye_to_hand")
    paths = commented_log(tmp_path, st, seed)
    session = read_any(paths[0])
    assert same_as_truth(session, st, tol_mm=0.01), (seed, session.extra["import"]["notes"])
    assert recovers_x(session, st)
