"""What the workers of one test run share: deterministic builds, kept once for the run.

``tests/conftest.py`` makes the run's folder before the xdist workers start (they inherit its name in
``RUN_CACHE``) and removes it when the run ends.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path

from handeye.base.files import write_bytes_atomic

#: Environment variable naming the folder the workers of one test run share.
RUN_CACHE = "HANDEYE_TEST_RUN_CACHE"


def shared_by_workers(key: str, build):
    """``build()``, or the value another worker of this run already built under ``key``.

    For deterministic builders only (the same value in every process): the first worker to finish writes
    it to the run's folder (a pickle, written atomically, so a reader never sees half of one); workers that
    come later read it. Without the folder (a test file imported outside pytest) it builds.
    """
    folder = os.environ.get(RUN_CACHE)
    if not folder or not os.path.isdir(folder):
        return build()
    path = Path(folder) / f"{key}.pickle"
    try:
        return pickle.loads(path.read_bytes())
    except FileNotFoundError:
        pass
    value = build()
    write_bytes_atomic(path, pickle.dumps(value))
    return value
