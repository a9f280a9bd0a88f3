import numpy as np
import pytest
import yaml

from handeye.base.errors import SessionError
from handeye.calibration.session import Posture, Session, create_session, read_session, write_posture
from handeye.geometry.board import BoardGeometry
from handeye.calibration.synthetic import NoiseConfig, sample_session

from helpers import scene


def _write(tmp_path, session):
    path = tmp_path / "s"
    create_session(path, session)
    for p in session.postures:
        write_posture(path, p)
    return path


def test_round_trip(tmp_path):
    session = sample_session(scene(6), NoiseConfig(sigma_cam_mm=1.0, sigma_rob_deg=0.1, seed=1))
    path = _write(tmp_path, session)
    back = read_session(path)
    assert back.setup == "eye_in_hand" and back.robot == "IRB1400"
    assert back.target == BoardGeometry((13, 8), 30.0)
    assert [p.index for p in back.postures] == list(range(6))
    for a, b in zip(session.postures, back.postures):
        assert np.allclose(a.tool0_in_base, b.tool0_in_base, atol=1e-6)
        assert np.allclose(a.joints_deg, b.joints_deg, atol=1e-8)
        assert np.allclose(a.points_mm, b.points_mm, atol=1e-6)
    # files follow the conventions: w >= 0, one posture per file, no temporary files left
    data = yaml.safe_load((path / "postures" / "003.yaml").read_text())
    assert data["index"] == 3 and data["tool0_in_base"]["quaternion_wxyz"][0] >= 0
    assert sorted(f.name for f in (path / "postures").iterdir()) == [f"{i:03d}.yaml" for i in range(6)]


def test_refuses_to_overwrite(tmp_path):
    session = Session(setup="eye_in_hand")
    create_session(tmp_path / "s", session)
    with pytest.raises(SessionError, match="already holds a session"):
        create_session(tmp_path / "s", session)


def _base(tmp_path):
    path = tmp_path / "s"
    create_session(path, Session(setup="eye_in_hand", target=BoardGeometry((3, 2), 10.0)))
    return path


def _posture_file(path, data):
    (path / "postures" / "000.yaml").write_text(yaml.safe_dump(data))


GOOD_POSE = {"position_mm": [1, 2, 3], "quaternion_wxyz": [1, 0, 0, 0]}


@pytest.mark.parametrize("data, message", [
    ({"index": 0, "tool0_in_base": {"position_mm": [1, 2, float("nan")], "quaternion_wxyz": [1, 0, 0, 0]},
      "target_in_camera": GOOD_POSE}, "posture 0 .*position_mm holds nan"),
    ({"index": 0, "tool0_in_base": {"position_mm": [1, 2, 3], "quaternion_wxyz": [1, 0.2, 0, 0]},
      "target_in_camera": GOOD_POSE}, "posture 0 .*not unit"),
    ({"index": 0, "target_in_camera": GOOD_POSE}, "neither tool0_in_base nor joints_deg"),
    ({"index": 0, "tool0_in_base": GOOD_POSE}, "neither points_mm nor target_in_camera"),
    ({"index": 0, "tool0_in_base": GOOD_POSE, "points_mm": [[1, 2], [3, 4]]}, "points_mm must have shape"),
    ({"index": "a", "tool0_in_base": GOOD_POSE, "target_in_camera": GOOD_POSE}, "index must be an integer"),
])
def test_bad_posture_files_name_the_posture(tmp_path, data, message):
    path = _base(tmp_path)
    _posture_file(path, data)
    with pytest.raises(SessionError, match=message):
        read_session(path)


def test_bad_yaml_and_header(tmp_path):
    path = _base(tmp_path)
    (path / "postures" / "000.yaml").write_text("index: [unclosed\n")
    with pytest.raises(SessionError, match="not valid YAML"):
        read_session(path)
    (path / "session.yaml").write_text("format: something-else\n")
    with pytest.raises(SessionError, match="format must be"):
        read_session(path)
    with pytest.raises(SessionError, match="no session folder"):
        read_session(tmp_path / "missing")


def test_duplicate_index(tmp_path):
    path = _base(tmp_path)
    write_posture(path, Posture(index=1, tool0_in_base=np.eye(4), target_in_camera=np.eye(4)))
    (path / "postures" / "005.yaml").write_text((path / "postures" / "001.yaml").read_text())
    with pytest.raises(SessionError, match="appears twice"):
        read_session(path)


def test_stale_temporaries_of_a_killed_writer_are_removed(tmp_path):
    from handeye.base.files import remove_stale_temporaries, write_text_atomic

    write_text_atomic(tmp_path / "postures" / "000.yaml", "index: 0\n")
    stale = tmp_path / "postures" / ".000.yaml.abc123.tmp"
    stale.write_text("index: 0\ntool0_in_")  # what a SIGKILL between write and rename leaves
    keep = tmp_path / "notes.tmp"
    keep.write_text("not ours")
    assert remove_stale_temporaries(tmp_path) == [stale]
    assert not stale.exists() and keep.exists() and (tmp_path / "postures" / "000.yaml").read_text() == "index: 0\n"
