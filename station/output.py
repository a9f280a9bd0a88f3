"""Writing results: JSON to a file (atomically) or to standard output."""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

from ..calibration.errors import HandEyeError


def write_json(target: str, data: dict) -> None:
    """Write ``data`` as indented JSON to ``target`` ('-' = stdout), atomically for files."""
    text = json.dumps(data, indent=2, allow_nan=False) + "\n"
    if target == "-":
        sys.stdout.write(text)
        return
    path = Path(target)
    if path.parent and not path.parent.exists():
        raise HandEyeError(f"cannot write {path}: folder {path.parent} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent if str(path.parent) else ".")
    try:
        with os.fdopen(fd, "w") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
