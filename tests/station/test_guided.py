"""Operator-guided capture (issue 15): a scripted operator jogs the mock arm; the capture watches the
joints, captures at every rest, says what is missing, and writes a session that calibrates as well as
the planned capture does."""

import threading
import time
from dataclasses import replace

import numpy as np
import pytest

from handeye.robot.kinematics import load_robot
from handeye.calibration.session import read_session
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.geometry.transforms import invert_transforms, rotation_error_deg, translation_error_mm
from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
from handeye.station.capture.loop import CaptureError, capture
from handeye.station.cell.plan import cell_check
from handeye.station.config.cell import GuidedSettings
from handeye.station.config.station import default_config
from handeye.station.guided.capture import StillWatch, guided_capture, postures_needed, what_is_missing
from handeye.station.capture.planning import plan_postures
from handeye.station.report.quality import QualityThresholds
from handeye.station.runtime import StationLink, open_station

ROBOT = load_robot("IRB1400")
POSTURES = 16


def _config():
    config = default_config()
    return replace(config, guided=replace(config.guided, still_s=0.3, poll_s=0.03),
                   plan=replace(config.plan, postures=POSTURES, seed=4))


def _operator_poses(config):
    """Where the scripted operator jogs to: good postures around the board (as an operator who knows)."""
    view = invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    return plan_postures(ROBOT, DEFAULT_START, view, DEFAULT_MOUNT, config.target, count=POSTURES, seed=11,
                         cell=cell_check(config)).joints_deg


def _jog_through(link, poses, captured: list, stop: threading.Event, dwell_extra=()):
    """The scripted operator: jog to each pose (the pendant moves the arm), wait until it was captured."""
    def run():
        try:
            for k, target in enumerate(poses):
                before = len(captured)
                link.mock.arm.start_move(target)
                deadline = time.monotonic() + 20
                while len(captured) == before and time.monotonic() < deadline:
                    time.sleep(0.02)
                if k in dwell_extra:  # a nudge of half a degree and a rest: no second capture at the same place
                    link.mock.arm.start_move(target + [0, 0, 0, 0, 0, 0.5])
                    time.sleep(1.0)
        finally:
            stop.set()
    thread = threading.Thread(target=run, name="scripted-operator")
    thread.start()
    return thread


@pytest.fixture(scope="module")
def guided_and_planned(tmp_path_factory):
    config = _config()
    folder = tmp_path_factory.mktemp("guided")
    poses = _operator_poses(config)
    messages, captured = [], []
    with open_station(config, mock=True) as link:
        stop = threading.Event()
        operator = _jog_through(link, poses, captured, stop, dwell_extra={3})
        summary = guided_capture(config, folder / "g", link, progress=messages.append, on_posture=captured.append,
                                 stop=stop)
        operator.join()
        planned = capture(config, folder / "p", link)
        truth = link.truth_cam2tool0
    return config, folder, summary, messages, planned, truth


def _errors(session_dir, truth):
    result = calibrate(problem_from_session(read_session(session_dir)))
    return float(translation_error_mm(result.x, truth)), float(rotation_error_deg(result.x, truth))


def test_the_operator_set_reaches_the_thresholds_coverage(guided_and_planned):
    config, folder, summary, messages, _, _ = guided_and_planned
    assert summary.captured == list(range(POSTURES)) and summary.already == 0
    assert summary.good_enough and summary.missing == []
    assert "missing: postures 0 (needs >= 15): capture 15 more (the first: the board whole in view, about 0.9 m away)" in messages
    assert any(m.startswith("GOOD ENOUGH: 15 postures") for m in messages)
    assert sum("from a captured posture: move on" in m for m in messages) == 1  # the nudge at pose 4: said once
    assert not any(m.startswith("careful:") for m in messages)  # the operator kept clear of the cell


def test_the_guided_session_calibrates_as_well_as_the_planned_one(guided_and_planned):
    _, folder, _, _, planned, truth = guided_and_planned
    assert planned.complete
    guided_mm, guided_deg = _errors(folder / "g", truth)
    planned_mm, planned_deg = _errors(folder / "p", truth)
    assert guided_mm < 0.5 and guided_deg < 0.05  # the demo's targets
    assert guided_mm <= 1.5 * planned_mm + 0.05 and guided_deg <= 1.5 * planned_deg + 0.005


def test_the_session_format_and_the_resume_rules(guided_and_planned):
    config, folder, _, _, _, _ = guided_and_planned
    session = read_session(folder / "g")
    assert session.extra["capture"]["mode"] == "guided" and session.extra["capture"]["station"] == "mock"
    assert [p.index for p in session.postures] == list(range(POSTURES))
    assert all(p.extra["guided"] and p.points_mm.shape == (104, 3) for p in session.postures)
    with open_station(config, mock=True) as link:
        with pytest.raises(CaptureError, match="captured in guided mode: resume it with capture --guided"):
            capture(config, folder / "g", link)
        with pytest.raises(CaptureError, match="holds a planned capture: resume it without --guided"):
            guided_capture(config, folder / "p", link)
        stop = threading.Event()
        stop.set()
        again = guided_capture(config, folder / "g", link, stop=stop)  # resumed: nothing new, nothing twice
    assert again.already == POSTURES and again.captured == [] and again.good_enough
    assert [p.index for p in read_session(folder / "g").postures] == list(range(POSTURES))
    with open_station(replace(config, controller=replace(config.controller, protocol="socket"),
                              camera=replace(config.camera, backend="xb3")).as_mock()) as link:
        real = replace(config, controller=replace(config.controller, protocol="socket"),
                       camera=replace(config.camera, backend="xb3"))
        with pytest.raises(CaptureError, match=r"captured on the mock station \(embedded, or a rehearsal\)"):
            # the real station: its config and a link without a mock part (the socket driver, no mock camera)
            guided_capture(real, folder / "g", StationLink(link.controller, None, link.stereo_model), stop=stop)
        # a real config over the mock's own link is the mock station (the link's mock parts): resumed
        assert guided_capture(real, folder / "g", link, stop=stop).already == POSTURES


