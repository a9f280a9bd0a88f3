"""Logs as their authors wrote them (issue 40 finding 4): XML-like state lines, section headers,
comment headers naming the columns, folders of per-posture files with the tool's own result and
settings beside them. Every structure is generated from a known station; the import recovers X."""

from __future__ import annotations

import pytest

from handeye.station.importers import read_any
from layout_logs import same_as_truth, station
from handeye.base.errors import SessionError
from structure_logs import commented_log, dump_json, posture_files_folder, recovers_x, side_files_folder, state_log


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


@pytest.mark.parametrize("seed", range(3))
def test_a_folder_of_side_files_with_the_result_and_settings_beside(tmp_path, seed):
    st = station(300 + seed, n=12, setup="eye_in_hand" if seed % 2 == 0 else "eye_to_hand")
    folder = side_files_folder(tmp_path, st, seed)[0]
    session = read_any(folder)  # the format detected from the folder's content
    assert same_as_truth(session, st, tol_mm=0.01), (seed, session.extra["import"]["notes"])
    assert recovers_x(session, st)
    note = next(n for n in session.extra["import"]["notes"] if n.startswith(f"in {folder.name}: read"))
    assert "settings.ini (settings)" in note and "the tool's result" in note
    result = next(p.name for p in folder.iterdir() if "result" in p.name)
    assert result in note


@pytest.mark.parametrize("seed", range(6))
def test_a_folder_of_per_posture_files_with_images_result_and_settings(tmp_path, seed):
    st = station(400 + seed, n=12, setup="eye_in_hand" if seed % 2 == 0 else "eye_to_hand")
    folder = posture_files_folder(tmp_path, st, seed)[0]
    session = read_any(folder)
    assert same_as_truth(session, st, tol_mm=0.01), (seed, session.extra["import"]["notes"])
    assert recovers_x(session, st)
    note = next(n for n in session.extra["import"]["notes"] if n.startswith(f"in {folder.name}: read 12 per-posture"))
    assert "(12 files: images)" in note and "settings.ini (settings)" in note and "handeye_result.json" in note


def test_a_folder_of_unrelated_files_is_refused_in_one_line(tmp_path):
    (tmp_path / "notes.txt").write_text("nothing here but words\n")
    (tmp_path / "a.ini").write_text("[x]\ny=1\n")
    with pytest.raises(SessionError, match="give the log file"):
        read_any(tmp_path, format="log")


def test_nested_column_vectors_are_a_position_and_a_rotation_vector(tmp_path):
    from scipy.spatial.transform import Rotation

    st = station(500, n=12, setup="eye_in_hand")
    items = [{"robot": m.ravel().tolist(),
              "board": {"rvec": [[float(v)] for v in Rotation.from_matrix(c[:3, :3]).as_rotvec()],
                        "tvec": [[float(v)] for v in c[:3, 3]]}} for m, c in zip(st.tool0, st.target)]
    path = tmp_path / "samples.json"
    dump_json(path, items)
    session = read_any(path)
    assert same_as_truth(session, st, tol_mm=0.01)
