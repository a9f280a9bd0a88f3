"""The forward kinematics of the IRB 1400 model against 20 flange poses of an IRB 1410 from RobotStudio.

The rows (``data/irb1410_robotstudio_targets.csv``, a copy of
``../shared/reference/irb1410-arte/irb1410_robotstudio_targets.csv``; source and licence in its header)
give controller axis angles (deg, as the controller shows them: axis 3 is the parallelogram's axis, not
the serial DH angle) and tool0 in base (mm, quaternion w x y z).

How the comparison is made: the IRB 1410 shares the IRB 1400's arm geometry (the reference README: d1
475, a1 150, a2 600, a3 120, d4 720, flange 85 mm, the same parallelogram coupling of axes 2-3), which is
exactly the package's robot file (``robot/robots/irb1400.yaml``, which also names IRB1410 as an
alias). So the rows are compared with ``load_robot("IRB1400").forward`` as they are, with no frame
correction. (The ARTE meshes beside the rows use a different DH table, d1 and d6 10 mm short; that
concerns only the meshes, not these poses.)

Tolerance: the source writes the joint angles to 0.01 deg, so each is up to 0.005 deg off; at the arm's
reach (about 1.6 m from axis 1 to the flange) that moves the flange up to about 0.14 mm, and six such
errors turn it up to about 0.012 deg. Measured today: 19 rows within 0.105 mm and 0.0085 deg.

Finding on row 7: its axis 1 is written ``-134`` (no decimals, unlike every other angle), and with it the
flange is 5 mm / 0.26 deg off. The axis-1 angle the pose itself implies is -133.73 deg: the wrist centre
(the flange origin moved back along tool0's z by the flange length) lies in the arm's plane, which axis 1
turns, so ``atan2(y, x)`` of the wrist centre is axis 1. With that value row 7 agrees like the others, and
it rounds to the written -134: the source rounded (or mistyped) that one angle. The test recovers the
angle from the pose, checks that the recovery gives back the written axis 1 on the 19 other rows, and
checks row 7 with the recovered angle.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handeye.robot.kinematics import RobotModel, load_robot

from helpers import SHARED

FIXTURE = Path(__file__).with_name("data") / "irb1410_robotstudio_targets.csv"
REFERENCE = SHARED / "reference" / "irb1410-arte" / "irb1410_robotstudio_targets.csv"
POSITION_TOL_MM = 0.15
ANGLE_TOL_DEG = 0.015
ROUNDED_ROW = 7  # the row whose axis 1 the source wrote rounded to whole degrees


def _read(path: Path) -> np.ndarray:
    """Rows ``(20, 14)``: index, six controller angles (deg), x y z (mm), w x y z."""
    lines = [line for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
    assert lines[0].startswith("index,j1"), f"{path}: header row expected first"
    return np.array([[float(v) for v in line.split(",")] for line in lines[1:]])


@pytest.fixture(scope="module")
def robot():
    return load_robot("IRB1400")


@pytest.fixture(scope="module")
def rows():
    return _read(FIXTURE)


def _errors(robot, joints, rows):
    """Position error (mm) and rotation angle (deg) between the model's tool0 and the rows' poses."""
    p, q = robot.forward(joints)
    position = np.linalg.norm(p - rows[:, 7:10], axis=-1)
    dot = np.clip(np.abs(np.sum(q * rows[:, 10:14], axis=-1)), 0.0, 1.0)
    return position, np.degrees(2.0 * np.arccos(dot))


def _axis1_from_pose(robot, rows) -> np.ndarray:
    """Axis 1 (deg) implied by each pose: atan2 of the wrist centre, which is the flange origin moved back
    by the model's wrist-centre-to-tool0 offset (taken in tool0's frame from the home pose)."""
    home = Rotation.from_quat(robot.tool0_home, scalar_first=True)
    offset_in_tool0 = home.inv().apply(robot.links[-1])  # (0, 0, 85) mm for the IRB 1400
    rotation = Rotation.from_quat(rows[:, 10:14], scalar_first=True)
    wrist = rows[:, 7:10] - rotation.apply(offset_in_tool0)
    return np.degrees(np.arctan2(wrist[:, 1], wrist[:, 0]))


def test_fixture_is_the_shared_reference_copy(rows):
    if not REFERENCE.is_file():
        pytest.skip("../shared/reference/irb1410-arte is only beside a development checkout; "
                    "the test fixture's copy of the rows is used instead")
    assert np.array_equal(_read(REFERENCE), rows)


def test_nineteen_rows_agree_with_the_model(robot, rows):
    others = rows[rows[:, 0] != ROUNDED_ROW]
    assert len(others) == 19
    position, angle = _errors(robot, others[:, 1:7], others)
    assert position.max() < POSITION_TOL_MM, dict(zip(others[:, 0].astype(int), position.round(3)))
    assert angle.max() < ANGLE_TOL_DEG, dict(zip(others[:, 0].astype(int), angle.round(4)))


def test_axis1_recovered_from_the_pose_gives_back_the_written_angles(robot, rows):
    others = rows[rows[:, 0] != ROUNDED_ROW]
    # the written angles are rounded to 0.01 deg
    assert np.abs(_axis1_from_pose(robot, others) - others[:, 1]).max() <= 0.005 + 1e-3


def test_row7_axis1_is_written_rounded(robot, rows):
    row = rows[rows[:, 0] == ROUNDED_ROW]
    written = row[:, 1:7]
    position, angle = _errors(robot, written, row)
    assert position[0] > 3.0 and angle[0] > 0.1  # as written, row 7 does not agree (5 mm, 0.26 deg)
    axis1 = _axis1_from_pose(robot, row)[0]
    assert round(axis1) == written[0, 0] == -134.0
    assert abs(axis1 - (-133.73)) < 0.01
    recovered = written.copy()
    recovered[0, 0] = axis1
    position, angle = _errors(robot, recovered, row)
    assert position[0] < POSITION_TOL_MM and angle[0] < ANGLE_TOL_DEG


def test_the_comparison_tells_a_one_millimetre_change_of_the_arm(robot, rows):
    # The tolerance is tight enough to matter: the same table with the forearm (d4) 1 mm longer fails it.
    dh = robot.dh.copy()
    dh[3, 0] += 1.0
    longer = RobotModel.from_dh("IRB1400+1mm", dh, coupling_rows=[[3, 2, -1.0]])
    others = rows[rows[:, 0] != ROUNDED_ROW]
    position, _ = _errors(longer, others[:, 1:7], others)
    assert position.max() > POSITION_TOL_MM
