"""An exclusive lock between processes around a read-modify-write of one file (the verify history).

``with exclusive_lock(path): ...`` holds a lock on ``path + ".lock"`` (created when missing, never
removed: removing it would let a waiting process lock a file another one has just created). POSIX
systems use ``fcntl.flock`` (released by the kernel when the process dies, so a killed check never
leaves the history locked); Windows ``msvcrt.locking`` on the lock file's first byte, retried while
another process holds it. Where neither exists the block runs unlocked.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

__all__ = ["exclusive_lock", "lock_path"]


def lock_path(path) -> Path:
    """The lock file of ``path``: ``history.jsonl`` -> ``history.jsonl.lock``."""
    path = Path(path)
    return path.with_name(path.name + ".lock")


@contextlib.contextmanager
def exclusive_lock(path):
    """Hold the exclusive lock of ``path`` (see the module docstring) for the ``with`` block.

    Raises
    ------
    OSError
        The lock file cannot be created (the folder is not writable).
    """
    with open(lock_path(path), "a+b") as handle:
        release = _acquire(handle)
        try:
            yield
        finally:
            release()


def _acquire(handle):
    """Lock ``handle``'s file, waiting for other holders; returns the function that releases it."""
    try:
        import fcntl
    except ImportError:
        fcntl = None
    if fcntl is not None:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        return lambda: fcntl.flock(handle.fileno(), fcntl.LOCK_UN)
    try:
        import msvcrt
    except ImportError:
        return lambda: None
    handle.seek(0)
    while True:
        try:
            msvcrt.locking(handle.fileno(), msvcrt.LK_NBLCK, 1)
            break
        except OSError:
            time.sleep(0.01)

    def release():
        handle.seek(0)
        msvcrt.locking(handle.fileno(), msvcrt.LK_UNLCK, 1)

    return release
