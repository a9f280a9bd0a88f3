"""Writing results: JSON to a file (atomically) or to standard output."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..calibration.errors import HandEyeError
from ..calibration.session import write_text_atomic


def write_json(target: str, data: dict) -> None:
    """Write ``data`` as indented JSON to ``target`` ('-' = stdout), atomically for files."""
    text = json.dumps(data, indent=2, allow_nan=False) + "\n"
    if target == "-":
        sys.stdout.write(text)
        return
    path = Path(target)
    if path.parent and not path.parent.exists():
        raise HandEyeError(f"cannot write {path}: folder {path.parent} does not exist")
    write_text_atomic(path, text)
