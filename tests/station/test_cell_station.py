"""The cell at the station (issue 15): the mock arm refuses moves into the cell as world zones would, the
generated RAPID declares the world zones and the speed override, capture previews and plans without
moving, motion waits for confirmation at a real station, and the config's cell keys are checked."""

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
import yaml

from handeye.robot.cell import Box, CellModel, Floor
from handeye.robot.clearance import CellGuard
from handeye.robot.kinematics import load_robot
from handeye.calibration.session import read_session
from handeye.drivers.controller import open_controller
from handeye.drivers.errors import StationError
from handeye.mocks.controller import start_mock_controller
from handeye.mocks.robot import SimulatedRobot, ZoneViolation
from handeye.rapid.checks import check_program
from handeye.rapid.generate import render_program, write_modules
from handeye.rapid.station import station_from_dict
from handeye.station.capture.loop import CaptureError, capture
from handeye.station.config.cell import DEFAULT_CARRIED
from handeye.station.config.station import ConfigError, config_from_dict, default_config
from handeye.station.runtime import StationLink, open_station

ROBOT = load_robot("IRB1400")
A = np.array([-40.0, 10, 10, 0, 60, 0])
B = np.array([40.0, 10, 10, 0, 60, 0])
MOCK = {"controller": {"protocol": "mock"}, "camera": {"backend": "mock"}}


def _post_between():
    """A post the move A -> B sweeps the wrist through, clear of both ends."""
    mid = ROBOT.forward_transform((A + B) / 2)[:3, 3]
    return Box("post", tuple(mid - 60), tuple(mid + 60))


# ------------------------------------------------------------------------------------------- the mock arm
def test_the_mock_arm_refuses_a_move_whose_path_enters_the_cell():
    guard = CellGuard(ROBOT, [_post_between()], DEFAULT_CARRIED, margin_mm=0.0, step_mm=5.0)
    arm = SimulatedRobot([A, B], start_joints=A, time_scale=0.001, guard=guard)
    with pytest.raises(ZoneViolation, match="world zone: .* would enter 'post' on the way to posture 2"):
        arm.start_posture(2)
    assert np.array_equal(arm.current_joints, A) and arm.moves == 0 and len(arm.refusals) == 1
    arm.guard = None  # no cell: the same move runs
    arm.start_posture(2)
    assert arm.wait_until_stopped(timeout=5) and np.allclose(arm.current_joints, B)


@pytest.mark.parametrize("protocol", ["socket", "modbus"])
def test_the_mock_controller_stops_the_program_before_such_a_move(protocol, no_leaked_threads):
    """The interpreted RAPID's MoveAbsJ into the cell stops the program as motion supervision would: the
    arm stays, the PC gets an error (no link / program stopped), the reason names the volume."""
    guard = CellGuard(ROBOT, [_post_between()], DEFAULT_CARRIED, margin_mm=0.0, step_mm=5.0)
    arm = SimulatedRobot([A, B], start_joints=A, time_scale=0.001, guard=guard)
    with start_mock_controller(protocol, robot=arm, postures=[A, B]) as server:
        with open_controller(protocol, timeout=1.0, motion_timeout=5.0, **server.client_options()) as controller:
            with pytest.raises(StationError):
                controller.goto_posture(2)
                controller.wait_at_rest()
        assert "would enter 'post' on the way to posture 2" in server.program_error
    assert np.array_equal(arm.current_joints, A) and arm.moves == 0 and len(arm.refusals) == 1


def test_the_embedded_mock_station_carries_the_configured_cell(no_leaked_threads):
    config = config_from_dict({**MOCK, "cell": {"keep_out": [{"type": "floor", "z_mm": 0},
                                                             {"type": "box", "name": "cabinet", "min_mm": [500, 250, 0],
                                                              "max_mm": [1200, 700, 1400]}]}})
    with open_station(config) as link:
        guard = link.mock.arm.guard
        names = [v.name for v in guard.volumes]
        assert names == ["floor", "cabinet", "board stand"] and guard.margin_mm == 0
        # the stand is built around the TRUE board, not an estimate
        board = link.mock.truth["board2base"]
        assert guard.volumes[2].signed_distance(board[:3, 3]) < -40


# ------------------------------------------------------------------------------------------------ RAPID
def _zoned_config(**cell):
    return config_from_dict({**MOCK, "motion": {"speed_override_pct": 25},
                             "cell": {"world_zones": True, **cell,
                                      "keep_out": [{"type": "floor", "z_mm": -5},
                                                   {"type": "cylinder", "name": "column", "centre_mm": [-400, 700],
                                                    "radius_mm": 120, "z_mm": [0, 2200]}]}})


