"""What write-back and the verdict tell the operator (issue 25, findings 7e and 7f): a classic method
fails the verdict for want of an uncertainty, so the advice is the default method, not a better
session; a camera frame 14 mm from the flange in a session in mm is too near, not metres."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from handeye.calibration.methods import DEFAULT_METHOD
from handeye.calibration.session import create_session, write_posture
from handeye.calibration.solve import calibrate, problem_from_session
from handeye.calibration.synthetic import NoiseConfig, sample_session
from handeye.station.cli import main
from handeye.station.config.station import default_config
from handeye.station.report.quality import verdict
from handeye.station.writeback import WritebackError, writeback

from helpers import scene

NOISE = NoiseConfig(sigma_rob_deg=0.001, sigma_cam_mm=0.05, camera_model="gaussian", seed=1)


def _session(postures=16, offset_mm=None):
    """A synthetic session in mm; with ``offset_mm`` its true camera sits that far from the flange."""
    sc = scene(postures)
    if offset_mm is not None:
        x = sc.x_true.copy()
        x[:3, 3] *= offset_mm / np.linalg.norm(x[:3, 3])
        sc = dataclasses.replace(sc, x_true=x)
    return sample_session(sc, NOISE)


def test_a_classic_method_is_told_to_use_the_default_method_not_to_improve_the_session(tmp_path):
    problem = problem_from_session(_session())
    result = calibrate(problem, "tsai")
    judged = verdict(result, problem)
    assert [c.name for c in judged.failed] == ["max_sigma_translation_mm", "max_sigma_rotation_deg"]
    with pytest.raises(WritebackError) as refused:
        writeback(tmp_path, default_config(), result, None, dry_run=True, verdict_passed=False,
                  verdict_reason=judged.line())
    message = str(refused.value)
    assert "improve it" not in message
    assert "method tsai does not give" in message and f"--method {DEFAULT_METHOD}" in message and "--force" in message
    assert "\n" not in message
    assert verdict(calibrate(problem), problem).passed  # the default method's verdict on the same session


def test_the_writeback_command_says_so_too(tmp_path, capsys):
    session = _session()
    create_session(tmp_path / "s", session)
    for posture in session.postures:
        write_posture(tmp_path / "s", posture)
    assert main(["writeback", str(tmp_path / "s"), "--dry-run", "--method", "park"]) != 0
    err = capsys.readouterr().err
    assert "method park does not give" in err and "leave out --method" in err and "improve it" not in err


def test_a_camera_14_mm_from_the_flange_in_a_session_in_mm_is_too_near_not_metres(tmp_path):
    problem = problem_from_session(_session(offset_mm=14.0))  # the plausibility check passes it: lengths are mm
    result = calibrate(problem)
    judged = verdict(result, problem)
    check = next(c for c in judged.checks if c.name == "min_camera_offset_mm")
    assert [c.name for c in judged.failed] == ["min_camera_offset_mm"] and judged.cause == ""
    assert check.advice.startswith("the camera frame is 14.0 mm from the flange, nearer than quality.min_camera_offset_mm")
    assert "look like metres" not in check.advice and "not metres" in check.advice
    assert "set-up" in check.advice and "lower min_camera_offset_mm" in check.advice
    with pytest.raises(WritebackError) as refused:
        writeback(tmp_path, default_config(), result, None, dry_run=True, force=True)
    assert "look like metres" not in str(refused.value) and "14.0 mm from the flange" in str(refused.value)
    assert str(refused.value).endswith("; nothing was written")


def test_a_camera_a_fraction_of_a_mm_from_the_flange_still_says_metres():
    problem = problem_from_session(_session())
    result = calibrate(problem)
    result.x = result.x.copy()
    result.x[:3, 3] *= 0.165 / np.linalg.norm(result.x[:3, 3])  # the 165 mm mount written in metres
    check = next(c for c in verdict(result, problem).checks if c.name == "min_camera_offset_mm")
    assert "look like metres" in check.advice
