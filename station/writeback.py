"""Write the calibrated camera frame into the robot's ``PERS tooldata`` and read it back.

Order of work, so nothing is lost and nothing wrong is written:

1. refuse a calibration whose quality verdict failed (unless forced);
2. build the tool data (frame from X, mass and centre of gravity from the config) and validate it:
   unit quaternion, a frame within 1 m of the flange, mass > 0 (``drivers.controller.check_tooldata``);
3. ``--dry-run`` stops here and prints the RAPID literal;
4. read the controller's current tool data and save it in the session (``tooldata_backup_*.yaml``);
5. write, read back, and compare to the last digit the controller keeps (0.001 mm, 1e-6);
6. record what was done in ``SESSION/writeback.yaml``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from ..calibration.errors import HandEyeError
from ..calibration.problem import EYE_IN_HAND
from ..calibration.session import write_yaml_atomic
from ..calibration.solve import CalibrationResult
from ..drivers.controller.types import ToolData, check_tooldata
from ..rapid.literals import POSITION_DECIMALS, QUATERNION_DECIMALS, tooldata_literal
from .config import StationConfig

__all__ = ["WritebackError", "WritebackOutcome", "side_by_side", "tooldata_from_result", "writeback"]


class WritebackError(HandEyeError):
    """The tool data must not be written (failed verdict, implausible frame, read-back mismatch)."""


@dataclass
class WritebackOutcome:
    """What :func:`writeback` did.

    Attributes
    ----------
    literal : str
        ``PERS tooldata <name> := [...];``
    new : ToolData
        As rounded to what RAPID keeps.
    old, readback : ToolData or None
        Before writing, and read back after (None on a dry run).
    readback_ok : bool
        The read-back equals the written values to the controller's last digit.
    backup : Path or None
    """

    literal: str
    new: ToolData
    old: ToolData | None = None
    readback: ToolData | None = None
    readback_ok: bool = False
    backup: Path | None = None
    dry_run: bool = False


def _rounded(tool: ToolData) -> ToolData:
    p, q, m, c = tool.as_arrays()
    return ToolData(tuple(round(float(v), POSITION_DECIMALS) for v in p), tuple(round(float(v), QUATERNION_DECIMALS) for v in q),
                    round(float(m), 3), tuple(round(float(v), POSITION_DECIMALS) for v in c))


def tooldata_from_result(result: CalibrationResult, config: StationConfig) -> ToolData:
    """Validated, rounded tool data for the camera frame of an eye-in-hand result.

    Raises
    ------
    WritebackError
        Eye-to-hand results (the camera is not a tool), or values the controller must not get.
    """
    if result.setup != EYE_IN_HAND:
        raise WritebackError("only an eye-in-hand calibration (camera on the flange) becomes tooldata")
    from ..drivers.errors import ControllerError

    try:
        tool = check_tooldata(ToolData.from_transform(result.x, config.tool.mass_kg, config.tool.cog_mm))
    except ControllerError as exc:
        raise WritebackError(str(exc)) from None
    return _rounded(tool)


def _same_to_last_digit(a: ToolData, b: ToolData) -> bool:
    return _rounded(a).values() == _rounded(b).values()


def side_by_side(old: ToolData | None, new: ToolData) -> str:
    """A table of the old and new tool frames and the change."""
    names = ["x mm", "y mm", "z mm", "q1", "q2", "q3", "q4", "mass kg", "cog x", "cog y", "cog z"]
    rows = [f"  {'':8s} {'old':>12s} {'new':>12s} {'change':>12s}"]
    old_values = old.values() if old is not None else [float("nan")] * 11
    for name, a, b in zip(names, old_values, new.values()):
        digits = 6 if name.startswith("q") else 3
        rows.append(f"  {name:8s} {a:12.{digits}f} {b:12.{digits}f} {b - a:+12.{digits}f}")
    return "\n".join(rows)


def writeback(session_dir, config: StationConfig, result: CalibrationResult, controller=None, *,
              verdict_passed: bool = True, verdict_reason: str = "", force: bool = False,
              dry_run: bool = False, progress=lambda message: None) -> WritebackOutcome:
    """Write the calibrated camera frame to the controller (see the module docstring).

    Raises
    ------
    WritebackError
        Failed verdict without ``force``; an implausible frame; a read-back that differs.
    """
    session_dir = Path(session_dir)
    if not verdict_passed and not force:
        raise WritebackError(f"the calibration failed its quality verdict ({verdict_reason}); improve it (see the report) "
                             "or pass --force to write it anyway")
    new = tooldata_from_result(result, config)
    literal = f"PERS tooldata {config.tool.name} := {tooldata_literal(result.x, new.mass_kg, new.cog_mm)};"
    if dry_run:
        return WritebackOutcome(literal, new, dry_run=True)
    if controller is None:
        raise WritebackError("no controller to write to (give --config or --mock, or use --dry-run)")
    old = controller.read_tool()
    stamp = time.strftime("%Y%m%d-%H%M%S")
    backup = session_dir / f"tooldata_backup_{stamp}.yaml"
    write_yaml_atomic(backup, {"tool": config.tool.name, "controller": getattr(controller, "address", "?"),
                               "saved_at": stamp, "values": dict(zip(
                                   ["x_mm", "y_mm", "z_mm", "q1", "q2", "q3", "q4", "mass_kg", "cog_x_mm", "cog_y_mm",
                                    "cog_z_mm"], old.values()))})
    progress(f"old tool data saved to {backup}")
    try:
        back = controller.set_tool(new)
    except HandEyeError as exc:
        raise WritebackError(f"writing the tool data failed: {exc}; the old values are in {backup}") from None
    ok = _same_to_last_digit(back, new)
    write_yaml_atomic(session_dir / "writeback.yaml", {
        "written_at": stamp, "tool": config.tool.name, "literal": literal, "method": result.method,
        "new": new.values(), "old": old.values(), "read_back": back.values(), "read_back_ok": ok,
        "backup": backup.name, "forced": bool(force and not verdict_passed)})
    if not ok:
        raise WritebackError(f"the controller holds {back.values()} after writing {new.values()}; "
                             f"the old values are in {backup}")
    return WritebackOutcome(literal, new, old, back, ok, backup)
