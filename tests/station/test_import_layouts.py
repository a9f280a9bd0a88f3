"""Logs as other tools write them (tagged rows, P + C rows, matrices over rows, one file per side,
camera-calibration rows per image, extra columns), with random words, separators, conventions,
units and decoys: imported to the truth, or refused naming the flag; never a wrong session."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.base.errors import SessionError
from handeye.station.importers import read_any
from layout_logs import LAYOUTS, Station, station, write_log, same_as_truth


def _read(written):
    return read_any(written.paths if len(written.paths) > 1 else written.paths[0])


@pytest.mark.parametrize("layout", LAYOUTS)
def test_each_layout_imports_the_truth_or_names_the_flag(tmp_path, layout):
    for seed in (LAYOUTS.index(layout), 40 + LAYOUTS.index(layout)):
        st = station(seed, n=14)
        written = write_log(tmp_path, st, layout, seed)
        try:
            session = _read(written)
        except SessionError as exc:
            assert "pass --" in str(exc), (layout, written.words, str(exc))
            continue
        assert same_as_truth(session, st), (layout, written.words, session.extra["import"]["notes"])
        assert session.extra["import"]["notes"][0].startswith("layout: ")


def test_tags_in_any_case_and_the_side_flag(tmp_path):
    st = station(5, n=12, setup="eye_in_hand")
    from layout_logs import encode

    robot, camera = encode(st.tool0, "kuka", "mm", False), encode(st.target, "rotvec", "m", False)
    lines = []
    for a, b in zip(robot, camera):
        lines += ["Alpha: " + " ".join(f"{v:.10g}" for v in a), "BETA: " + " ".join(f"{v:.10g}" for v in b)]
    path = tmp_path / "log.txt"
    path.write_text("\n".join(lines) + "\n")
    session = read_any(path)  # no name says which is which: the board's cone does
    assert same_as_truth(session, st)
    assert any("its boards lie within" in n for n in session.extra["import"]["notes"])
    forced = read_any(path, robot_rows="beta")  # the side flag forces the other reading, whatever it gives
    assert not same_as_truth(forced, st) if forced is not None else True
    with pytest.raises(SessionError, match="--robot-rows gamma"):
        read_any(path, robot_rows="gamma")


def test_a_count_line_and_a_result_matrix_are_not_poses(tmp_path):
    st = station(8, n=10, setup="eye_to_hand")
    from layout_logs import encode

    lines = ["10"]
    for a, b in zip(encode(st.tool0, "m16", "m", False), encode(st.target, "m16", "m", True)):
        for m in (a, b):
            lines += [" ".join(f"{v:.10g}" for v in row) for row in m.reshape(4, 4)] + [""]
    lines += ["# calibration result", "1 0 0 10", "0 1 0 20", "0 0 1 30", "0 0 0 1"]
    path = tmp_path / "matrices.txt"
    path.write_text("\n".join(lines) + "\n")
    try:
        session = read_any(path)
    except SessionError as exc:
        assert "pass --" in str(exc)
        return
    assert same_as_truth(session, st)


def test_image_rows_say_which_columns_were_read_as_what(tmp_path):
    st = station(3, n=12, setup="eye_in_hand")
    written = write_log(tmp_path, st, "image_rows", 3)
    session = _read(written)
    assert same_as_truth(session, st)
    assert "read as a rotation matrix" in session.extra["import"]["notes"][0]
    assert "as the translation" in session.extra["import"]["notes"][0]


@pytest.fixture(scope="module")
def real_stations():
    from helpers import shared_dataset

    out = {}
    for name, file in {"moveit-calibration": "pose_samples.json", "visp-eye-in-hand": None,
                       "camodocal-ar-tag": "TransformPairsInput.yml", "ethz-robot-arm": None}.items():
        folder = shared_dataset(name)
        session = read_any(folder / file if file else folder)
        tool0 = np.array([p.tool0_in_base for p in session.postures])
        target = np.array([p.target_in_camera for p in session.postures])
        out[name] = Station(session.setup, tool0, target, np.eye(4), np.zeros((len(tool0), 6)))
    return out


@pytest.mark.parametrize("layout", ["tag_rows", "p_and_c", "matrix_rows", "two_files"])
def test_real_sets_rewritten_in_other_layouts(tmp_path, real_stations, layout):
    for k, (name, st) in enumerate(real_stations.items()):
        written = write_log(tmp_path / name, st, layout, 100 + k)
        try:
            session = _read(written)
        except SessionError as exc:
            assert "pass --" in str(exc), (name, layout, str(exc))
            continue
        assert same_as_truth(session, st, tol_mm=1e-3, tol_rot=1e-6), (name, layout, written.words)


def test_a_tools_json_log_its_frame_names_and_its_own_result(tmp_path, capsys):
    """A calibration tool's log: per-posture transform pairs among joint lists, frame names and the
    tool's own result; the result is compared in the import output, never read as input."""
    import json

    from handeye.station.cli import main
    from layout_logs import encode

    st = station(21, n=12, setup="eye_in_hand")
    rng = np.random.default_rng(0)
    off = st.x.copy()
    off[:3, 3] += [3.0, 0.0, 4.0]  # the tool's answer, 5 mm from the truth
    log = {"robot_base_frame": "base", "robot_effector_frame": "tool0", "camera": "attached on robot",
           "samples": [{"joints": list(rng.uniform(-90, 90, 6)),
                        "pair": {"a": encode(st.tool0[k:k + 1], "m16", "m", False)[0].reshape(4, 4).tolist(),
                                 "b": encode(st.target[k:k + 1], "m16", "m", False)[0].reshape(4, 4).tolist()}}
                       for k in range(st.tool0.shape[0])],
           "result": {"T camera to tool0": (off * [[1, 1, 1, 1e-3]]).tolist()}}  # in m, as the pairs
    path = tmp_path / "tool_log.json"
    path.write_text(json.dumps(log))
    code = main(["import", str(path), "-o", str(tmp_path / "s")])
    out = capsys.readouterr().out
    assert code == 0
    assert "the frame names say eye_in_hand" in out
    line = next(s for s in out.splitlines() if "the log's own answer" in s)
    mm = float(line.split("differs from ours by ")[1].split(" mm")[0])
    assert 3.0 < mm < 7.0 and "as its name says" in line  # ours is near the truth, theirs 5 mm off
    session = read_any(path)
    assert same_as_truth(session, st, tol_mm=1e-3, tol_rot=1e-6)


