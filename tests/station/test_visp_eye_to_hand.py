"""ViSP's hand-eye app folders eye-to-hand (``visp-compute-eye-to-hand-calibration``), AprilTag or chessboard:
tag pose files ``pose_cPo_<i>.yaml`` as ``visp-compute-apriltag-poses`` writes them, or the images
and the tag size (``--tag-mm``), the set-up and directions inferred from the data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.base.errors import SessionError
from handeye.calibration.solve import calibrate_session
from handeye.geometry.transforms import rotation_error_deg
from handeye.robot.views import NOMINAL_XB3_LEFT as CAM
from handeye.station.importers import read_any

from pose_logs import Truth

TAG_MM = 160.0
K = np.array([[CAM.f_px, 0, CAM.cx], [0, CAM.f_px, CAM.cy], [0, 0, 1.0]])


@pytest.fixture(scope="module")
def eth():
    truth = Truth("eye_to_hand", postures=10, sigma_cam=0.0, sigma_rob=0.0)
    # the tag sits at the board's centre, in the board's plane: tag frame = conventions' target frame
    # moved to the centre (x right, y down as printed, z into the tag)
    centre = np.eye(4)
    centre[:3, 3] = [6 * 30.0, 3.5 * 30.0, 0.0]
    truth.tag = truth.target @ centre
    return truth


def _pose_vector_yaml(t, metres=True):
    v = np.concatenate([t[:3, 3] / (1000.0 if metres else 1.0), Rotation.from_matrix(t[:3, :3]).as_rotvec()])
    return "rows: 6\ncols: 1\ndata:\n" + "".join(f"  - [{float(x)!r}]\n" for x in v)


def render_tag(tag2cam, size_px=(CAM.width, CAM.height), px_per_mm=2.0, quiet_mm=40.0):
    """A grey image of AprilTag 36h11 number 7 (side ``TAG_MM``) at ``tag2cam`` (mm)."""
    import cv2

    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    side = int(round(TAG_MM * px_per_mm))
    marker = cv2.aruco.generateImageMarker(dictionary, 7, side, borderBits=1)
    quiet = int(round(quiet_mm * px_per_mm))
    texture = np.full((side + 2 * quiet, side + 2 * quiet), 255, np.uint8)
    texture[quiet:quiet + side, quiet:quiet + side] = marker
    offset = TAG_MM / 2.0 + quiet_mm  # texture pixel (0, 0) -> tag frame (-offset, -offset)
    half = 0.5 / px_per_mm
    a = np.array([[1 / px_per_mm, 0, half - offset], [0, 1 / px_per_mm, half - offset], [0, 0, 1.0]])
    h = K @ np.column_stack([tag2cam[:3, 0], tag2cam[:3, 1], tag2cam[:3, 3]]) @ a
    up = np.diag([3.0, 3.0, 1.0]) @ np.array([[1, 0, 1.0 / 3], [0, 1, 1.0 / 3], [0, 0, 1]])
    big = cv2.warpPerspective(texture, up @ h, (3 * size_px[0], 3 * size_px[1]), flags=cv2.INTER_LINEAR, borderValue=128)
    return cv2.resize(big, size_px, interpolation=cv2.INTER_AREA)


def _camera_xml(path):
    path.write_text(f"""<?xml version="1.0"?>