def _rotations(axes_angles):
    from scipy.spatial.transform import Rotation

    out = []
    for axis, angle in axes_angles:
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_rotvec(np.radians(angle) * np.asarray(axis, float)).as_matrix()
        out.append(pose)
    return np.array(out)


def test_what_is_missing_names_the_word_the_value_and_what_to_do():
    thresholds = QualityThresholds()
    guided = GuidedSettings()
    # the flange turned about tool0 x and y only: turn about z next
    poses = _rotations([((1, 0, 0), 0), ((1, 0, 0), 30), ((0, 1, 0), 30), ((1, 1, 0), 35), ((1, -1, 0), 25)])
    missing = what_is_missing(poses, np.array([800, 820, 850, 830, 810.0]), {(1, 1), (0, 1)}, thresholds, guided)
    words = {m.word: m for m in missing}
    assert words["postures"].line() == "postures 5 (needs >= 15): capture 10 more"
    assert "turn the flange about tool0 z (axis 6 alone does that) next" in words["rotation-axis spread"].advice
    assert words["distance spread"].now == "50 mm" and "nearer than 800 mm or farther than 850 mm" in \
        words["distance spread"].advice
    assert words["board position in the image"].now == "2 of 9 cells"
    assert "upper left" in words["board position in the image"].advice and "centre" not in \
        words["board position in the image"].advice
    assert postures_needed(thresholds) == 15 and postures_needed(QualityThresholds(min_inlier_postures=20)) == 25
    # before the first posture only the count; after it, turn at all
    assert [m.word for m in what_is_missing(np.zeros((0, 4, 4)), np.zeros(0), set(), thresholds, guided)] == ["postures"]
    one = what_is_missing(poses[:1], np.array([800.0]), {(1, 1)}, thresholds, guided)
    assert [m.word for m in one] == ["postures", "relative rotation angle (median)", "distance spread",
                                     "board position in the image"]
    assert "turn the flange 20-45 deg from this posture" in one[1].advice


def test_the_arm_counts_as_still_once_per_rest():
    watch = StillWatch(1.0, 0.01)
    joints = np.zeros(6)
    assert not watch.update(joints, 0.0)
    assert not watch.update(joints + 0.005, 0.5)  # within the tolerance: still
    assert watch.update(joints, 1.0)
    assert not watch.update(joints, 5.0)  # this rest was reported
    assert not watch.update(joints + 1.0, 5.1)  # moved
    assert not watch.update(joints + 1.0, 5.5)
    assert watch.update(joints + 1.0, 6.2)


def test_guided_over_rws_reads_the_joints_with_no_program_running(tmp_path):
    """On a controller with Robot Web Services the PC reads the joints from the controller itself: guided
    capture needs no RAPID program (no Multitasking option for jogging while it runs)."""
    config = _config()
    config = replace(config, mock=replace(config.mock, protocol="rws"))
    poses = _operator_poses(config)[:4]
    captured = []
    with open_station(config, mock=True) as link:
        link.controller.stop_program()
        assert link.controller.controller_state()["execution"] == "stopped"
        stop = threading.Event()
        operator = _jog_through(link, poses, captured, stop)
        summary = guided_capture(config, tmp_path / "g", link, on_posture=captured.append, stop=stop)
        operator.join()
        assert link.controller.controller_state()["execution"] == "stopped"
    assert summary.captured == [0, 1, 2, 3]
    session = read_session(tmp_path / "g")
    assert [p.index for p in session.postures] == [0, 1, 2, 3]
    assert all(np.allclose(p.joints_deg, q, atol=1e-3) for p, q in zip(session.postures, poses))


def test_the_joint_watching_loop_says_rest_somewhere_new_never_press_start(guided_and_planned):
    """Issue 40.6: the loop that reads the joints captures when the arm rests somewhere new; what it prints
    says that (and how to stop it), never the guided program's keys."""
    config, _, _, messages, _, _ = guided_and_planned
    intro = messages[0]
    assert intro.startswith("guided capture into ")
    assert "the simulated operator jogs the arm" in intro  # the embedded mock has no pendant
    assert f"each time it rests {config.guided.still_s:g} s somewhere new with the board in view, the posture is " \
           "captured" in intro
    good = next(m for m in messages if m.startswith("GOOD ENOUGH:"))
    assert "add more or stop (Ctrl-C)" in good
    for word in ("Start", "press", "Done", "Capture"):  # the pendant program's words
        assert not any(word in m for m in messages), word
