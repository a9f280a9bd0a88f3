"""``handeye verify`` on a ChArUco session with occlusion (issue 37): the embedded mock station (a real TCP
controller server, rendered XB3 frames) captures a ChArUco session with a band over part of the board at
a third of the postures (``mock.occlude``); the check revisits some of those partial postures (board
points by id) and says OK when nothing changed, and names the cause of an injected fault."""

from __future__ import annotations

import numpy as np
import pytest

from handeye.calibration.session import read_session
from helpers import mock_baseline, mock_station_config, verify_against

BASE_YAML = ("controller: {protocol: mock}\ncamera: {backend: mock}\nplan: {postures: 14}\nboard: {type: charuco}\n"
             "mock:\n  occlude: {postures: 0.35}\n")


def _config(folder, name: str, faults: str = "") -> str:
    return mock_station_config(folder, name, BASE_YAML, faults)


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    root = tmp_path_factory.mktemp("verify_charuco")
    return root, mock_baseline(root, _config(root, "mock"))


def _verify(station, name: str, faults: str = ""):
    root, session = station
    return verify_against(root, session, _config(root, name, faults), name)


def _partial_postures(folder) -> list:
    return [p.index for p in read_session(folder).postures if p.corner_ids is not None and len(p.corner_ids) < 104]


def test_the_session_holds_partial_views(station):
    _, session = station
    assert len(_partial_postures(session)) >= 3


def test_nothing_changed_is_ok_with_partial_views_among_the_checked(station):
    code, data = _verify(station, "none")
    assert code == 0 and data["verdict"] == "ok", data
    assert data["measured"] == data["postures"] == 5
    assert data["diagnosis"]["cause"] == "none"
    assert _partial_postures(data["check_session"]), "the check saw no partial view: the test would not test them"


def test_a_camera_move_is_named_with_its_size(station):
    shift = np.array([0.9, -0.8, 0.6])  # 1.34 mm
    code, data = _verify(station, "camera", f"camera_shift_mm: {shift.tolist()}, camera_turn_deg: [0.05, -0.08, 0.1]")
    assert code == 3 and data["verdict"] == "drift"
    assert data["diagnosis"]["cause"] == "camera"
    assert data["diagnosis"]["translation_mm"] == pytest.approx(np.linalg.norm(shift), rel=0.3)
    assert _partial_postures(data["check_session"])


def test_a_joint_zero_is_named(station):
    code, data = _verify(station, "joint3", "joint_zero_deg: [0, 0, 0.08, 0, 0, 0]")
    assert code == 3 and data["diagnosis"]["cause"] == "joint" and data["diagnosis"]["joint"] == 3
