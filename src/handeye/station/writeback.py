"""Write the calibrated camera frame into the robot's ``PERS tooldata`` and read it back.

Order of work, so nothing is lost and nothing wrong is written:

1. refuse a calibration from the mock station or a simulation for a real controller, and one whose
   quality verdict failed (unless forced);
2. build the tool data (frame from X, mass and centre of gravity from the config) and validate it:
   unit quaternion, a frame within 1 m of the flange, mass > 0 (``drivers.controller.check_tooldata``),
   and a camera frame within the config's ``min_camera_offset_mm`` .. ``max_camera_offset_mm`` of the
   flange (a frame inside the flange means lengths in metres), whether forced or not;
3. ``--dry-run`` stops here and prints the RAPID literal;
4. read the controller's current tool data; when an earlier write-back of this session was cut off
   (``writeback_pending.yaml``), say which values that read shows in place; save the current values
   in a new backup file (``tooldata_backup_<time>[_n].yaml``: never overwritten, so the first backup
   of a session, taken before anything was written, is always kept);
5. note the write as pending, write, read back, and compare to the last digit the controller keeps
   (0.001 mm, 1e-6); a link that fails after the save may have been sent is reported as exactly that;
6. record what was done in ``SESSION/writeback.yaml`` and clear the pending note.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..base import HandEyeError, OutputError
from ..base import parse_yaml, read_text_file
from ..calibration import DEFAULT_METHOD
from ..calibration import EYE_IN_HAND
from ..calibration import write_yaml_atomic
from ..calibration import CalibrationResult
from ..drivers import ToolData, check_tooldata
from ..rapid import POSITION_DECIMALS, QUATERNION_DECIMALS, tooldata_literal
from .config.station import StationConfig
from .origin import MOCK, SIMULATED

if TYPE_CHECKING:
    from ..drivers import Controller

__all__ = ["PENDING_FILE", "WritebackError", "check_camera_offset", "check_session_origin", "WritebackOutcome", "side_by_side", "tooldata_from_result", "writeback"]

#: Written before the tool data is sent and removed once the outcome is known: its presence means an
#: earlier write-back was cut off and the controller may hold either value.
PENDING_FILE = "writeback_pending.yaml"
VALUE_NAMES = ["x_mm", "y_mm", "z_mm", "q1", "q2", "q3", "q4", "mass_kg", "cog_x_mm", "cog_y_mm", "cog_z_mm"]


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
    previous : str or None
        What the read before writing showed about an earlier write-back that was cut off.
    mock : bool
        Written to the embedded mock station's controller, not a robot.
    """

    literal: str
    new: ToolData
    old: ToolData | None = None
    readback: ToolData | None = None
    readback_ok: bool = False
    backup: Path | None = None
    dry_run: bool = False
    previous: str | None = None
    mock: bool = False


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
    from ..drivers import ControllerError

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


def check_session_origin(origin: str | None, mock_controller: bool) -> None:
    """Refuse a mock or simulated session's frame for a real controller (``station.origin``)."""
    if mock_controller or origin not in (MOCK, SIMULATED):
        return
    what = ("on a mock station (the embedded one, or a rehearsal against handeye mock controller)" if origin == MOCK
            else "by a simulation")
    raise WritebackError(f"this session was made {what}: its camera frame is not your robot's; capture a session on the "
                         "real station (handeye capture --config STATION.yaml) and calibrate that one")


def check_camera_offset(cam2tool0: np.ndarray, config: StationConfig) -> None:
    """Refuse a camera frame whose distance from the flange is outside the config's quality limits
    (``min_camera_offset_mm``, ``max_camera_offset_mm``): checked before every write, ``--force`` or not."""
    from .report.quality import camera_too_near, config_thresholds

    limits = config_thresholds(config)
    offset = float(np.linalg.norm(np.asarray(cam2tool0, float)[:3, 3]))
    if offset < limits.min_camera_offset_mm:
        raise WritebackError(f"{camera_too_near(offset, limits)}; nothing was written")
    if offset > limits.max_camera_offset_mm:
        raise WritebackError(f"the camera frame is {offset:.0f} mm from the flange, beyond quality.max_camera_offset_mm "
                             f"({limits.max_camera_offset_mm:g}): check the session's units and set-up; nothing was written")


def _verdict_refusal(result: CalibrationResult, verdict_reason: str, session_dir: Path | str = "SESSION") -> str:
    """Why a failed verdict is not written, and what to do: a method without an uncertainty (the classics)
    can never pass the precision checks, so the advice is the default method, not a better session."""
    failed = f"the calibration failed its quality verdict ({verdict_reason})"
    if result.uncertainty is None:
        return (f"{failed}; the verdict needs the camera frame's uncertainty (max_sigma_translation_mm, "
                f"max_sigma_rotation_deg), which method {result.method} does not give: calibrate with the default "
                f"method (handeye calibrate {session_dir}: leave out --method, or --method {DEFAULT_METHOD}) and write "
                "back its result, or pass --force to write it anyway")
    return f"{failed}; improve it (see the report) or pass --force to write it anyway"


def _values(tool: ToolData) -> dict:
    return dict(zip(VALUE_NAMES, tool.values()))


def _new_backup(session_dir: Path, record: dict, stamp: str) -> Path:
    """Write the backup under a name no earlier backup holds (the name is reserved with O_EXCL)."""

    for n in range(1, 10000):
        path = session_dir / (f"tooldata_backup_{stamp}.yaml" if n == 1 else f"tooldata_backup_{stamp}_{n}.yaml")
        try:
            os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        except OSError as exc:
            raise WritebackError(f"cannot save the old tool data in {session_dir} ({exc.strerror or exc}); nothing was "
                                 "written to the controller; make the session folder writable and run again") from None
        try:
            write_yaml_atomic(path, record)
        except BaseException:
            path.unlink(missing_ok=True)  # give the reserved name back: no empty backup is left behind
            raise
        return path
    raise WritebackError(f"{session_dir} holds 9999 backups of {stamp}; nothing was written")