<root><camera><name>Camera</name><image_width>{CAM.width}</image_width><image_height>{CAM.height}</image_height>
<model><type>perspectiveProjWithoutDistortion</type><px>{K[0, 0]}</px><py>{K[1, 1]}</py><u0>{K[0, 2]}</u0><v0>{K[1, 2]}</v0>
</model></camera></root>
""")


def test_apriltag_images_eye_to_hand(tmp_path, eth):
    import cv2

    folder = tmp_path / "data-eye-to-hand"
    folder.mkdir()
    for i, (a, tag) in enumerate(zip(eth.tool0, eth.tag), start=1):
        (folder / f"franka_pose_rPe_{i}.yaml").write_text(_pose_vector_yaml(a))
        cv2.imwrite(str(folder / f"franka_image-{i}.png"), render_tag(tag))
    _camera_xml(folder / "franka_camera.xml")
    with pytest.raises(SessionError, match=r"pass --tag-mm MM \(an AprilTag 36h11\) or --board"):
        read_any(folder)
    session = read_any(folder, tag_mm=TAG_MM)
    record = session.extra["import"]
    assert record["format"] == "visp" and len(session.postures) == eth.n and session.setup == "eye_to_hand"
    assert "AprilTag 36h11, 160 mm" in record["board_measurement"]["target"]
    measured = np.array([p.target_in_camera for p in session.postures])
    assert np.max(np.linalg.norm(measured[:, :3, 3] - eth.tag[:, :3, 3], axis=1)) < 5.0
    assert np.max(rotation_error_deg(measured, eth.tag)) < 1.0
    result = calibrate_session(session, "mcb")
    assert result.setup == "eye_to_hand"
    assert np.linalg.norm(result.x[:3, 3] - eth.x[:3, 3]) < 10.0 and rotation_error_deg(result.x, eth.x) < 0.5
    # the app folder states the tag's size in its own file, as chessboard-data.txt does the board's
    (folder / "apriltag-data.txt").write_text(f"AprilTag\nfamily: 36h11\nsize: {TAG_MM / 1000.0} m\n")
    stated = read_any(folder)
    assert "AprilTag 36h11, 160 mm" in stated.extra["import"]["board_measurement"]["target"]
    assert np.allclose([p.target_in_camera for p in stated.postures], measured)
    (folder / "apriltag-data.txt").write_text("AprilTag\nfamily: 25h9\nsize: 0.16 m\n")
    with pytest.raises(SessionError, match="only 36h11 is detected"):
        read_any(folder)


def test_apriltag_pose_files_eye_to_hand(tmp_path, eth):
    """pose_rPe + pose_cPo as ViSP writes them, with ViSP's default tag frame (z out of the tag, towards
    the camera). Seen head-on, a tag's pose reads as well inverted with the other set-up; ViSP's file
    names (rPe, cPo) break that tie."""
    folder = tmp_path / "poses"
    folder.mkdir()
    visp_tag = np.diag([1.0, -1.0, -1.0, 1.0])  # 180 deg about x: y up, z out of the tag
    for i, (a, tag) in enumerate(zip(eth.tool0, eth.tag), start=1):
        (folder / f"pose_rPe_{i}.yaml").write_text(_pose_vector_yaml(a))
        (folder / f"pose_cPo_{i}.yaml").write_text(_pose_vector_yaml(tag @ visp_tag))
    session = read_any(folder)
    assert session.setup == "eye_to_hand"
    record = session.extra["import"]
    assert "camera poses read as target in camera" in record["conventions"]["camera"]
    assert record["conventions"]["decided_by"][-1] == "what the file declares"
    assert any("the data alone also fit eye_in_hand" in note for note in record["notes"])
    result = calibrate_session(session, "mcb")
    assert np.linalg.norm(result.x[:3, 3] - eth.x[:3, 3]) < 1e-4 and rotation_error_deg(result.x, eth.x) < 1e-5


def test_chessboard_images_eye_to_hand(tmp_path, eth):
    """The same app folder with a chessboard on the flange (chessboard-data.txt): eye-to-hand from the data."""
    import cv2

    from test_importers import render_board

    folder = tmp_path / "chessboard"
    folder.mkdir()
    for i, (a, b) in enumerate(zip(eth.tool0, eth.target), start=1):
        (folder / f"ur_pose_rPe_{i}.yaml").write_text(_pose_vector_yaml(a))
        cv2.imwrite(str(folder / f"ur_image-{i}.png"), render_board(b, (13, 8), 30.0, K, (CAM.width, CAM.height),
                                                                     px_per_mm=3.0))
    _camera_xml(folder / "ur_camera.xml")
    (folder / "chessboard-data.txt").write_text("Chessboard\n13 x 8\nsquare size: 0.030 m\n")
    session = read_any(folder)
    assert session.setup == "eye_to_hand" and len(session.postures) == eth.n
    assert "detected from the data" in session.extra["import"]["setup_how"]
    result = calibrate_session(session, "mcb")
    assert np.linalg.norm(result.x[:3, 3] - eth.x[:3, 3]) < 10.0 and rotation_error_deg(result.x, eth.x) < 0.5
