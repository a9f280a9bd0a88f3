"""Duplicated postures are reported once per group of equal poses, not once per pair (issue 25, finding 7d)."""

from __future__ import annotations

import numpy as np

from handeye.calibration import diagnostics

from helpers import scene


def _poses():
    s = scene(12)
    return s.tool02base().copy(), s.target2cam().copy()


def test_a_pose_taken_four_times_is_one_finding():
    a, b = _poses()
    for k in (3, 7, 10):  # postures 3, 7 and 10 repeat posture 2
        a[k], b[k] = a[2], b[2]
    findings = diagnostics.find_duplicates(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("duplicate_posture", (2, 3, 7, 10))]
    message = findings[0].message
    assert message.startswith("postures 3, 7, 10 are the same robot pose as posture 2")
    assert "the board pose too" in message and "\n" not in message


def test_two_groups_and_a_pair_keep_the_pair_wording():
    a, b = _poses()
    a[5], b[5] = a[1], b[1]
    a[9], a[11] = a[4], a[4]
    b[9] = b[4]
    b[11] = b[4].copy()
    b[11][0, 3] += 5.0  # the board moved for one of them
    findings = diagnostics.find_duplicates(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("duplicate_posture", (1, 5)),
                                                        ("duplicate_posture", (4, 9, 11))]
    assert findings[0].message.startswith("postures 1 and 5: the same robot pose")
    assert "board poses differ by up to 5.0 mm" in findings[1].message


def test_stale_board_frames_are_grouped():
    a, b = _poses()
    b[5] = b[6] = b[8] = b[4]  # the camera frame did not update while the robot moved
    findings = diagnostics.find_duplicates(a, b)
    assert [(f.kind, f.postures) for f in findings] == [("stale_target", (4, 5, 6, 8))]
    assert findings[0].message.startswith("postures 5, 6, 8 show the same board pose as posture 4")
    assert "drop postures 5, 6, 8" in findings[0].message
