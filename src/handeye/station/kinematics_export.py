"""``handeye kinematics export``: what the station does with the identified arm (never written silently).

(a) ``joint_offsets.txt`` / ``kinematics.json``: the identified zero offsets of the controller axes
(arm side, degrees and radians) for an engineer to enter in the controller's calibration. What we can
cite of where: an IRC5 keeps calibration data per mechanical unit, which can be fine calibrated,
offset by hand and loaded from a file (ABB PC SDK, ``Grant.CalibrateRobot``: "Fine calibrate
mechanical unit", "Manual offset of mechanical unit calibration data and loading new calibration data
from file require grant Modify configuration"); the motion configuration file ``MOC.cfg`` holds the
motor calibration data, and the revolution counters are updated on the FlexPendant under Calibration
(third-party service notes, industrialmonitordirect.com). The parameter's exact name in the Motion
topic, its unit (motor or arm side) and its sign: check in the controller's manual (Technical
reference manual, System parameters; the robot's Operating manual, Calibration). A calibrated arm
model from the maker (for ABB the Absolute Accuracy option the issue names; check with ABB) is the
supported route: this export is for stations without it, and it says so in the file.

(b) ``--program DIR``: a corrected copy of a RAPID program's targets, computed with the identified arm:
every ``jointtarget`` ``q`` becomes the angles at which the REAL arm puts the camera where the station's
camera-only calibration with the nominal model puts it at ``q``, relative to the board
(``q' = IK_identified(T_k T_0^-1 FK_nominal(q) X_0 X_k^-1)``), every ``robtarget`` ``P`` (taken in
wobj0, corrected as a pose of the flange) becomes ``FK_nominal`` of the angles so found: what the
controller, which computes with its nominal model, must be told so the real arm reaches ``P``. The corrected
joint targets go through the cell checks (``handeye cell check``: the station's keep-out volumes and the
arm's own links); nothing is written when one is not clear.

Both are refused when the identification is weak: one of the zeros of axes 2-5 not identified.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..base import HandEyeError
from ..base import write_text_atomic

__all__ = ["export_kinematics", "correct_program_text"]

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
JOINTTARGET = re.compile(r"(jointtarget\s+\w+\s*:=\s*\[\s*\[)([^\]]*)(\])", re.IGNORECASE)
ROBTARGET = re.compile(r"(robtarget\s+\w+\s*:=\s*\[\s*\[)([^\]]*)(\]\s*,\s*\[)([^\]]*)(\])", re.IGNORECASE)

SUPPORTED_ROUTE = ("the supported route to a corrected arm model is a calibrated model from the maker (for ABB the "
                   "Absolute Accuracy option; check with ABB); these values are for a station without it, entered "
                   "by an engineer, never written by handeye")


def _refusal(ident) -> str | None:
    weak = [f"J{axis}" for axis in (2, 3, 4, 5) if not ident.identified(f"zero{axis}")]
    if weak:
        return (f"the identification is weak: the zero of {', '.join(weak)} is not identified at these postures; "
                "capture more varied postures (handeye capture) and calibrate again")
    return None


def offsets_text(ident, session) -> str:
    """``joint_offsets.txt``: the offsets, their sigmas and where they go."""
    lines = [f"# Arm joint zero offsets identified with the camera from {session}",
             "# offset = how much further the axis stands than its controller angle (arm side).",
             "# Where: the controller's calibration data of the robot's mechanical unit (IRC5: fine calibration,",
             "# manual offset of the calibration data, per ABB's PC SDK; the motor calibration data are in MOC.cfg).",
             "# The parameter's exact name, its unit (arm or motor side: arm side x transmission ratio) and sign:",
             "# check in the controller's manual (System parameters, Motion topic; Operating manual, Calibration).",
             "# Afterwards update the revolution counters and check the calibration position (FlexPendant, Calibration).",
             "# " + SUPPORTED_ROUTE + ".",
             "axis, offset_deg, offset_rad, sigma_deg, status"]
    for axis in range(1, 7):
        j = ident.names.index(f"zero{axis}")
        if ident.status[j] == "identified":
            v, s = ident.values[j], ident.sigma[j]
            lines.append(f"{axis}, {v:+.5f}, {np.radians(v):+.7f}, {s:.5f}, identified")
        else:
            lines.append(f"{axis}, , , , not identifiable: {ident.reasons[ident.names[j]]}")
    return "\n".join(lines) + "\n"


def _numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(NUMBER, text)]


def _fmt(values, decimals: int) -> str:
    return ",".join(f"{v:.{decimals}f}" for v in values)


def correct_program_text(text: str, nominal, identified, base_fix=None, flange_fix=None) -> tuple[str, list]:
    """A RAPID module's text with its jointtargets and robtargets corrected; and the corrected joints
    ``(k,)`` of every target, for the cell checks.

    ``base_fix``, ``flange_fix`` (4x4): the flange pose the identified arm must reach is
    ``base_fix @ FK_nominal(q) @ flange_fix``: the same place relative to the board and the camera as the
    station's camera-only calibration puts it (``T_k T_0^-1`` and ``X_0 X_k^-1``): the base's own gauge
    (J1's zero, d1) is not seen by hand-eye data, the board is.

    Raises
    ------
    HandEyeError
        A target the identified arm cannot reach (inverse kinematics fails).
    """
    from ..robot import inverse_kinematics
    from ..geometry import transform_from_rotation_translation
    from scipy.spatial.transform import Rotation

    corrected_joints = []
    base_fix = np.eye(4) if base_fix is None else base_fix
    flange_fix = np.eye(4) if flange_fix is None else flange_fix

    def joint(match):
        q = np.array(_numbers(match.group(2))[:6])
        ik = inverse_kinematics(identified, base_fix @ nominal.forward_transform(q) @ flange_fix, q)
        if not ik.success:
            raise HandEyeError(f"jointtarget [{match.group(2)}]: the identified arm cannot reach its pose")
        corrected_joints.append(ik.joints_deg)
        return match.group(1) + _fmt(ik.joints_deg, 4) + match.group(3)

    def rob(match):
        p, q = _numbers(match.group(2))[:3], _numbers(match.group(4))[:4]
        pose = transform_from_rotation_translation(Rotation.from_quat(q, scalar_first=True).as_matrix(), p)
        seed = _seed(nominal, pose)
        ik = inverse_kinematics(identified, base_fix @ pose @ flange_fix, seed)
        if not ik.success:
            raise HandEyeError(f"robtarget [{match.group(2)}]: the identified arm cannot reach it")
        corrected_joints.append(ik.joints_deg)
        pos, quat = nominal.forward(ik.joints_deg)
        if np.dot(quat, q) < 0:  # the same rotation, with the program's sign
            quat = -quat
        return match.group(1) + _fmt(pos, 3) + match.group(3) + _fmt(quat, 7) + match.group(5)

    out = JOINTTARGET.sub(joint, text)
    out = ROBTARGET.sub(rob, out)
    return out, corrected_joints


def _fixes(ident) -> tuple[np.ndarray, np.ndarray]:
    """``T_k T_0^-1`` and ``X_0 X_k^-1`` of an identification (see :func:`correct_program_text`)."""
    fit = ident.camera_only.fit
    return ident.target @ np.linalg.inv(fit.target), fit.x @ np.linalg.inv(ident.x)


def _seed(nominal, pose) -> np.ndarray:
    from ..robot import ik_from_standard_seeds

    found = ik_from_standard_seeds(nominal, pose, 0.0)
    if found is None:
        raise HandEyeError("a robtarget the nominal arm cannot reach: check the program's targets")
    return found


def export_kinematics(session, out_dir, program=None, config=None) -> dict:
    """Identify and write the export; returns what was written (``files``, ``cell``)."""
    from ..calibration import corrected_robot
    from ..robot import load_robot
    from .calibrate import calibrate_session_folder
    from .kinematics_step import identify_outcome, kinematics_json

    outcome = calibrate_session_folder(session)
    ident, standoff = identify_outcome(outcome)
    refusal = _refusal(ident)
    if refusal:
        raise HandEyeError(f"kinematics export refused: {refusal}")
    nominal = load_robot(ident.robot)
    identified = corrected_robot(nominal, ident.values)
    corrected = {}
    joints = []
    if program is not None:
        files = sorted(p for p in Path(program).iterdir() if p.suffix.lower() in (".mod", ".sys", ".modx"))
        if not files:
            raise HandEyeError(f"{program} holds no RAPID module (.mod, .sys): give the program's folder")
        for path in files:
            text, rows = correct_program_text(path.read_text(encoding="utf-8"), nominal, identified, *_fixes(ident))
            corrected[path.name] = text
            joints += rows
    cell = _cell_checked(joints, nominal, config)
    if cell is not None and not cell.clear:
        raise HandEyeError("kinematics export refused: a corrected target is not clear of the cell: "
                           + "; ".join(line for line in cell.lines() if "NOT CLEAR" in line)[:300])
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "joint_offsets.txt", out / "kinematics.json"]
    write_text_atomic(written[0], offsets_text(ident, session))
    entry = {"kinematics": kinematics_json(ident, standoff), "supported_route": SUPPORTED_ROUTE}
    write_text_atomic(written[1], json.dumps(entry, indent=1) + "\n")
    if corrected:
        (out / "program").mkdir(exist_ok=True)
        for name, text in corrected.items():
            note = "\n  ! targets corrected by handeye kinematics export with the identified arm (not the nominal)"
            text = re.sub(r"^(\s*MODULE\b[^\n]*)", lambda m: m.group(1) + note, text, count=1, flags=re.MULTILINE)
            write_text_atomic(out / "program" / name, text)
            written.append(out / "program" / name)
    return {"files": [str(p) for p in written], "targets_corrected": len(joints),
            "cell": None if cell is None else cell.to_dict()}


def _cell_checked(joints, robot, config):
    if not joints:
        return None
    from .cell.plan import cell_check
    from .cell.check import check_joints
    from .config.station import default_config

    config = config or default_config()
    return check_joints(robot, cell_check(config).guard(robot), np.array(joints))