def _fake(cone_deg: float, badness: float):
    """A read candidate whose boards lie ``cone_deg`` off the camera axis (for the choice alone)."""
    from types import SimpleNamespace

    from handeye.station.importers.layout_choice import Candidate
    from handeye.station.importers.log_group import Group

    a = np.radians(cone_deg)
    postures = [SimpleNamespace(tool0_in_base=np.eye(4), target_in_camera=np.array(
        [[1, 0, 0, 900 * np.sin(a) * (k % 2)], [0, 1, 0, 0], [0, 0, 1, 900 * np.cos(a * (k % 2))], [0, 0, 0, 1.0]]))
        for k in range(6)]
    record = {"inference": {"scores": {"angle_gap_deg": badness, "axis_misfit_deg": 0.0, "translation_misfit": 0.0}},
              "notes": [], "layout": {}}
    group = Group(np.zeros((6, 7)), [""] * 6)
    return Candidate(group, group, "two lists", "a", "b", 0, swap=1,
                     session=SimpleNamespace(extra={"import": record}, postures=postures, setup="eye_in_hand"))


def test_two_lists_the_content_cannot_tell_apart_are_refused_naming_the_side_flag():
    from handeye.station.importers.layout_choice import choose_layout

    with pytest.raises(SessionError, match=r"cannot tell which list holds the robot poses.*pass --robot-rows a"):
        choose_layout([_fake(20.0, 0.2), _fake(25.0, 0.2)], "log.txt")  # both look like a camera's view
    chosen = choose_layout([_fake(20.0, 0.2), _fake(60.0, 0.2)], "log.txt")
    assert "within 20 deg of the camera axis" in chosen.extra["import"]["notes"][1]


def test_two_different_layouts_within_the_noise_are_refused_and_a_clear_best_names_its_runner_up():
    from handeye.station.importers.layout_choice import choose_layout

    one, two = _fake(20.0, 0.2), _fake(30.0, 0.3)
    one.swap = two.swap = None
    two.words = "another grouping"
    with pytest.raises(SessionError, match=r"two layouts fit within the noise.*pass --robot-rows, or --format"):
        choose_layout([one, two], "log.txt")
    one, two = _fake(20.0, 0.2), _fake(30.0, 2.0)
    one.swap = two.swap = None
    two.words = "another grouping"
    notes = choose_layout([one, two], "log.txt").extra["import"]["notes"]
    assert notes[0] == "layout: two lists (robot poses: 'a')" and notes[1].startswith("layout runner-up: another grouping")