def test_world_zones_and_the_speed_override_in_the_program(tmp_path):
    config = _zoned_config()
    postures = [[0, 0, 0, 0, 30, 0], [10, 0, 0, 0, 30, 0]]
    board = np.eye(4)
    board[:3, 3] = [900, 0, 60]
    station = station_from_dict(config.rapid_dict(postures, board), "test")
    modules = render_program(station)
    names = [m.name for m in modules]
    assert names == ["HeMain", "HeSocket", "HeTool", "HeCell"]
    main, cell = modules[0].text, modules[3].text
    assert "    HeCellSetup;\n    heState := HE_READY;" in main
    assert main.count("fine, tHeCamZone;") == 2 and "tool0;" not in main
    assert "VelSet HE_SPEED_OVERRIDE, HE_MAX_TCP;" in cell and "HE_SPEED_OVERRIDE := 25;" in cell
    assert cell.count("WZLimSup \\Temp") == 4  # floor, column, board stand and its leg (the board is above the floor)
    assert "! zone 3: board stand\n" in cell and "! zone 4: board stand leg\n" in cell
    assert "WZCylDef \\Inside, heShape, pHeZone2Base, 120, 2200;" in cell
    assert "CONST pos pHeZone1Hi := [10000,10000,-5];" in cell
    assert "PERS tooldata tHeCamZone := [TRUE,[[-115,30,95],[0.707107,0,0,0.707107]]" in cell
    paths = write_modules(modules, tmp_path / "rapid")
    result = subprocess.run([sys.executable, "-m", "rapidchecker", *map(str, paths)], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    texts = [(m.name, m.text) for m in modules]
    assert check_program(texts, approved=postures, move_tools=("tool0", "tHeCamZone")) == []
    refused = check_program(texts, approved=postures)  # tool0 only: the camera tool is refused
    assert any("MoveAbsJ must use tool0" in f.message for f in refused)


def test_without_the_flag_the_program_is_the_one_it_always_was():
    config = config_from_dict(MOCK)
    postures = [[0, 0, 0, 0, 30, 0]]
    modules = render_program(station_from_dict(config.rapid_dict(postures), "test"))
    assert [m.name for m in modules] == ["HeMain", "HeSocket", "HeTool"]
    assert "HeCell" not in modules[0].text and "fine, tool0;" in modules[0].text


# ----------------------------------------------------------------------------------------- capture
def _small(config, postures=6):
    return replace(config, plan=replace(config.plan, postures=postures))


def test_plan_only_writes_plan_preview_and_program_and_moves_nothing(tmp_path, no_leaked_threads):
    config = _small(default_config())
    with open_station(config, mock=True) as link:
        summary = capture(config, tmp_path / "s", link, plan_only=True)
        assert link.mock.arm.moves == 0 and summary.captured == []
        record = read_session(tmp_path / "s").extra["capture"]
        assert (tmp_path / "s" / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert sorted(p.name for p in (tmp_path / "s" / "rapid").iterdir()) == ["HeMain.mod", "HeSocket.mod", "HeTool.mod"]
        # the tube's capsule fitted to the meshes (issue 41: radius 110 mm, was 75) refuses two of the draws
        # (the camera, the bracket against link 3), which are drawn again; no move is refused
        rejections = record["plan_score"]["rejections"]
        assert len(rejections) == 2 and all(line.endswith("against link 3") for line in rejections), rejections
        assert record["plan_score"]["rejected_moves"] == 0
        again = capture(config, tmp_path / "s", link)  # the same plan, captured now
    assert again.complete and again.captured == list(range(6))
    assert read_session(tmp_path / "s").extra["capture"]["plan_joints_deg"] == record["plan_joints_deg"]


def test_a_real_station_moves_only_after_a_yes(tmp_path, no_leaked_threads):
    config = _small(default_config(), 4)
    messages = []
    with open_station(config, mock=True) as link:
        real = StationLink(link.controller, link.camera, link.stereo_model, link.load_program)  # no mock: asks
        with pytest.raises(CaptureError, match="motion needs the operator's confirmation.*--yes"):
            capture(config, tmp_path / "s", real)
        assert link.mock.arm.moves == 0
        asked = []
        with pytest.raises(CaptureError, match="not confirmed: nothing moved"):
            capture(config, tmp_path / "s", real, confirm=lambda q: asked.append(q) or False)
        assert link.mock.arm.moves == 0 and "move the robot through 4 postures" in asked[0]
        summary = capture(config, tmp_path / "s", real, confirm=lambda q: True)
        assert summary.complete
        capture(config, tmp_path / "s2", link, progress=messages.append)
    assert any("without asking (mock station" in m for m in messages)


def test_the_report_shows_the_preview(tmp_path, no_leaked_threads):
    from handeye.station.report.assessment import assess
    from handeye.station.calibrate import calibrate_session_folder
    from handeye.station.report.document import write_report

    config = _small(default_config(), 12)
    with open_station(config, mock=True) as link:
        capture(config, tmp_path / "s", link)
    assessment = assess(calibrate_session_folder(tmp_path / "s"))
    assert assessment.plan_preview == (tmp_path / "s" / "preview.png").read_bytes()
    html = write_report(tmp_path / "r.html", assessment).read_text()
    assert "Capture plan: the cell" in html


def test_the_preview_is_readable(tmp_path):
    import test_report_figures as figures

    from handeye.geometry.board import BoardGeometry
    from handeye.geometry.transforms import invert_transforms
    from handeye.mocks.station import DEFAULT_BOARD, DEFAULT_MOUNT, DEFAULT_START
    from handeye.station.cell.plan import CellCheck
    from handeye.station.capture.planning import plan_postures
    from handeye.station.cell.preview import plan_preview_figure

    view = invert_transforms(ROBOT.forward_transform(DEFAULT_START) @ DEFAULT_MOUNT) @ DEFAULT_BOARD
    cell = CellModel((Floor("floor", 0.0), Box("cabinet", (500, 250, 0), (1200, 700, 1400))), DEFAULT_CARRIED)
    plan = plan_postures(ROBOT, DEFAULT_START, view, DEFAULT_MOUNT, BoardGeometry((13, 8), 30.0), count=30, seed=1,
                         cell=CellCheck(cell))
    fig = plan_preview_figure(ROBOT, plan)
    assert figures.overlapping_texts(fig) == []
    numbers = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert set(numbers) <= {str(k) for k in range(30)} and len(numbers) >= 40  # most in both views
    patches = [p for ax in fig.axes for p in ax.patches]
    assert len(patches) >= 5  # floor (side), cabinet (both), stand (both)


# -------------------------------------------------------------------------------------------- config
@pytest.mark.parametrize("cell, words", [
    ({"keep_out": [{"type": "sphere", "centre_mm": [0, 0, 0]}]}, r"cell.keep_out\[0\].type must be one of box, floor, cyl"),
    ({"keep_out": [{"type": "box", "min_mm": [0, 0, 0], "max_mm": [10, -5, 10]}]}, r"cell.keep_out\[0\]: min_mm\[1\]"),
    ({"keep_out": [{"type": "floor"}]}, r"cell.keep_out\[0\] \(floor\) needs z_mm"),
    ({"keep_out": [{"type": "floor", "z_mm": 0, "height": 3}]}, r"unknown key cell.keep_out\[0\].height"),
    ({"keep_out": [{"type": "floor", "z_mm": 0}, {"type": "floor", "z_mm": 5}]}, "'floor' is used twice"),
    ({"carried": [{"type": "sphere", "centre_mm": [500, 500, 500], "radius_mm": 10}]},
     "camera.nominal_mount puts the camera .* mm from every body of cell.carried"),
    ({"margin_mm": 10, "path_step_mm": 20}, r"cell.path_step_mm \(20\) must not exceed cell.margin_mm \(10\)"),
    ({"world_zones": "yes"}, "cell.world_zones must be true or false"),
])
def test_bad_cell_keys_are_refused_naming_the_key(cell, words):
    with pytest.raises(ConfigError, match=words):
        config_from_dict({**MOCK, "cell": cell})


def test_the_cell_keys_read_back_from_the_session_record():
    config = config_from_dict({**MOCK, "cell": yaml.safe_load("""
        keep_out:
          - {type: floor, z_mm: -10}
          - {type: box, name: fixture, min_mm: [1001, 202, 3], max_mm: [1404, 505, 606]}  # clear of the base
          - {type: cylinder, centre_mm: [0, 700], radius_mm: 100, z_mm: [0, 2000]}
        stand_margin_mm: null
        world_zones: true
        """), "guided": {"still_s": 0.5}, "motion": {"speed_override_pct": 30}})
    again = config_from_dict(config.to_dict(), "record")
    assert again.cell == config.cell and again.guided == config.guided and again.motion == config.motion
    assert again.cell.model().volumes(np.eye(4)) == list(config.cell.keep_out)  # no stand: null
    assert [v.name for v in config.cell.keep_out] == ["floor", "fixture", "cylinder 2"]
    assert config.cell.model() == CellModel(config.cell.keep_out, DEFAULT_CARRIED, None, 100.0)
    assert Floor("floor", -10.0) in config.cell.keep_out
