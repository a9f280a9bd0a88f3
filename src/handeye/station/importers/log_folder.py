"""A folder given as a log: which of its files hold the poses, and which are beside them.

Capture tools save a run as a folder: one file per side (the robot's poses, the camera's), or one
file per posture (``000.json``, ``pose_003.yaml``, ...), with images, the tool's own result and its
settings beside them. :func:`plan_folder` sorts the files by content, not by name:

- *beside*: hidden files, settings (``.ini``, ``.cfg``, ``.conf``, ``.toml``, ``.properties``), and
  files whose first bytes are not a text log (images, archives, binaries: ``head.check_log_head``);
- *per-posture files*: at least three JSON/YAML files of the same structure (the same pose paths)
  holding a few poses each (one per side, joint values beside them): read as one document, one
  entry per file, numbered by the digits of the file name;
- *side files*: the files holding a list of at least three poses; one or two of them make the log;
- *results*: the files holding fewer than three poses (the tool's answer: one matrix), or a
  structure other than the per-posture files'.

Every file left out is named in the import's notes, with the reason.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ...base import SessionError
from ...base import parse_yaml
from .common import parse_json
from .head import check_log_head, read_head
from .layout_text import tokenise
from .log_tree import find_poses

__all__ = ["FolderPlan", "plan_folder", "parse_document", "TREE_SUFFIXES"]

TREE_SUFFIXES = (".json", ".yaml", ".yml")
SETTINGS_SUFFIXES = (".ini", ".cfg", ".conf", ".toml", ".properties")
#: A file per posture holds a few poses (robot, camera, maybe joints or a second camera); more is a list.
_PER_POSTURE_MAX = 4
_MIN_LIST = 3
_DIGITS = re.compile(r"(\d+)")


@dataclass
class FolderPlan:
    """What a folder's files are: the side files or the per-posture files read, and those left out."""

    folder: Path
    side_files: list = field(default_factory=list)
    posture_files: list = field(default_factory=list)
    skipped: list = field(default_factory=list)  # (file name, why)

    def document(self) -> dict:
        """The per-posture files as one document ``{"posture_<n>": file's document}``."""
        numbers = [_number(p) for p in self.posture_files]
        if None in numbers or len(set(numbers)) != len(numbers):
            numbers = list(range(len(self.posture_files)))
        return {f"posture_{n}": parse_document(p, p.read_text(encoding="utf-8"))
                for n, p in sorted(zip(numbers, self.posture_files))}

    def note(self) -> str | None:
        """One line naming what was read and what was left out (``None`` when nothing was)."""
        if not self.skipped:
            return None
        read = (f"{len(self.posture_files)} per-posture files" if self.posture_files
                else ", ".join(p.name for p in self.side_files))
        groups: dict = {}
        for name, why in self.skipped:
            groups.setdefault(why, []).append(name)
        left = "; ".join(f"{', '.join(names[:4])}{f', ... ({len(names)} files: ' if len(names) > 4 else ' ('}{why})"
                         for why, names in groups.items())
        return f"in {self.folder.name}: read {read}; skipped {left}"


def _number(path: Path) -> int | None:
    digits = _DIGITS.findall(path.stem)
    return int(digits[-1]) if digits else None


def parse_document(path: Path, text: str):
    """A JSON or YAML document (OpenCV's ``%YAML`` directive line dropped), or a one-line SessionError."""
    start = text.lstrip()
    if start[:1] in ("{", "[") and path.suffix.lower() not in (".yaml", ".yml"):
        return parse_json(text, path)
    if text.startswith("%YAML"):  # OpenCV's directive line, which PyYAML refuses
        text = "\n" + text.split("\n", 1)[-1] if "\n" in text else ""
    return parse_yaml(text, path)


def _poses_in(path: Path) -> tuple[int, frozenset | None]:
    """``(poses in the longest list, the pose paths)`` of a file (paths ``None`` for text)."""
    text = path.read_text(encoding="utf-8", errors="replace")
    if path.suffix.lower() in TREE_SUFFIXES or text.lstrip()[:1] in ("{", "["):
        try:
            leaves = find_poses(parse_document(path, text))
        except (SessionError, ValueError):
            return 0, None
        counts: dict = {}
        for leaf in leaves:
            counts[leaf.signature] = counts.get(leaf.signature, 0) + 1
        return max(counts.values(), default=0), frozenset(counts)
    rows = tokenise(text)
    return max(sum(len(r.values) >= 6 for r in rows), sum(len(r.values) == 4 for r in rows) // 4), None


def _beside(path: Path) -> str | None:
    """Why a file is not a log of poses at all (settings, an image, a binary), else ``None``."""
    if path.suffix.lower() in SETTINGS_SUFFIXES:
        return "settings"
    try:
        check_log_head(path, read_head(path))
    except SessionError as exc:
        text = str(exc)
        return "images" if "image" in text else "not a text log"
    return None


def plan_folder(folder) -> FolderPlan | None:
    """The files of ``folder`` that hold the poses (module docstring), or ``None`` when none do."""
    folder = Path(folder)
    plan = FolderPlan(folder)
    data = []
    for path in sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")):
        why = _beside(path)
        if why:
            plan.skipped.append((path.name, why))
            continue
        data.append((path, *_poses_in(path)))
    shapes: dict = {}
    for path, count, paths in data:
        if paths and count == 1 and len(paths) <= _PER_POSTURE_MAX:
            shapes.setdefault(paths, []).append(path)
    postures = max(shapes.values(), key=len, default=[])
    if len(postures) >= _MIN_LIST and len(postures) > len(data) // 2:
        plan.posture_files = postures
        plan.skipped += [(p.name, "another structure: the tool's result or notes") for p, _, _ in data
                         if p not in postures]
        return plan
    plan.side_files = [p for p, count, _ in data if count >= _MIN_LIST]
    plan.skipped += [(p.name, f"{count} pose(s) only: the tool's result, not a list") for p, count, _ in data
                     if count < _MIN_LIST]
    return plan if len(plan.side_files) in (1, 2) else None
