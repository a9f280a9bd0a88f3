"""Import other tools' samples into a session folder (the library side of ``handeye import``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..geometry import BoardGeometry
from ..calibration import diagnose
from ..base import CalibrationError, SessionError, SessionUsageError, brief
from ..calibration import bounded_pairs, pairs_used
from ..calibration import Session, create_session, write_postures
from .importers import read_any
from .importers.inference import format_table

__all__ = ["ImportOptions", "ImportOutcome", "import_to_session", "import_summary"]


@dataclass(frozen=True)
class ImportOptions:
    """What ``handeye import`` was asked to do (``None`` = not given: detect or use the default)."""

    sources: tuple
    output: str
    format: str | None = None
    setup: str | None = None
    units: str | None = None
    quaternion_order: str | None = None
    robot_pose: str | None = None
    camera_pose: str | None = None
    board: tuple | None = None
    square_mm: float | None = None
    skip_invalid: bool = False
    overwrite: bool = False
    format_options: dict = field(default_factory=dict)


@dataclass
class ImportOutcome:
    """The written session, how it was read, and what the checks found."""

    path: Path
    session: Session
    findings: list
    removed: list = field(default_factory=list)

    @property
    def record(self) -> dict:
        return self.session.extra.get("import", {})

    @property
    def warnings(self) -> list:
        """Every warning line: the flags the data contradict, then the checks' findings."""
        return list(self.record.get("warnings") or []) + [f.message for f in self.findings]


#: Findings that restate what the import's reading already warns about (a flag the data contradict).
_RESTATED = ("setup", "rotation_convention", "model_mismatch")


def _board(options: ImportOptions) -> BoardGeometry | None:
    if options.board is None:
        if options.square_mm is not None:
            raise SessionUsageError("--square-mm needs --board (the inner-corner counts, e.g. --board 9x6)")
        return None
    if options.square_mm is not None and not options.square_mm > 0:
        raise SessionUsageError(f"--square-mm must be positive; got {options.square_mm}")
    nx, ny = (int(c) for c in options.board)
    return BoardGeometry((nx, ny), options.square_mm)


def _compare_with_log_result(session) -> None:
    """When the log holds the tool's own result, solve the session and note how far that result is from
    ours (``importers.log_result``); the result is a comparison, never an input."""
    record = session.extra["import"]
    result = record.get("log_result")
    if not result:
        return
    from ..calibration import calibrate_session
    from .importers.log_result import compare_result

    factor = 1000.0 if (record.get("units") or {}).get("robot") == "m" else 1.0
    try:
        ours = calibrate_session(session)
    except (CalibrationError, ValueError, np.linalg.LinAlgError) as exc:
        record.setdefault("notes", []).append(f"the log holds its own answer ({result['path']}); ours could not be "
                                              f"computed to compare ({brief(str(exc))})")
        return
    line = compare_result(result, ours.x, factor)
    record.setdefault("notes", []).append(line)
    result["comparison"] = line


def import_to_session(options: ImportOptions, progress=lambda message: None) -> ImportOutcome:
    """Read, check and write: nothing is created until the whole input has been read and validated.

    Raises
    ------
    SessionError
        Unreadable or malformed input (one line naming the file and entry), an existing session
        without ``overwrite``, an output path that is a file.
    """
    out = Path(options.output)
    if out.exists() and not out.is_dir():
        raise SessionError(f"{out} is a file; give a folder for the session")
    if (out / "session.yaml").exists() and not options.overwrite:
        raise SessionError(f"{out} already holds a session; choose another folder or pass --overwrite")
    sources = [str(s) for s in options.sources]
    extra = {k: v for k, v in options.format_options.items() if v is not None}
    session = read_any(sources if len(sources) > 1 else sources[0], options.format, setup=options.setup,
                       units=options.units, quaternion_order=options.quaternion_order, board=_board(options),
                       skip_invalid=options.skip_invalid or None, robot_pose=options.robot_pose,
                       camera_pose=options.camera_pose, **extra)
    _compare_with_log_result(session)
    tool0 = [p.tool0_in_base for p in session.postures]
    target = [p.target_in_camera for p in session.postures]
    findings = diagnose(np.array(tool0), np.array(target), session.setup, [p.index for p in session.postures])
    if session.extra["import"].get("warnings"):  # the import already said what the data say about the flags
        findings = [f for f in findings if f.kind not in _RESTATED]
    removed = []
    if options.overwrite and (out / "truth.yaml").exists():
        (out / "truth.yaml").unlink()  # belonged to the replaced (synthetic) session
        removed.append("truth.yaml")
    create_session(out, session, overwrite=options.overwrite)
    write_postures(out, session.postures)
    progress(f"wrote {len(session.postures)} postures")
    return ImportOutcome(out, session, findings, removed)


def import_summary(outcome: ImportOutcome) -> list:
    """The lines ``handeye import`` prints (findings excluded: they go to stderr as warnings)."""
    r = outcome.record
    session = outcome.session
    source = r.get("source")
    source_text = ", ".join(source) if isinstance(source, list) else str(source)
    units = r.get("units", {})
    unit_text = (f"{units.get('robot')} for robot and camera" if units.get("robot") == units.get("camera")
                 else f"robot {units.get('robot')}, camera {units.get('camera')}")
    conventions = r.get("conventions") or {}
    lines = [
        f"read {source_text}",
        f"  format:   {r.get('format')}, {r.get('format_how', 'given')}",
        f"  setup:    {session.setup}, {r.get('setup_how')}",
        f"  units:    {unit_text}, {units.get('how')}; written in mm",
    ]
    for part in ("robot", "camera"):
        if conventions.get(part):
            lines.append(f"  {part + ':':9s} {conventions[part]}")
    if conventions.get("decided_by"):
        lines.append(f"  decided:  by {', then '.join(conventions['decided_by'])}")
    lines.append(f"  postures: {len(session.postures)} from {r.get('entries_read')} entries")
    decimated = r.get("decimated")
    if decimated:
        lines.append(f"  decimated: stream of {decimated['rows']} rows ({decimated['pairs']} pairs within the stamp "
                     f"tolerance) decimated to {decimated['postures']} postures by {decimated['how']}")
    if session.target is not None:
        square = f", {session.target.square_mm:g} mm squares" if session.target.square_mm else ""
        lines.append(f"  target:   {session.target.corners[0]}x{session.target.corners[1]} inner corners{square}")
    dropped = r.get("dropped") or []
    if not dropped:
        lines.append("  dropped:  none")
    for d in dropped:
        examples = ", ".join(d["examples"][:3]) + (", ..." if d["count"] > 3 else "")
        lines.append(f"  dropped:  {d['count']}: {d['reason']} ({examples})")
    for note in r.get("notes") or []:
        lines.append(f"  note:     {note}")
    for name in outcome.removed:
        lines.append(f"  removed:  {name} of the replaced session")
    table = format_table(r.get("inference") or {})
    if table:
        lines.append("  readings of the poses (X-free invariants of AX = XB; misfits near 0 fit):")
        lines += [f"    {line}" for line in table]
    lines.append(f"  checks:   {len(outcome.findings)} finding(s)" + (" (see warnings)" if outcome.findings else ": nothing odd")
                 + f", pairwise on {pairs_used(len(bounded_pairs(len(session.postures))), len(session.postures))}")
    lines.append(f"session written to {outcome.path}; next: handeye calibrate {outcome.path}")
    return lines