def _read_pending(session_dir: Path) -> dict | None:
    path = session_dir / PENDING_FILE
    if not path.is_file():
        return None
    try:
        data = parse_yaml(read_text_file(path, "write-back note", OutputError), path, OutputError)
    except OutputError:  # a damaged note says only that something was cut off
        return {}
    return data if isinstance(data, dict) else {}


def _previous_outcome(pending: dict, held: ToolData) -> str:
    """What the controller holds after a write-back that was cut off (from its pending note)."""
    held_values = _rounded(held).values()
    when = pending.get("started_at", "an earlier run")
    for key, meaning in (("new", "the write of {when} did reach the controller: it holds the values written then"),
                         ("old", "the write of {when} did not reach the controller: it still holds the values from before")):
        values = pending.get(key)
        if isinstance(values, list) and len(values) == 11 and all(abs(a - b) <= 1.5e-6 * max(1.0, abs(b))
                                                                   for a, b in zip(held_values, values)):
            return meaning.format(when=when)
    return (f"the write of {when} was cut off and the controller now holds neither the values written then nor those "
            "from before (someone changed it since?)")


def writeback(session_dir: str | Path, config: StationConfig, result: CalibrationResult, controller: Controller | None = None, *,
              verdict_passed: bool = True, verdict_reason: str = "", force: bool = False,
              dry_run: bool = False, progress: Callable[[str], None] = lambda message: None, origin: str | None = None,
              mock_controller: bool = False) -> WritebackOutcome:
    """Write the calibrated camera frame to the controller (see the module docstring).

    Parameters
    ----------
    session_dir : path
        The session the result was solved from (backups and the record go there).
    config : StationConfig
        Tool name, mass and centre of gravity.
    result : CalibrationResult
    controller : drivers.controller.Controller or None
        Connected; None only with ``dry_run``.
    origin : str, optional
        ``station.origin.session_origin`` of the session: a mock or simulated session is refused
        unless ``mock_controller``.
    mock_controller : bool
        The controller is the embedded mock station's.

    Raises
    ------
    WritebackError
        A mock or simulated session for a real controller; a failed verdict without ``force``; an
        implausible frame; a write that failed or may not have completed; a read-back that differs.
    """
    session_dir = Path(session_dir)
    check_session_origin(origin, mock_controller)
    if not verdict_passed and not force:
        raise WritebackError(_verdict_refusal(result, verdict_reason, session_dir))
    new = tooldata_from_result(result, config)
    check_camera_offset(result.x, config)
    literal = f"PERS tooldata {config.tool.name} := {tooldata_literal(result.x, new.mass_kg, new.cog_mm)};"
    if dry_run:
        return WritebackOutcome(literal, new, dry_run=True)
    if controller is None:
        raise WritebackError("no controller to write to (give --config or --mock, or use --dry-run)")
    from ..drivers import ControllerConnectionError, ControllerRefused, ControllerTimeout, InvalidRequest
    from ..drivers import ProtocolError

    old = controller.read_tool()
    previous = None
    pending = _read_pending(session_dir)
    if pending is not None:
        previous = _previous_outcome(pending, old)
        progress(f"an earlier write-back of this session was cut off: {previous}")
    stamp = time.strftime("%Y%m%d-%H%M%S")
    backup = _new_backup(session_dir, {"tool": config.tool.name, "controller": getattr(controller, "address", "?"),
                                       "saved_at": stamp, "values": _values(old)}, stamp)
    progress(f"old tool data saved to {backup}")
    write_yaml_atomic(session_dir / PENDING_FILE, {"started_at": stamp, "tool": config.tool.name, "backup": backup.name,
                                                   "new": new.values(), "old": old.values()})
    try:
        back = controller.set_tool(new)
    except (ControllerRefused, InvalidRequest) as exc:
        (session_dir / PENDING_FILE).unlink(missing_ok=True)  # refused: nothing was saved
        raise WritebackError(f"the controller refused the tool data ({exc}); nothing was written; the values in place "
                             f"are those in {backup}") from None
    except (ControllerTimeout, ControllerConnectionError, ProtocolError) as exc:
        raise WritebackError(f"the link failed while writing ({exc}): the controller may hold the new or the old tool "
                             f"data; run the same writeback again: it reads back and says which (old values: {backup})") from None
    except HandEyeError as exc:
        raise WritebackError(f"{exc}; run the same writeback again: it reads back and says what is in place "
                             f"(old values: {backup})") from None
    ok = _same_to_last_digit(back, new)
    write_yaml_atomic(session_dir / "writeback.yaml", {
        "written_at": stamp, "tool": config.tool.name, "literal": literal, "method": result.method,
        "controller": "mock" if mock_controller else getattr(controller, "address", "?"),
        "new": new.values(), "old": old.values(), "read_back": back.values(), "read_back_ok": ok,
        "backup": backup.name, "forced": bool(force and not verdict_passed)})
    (session_dir / PENDING_FILE).unlink(missing_ok=True)
    if not ok:
        raise WritebackError(f"the controller holds {back.values()} after writing {new.values()}; "
                             f"the old values are in {backup}")
    return WritebackOutcome(literal, new, old, back, ok, backup, previous=previous, mock=mock_controller)
