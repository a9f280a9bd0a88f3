"""Writing results: JSON to a file (atomically) or to standard output."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from ..base import OutputError
from ..base import write_text_atomic


def check_output_file(target: str) -> None:
    """Refuse an output file that cannot be written, before the work that produces it ('-' = stdout).

    Raises
    ------
    OutputError
        ``target`` is a folder, its folder does not exist or is a file, or is not writable.
    """
    if target == "-":
        return
    path = Path(target)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder; give a file name")
    if not path.parent.exists():
        raise OutputError(f"cannot write {path}: folder {path.parent} does not exist")
    if not path.parent.is_dir():
        raise OutputError(f"cannot write {path}: {path.parent} is a file, not a folder; choose a writable folder")
    if not os.access(path.parent, os.W_OK):
        raise OutputError(f"cannot write {path}: permission denied; choose a writable folder")


def write_json(target: str, data: dict) -> None:
    """Write ``data`` as indented JSON to ``target`` ('-' = stdout), atomically for files."""
    text = json.dumps(data, indent=2, allow_nan=False) + "\n"
    if target == "-":
        sys.stdout.write(text)
        return
    check_output_file(target)
    write_text_atomic(Path(target), text)
