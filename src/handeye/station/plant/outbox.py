"""The cell's outbox: events not yet acknowledged by the broker, one file each, numbered in order.

A folder (``plant.outbox``) holding one ``<seq:012d>.json`` per event waiting and ``last-sent.json``,
the last event the broker acknowledged. :meth:`Outbox.add` gives the next number (one more than the
largest of those) and writes the event under the folder's lock (``station.verify.file_lock``: two commands at
one cell never share a number), atomically (temporary file, flushed to disk, renamed: a killed command
leaves the whole event or none). :meth:`Outbox.pending` lists them in order; :meth:`Outbox.done` renames
an acknowledged one (QoS 1) over ``last-sent.json``, so the numbers never go back, with one write to
disk per event. A crash that loses the rename sends that event again: the fleet keeps it once, by its
number (``station.plant.store``).
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path

from ...base import write_text_atomic
from ..verify.file_lock import exclusive_lock

__all__ = ["Outbox"]


class Outbox:
    """The outbox folder ``folder`` (created when missing)."""

    def __init__(self, folder):
        self.folder = Path(folder)

    def _counter(self) -> Path:
        return self.folder / "seq"  # its lock file only

    def _last_sent(self) -> Path:
        return self.folder / "last-sent.json"

    def last_seq(self) -> int:
        """The number of the last event the broker acknowledged (0: none yet)."""
        try:
            return int(json.loads(self._last_sent().read_text()).get("seq") or 0)
        except FileNotFoundError:
            return 0

    def add(self, event: dict) -> dict:
        """Give ``event`` the cell's next sequence number and keep it until delivered; returns it numbered."""
        self.folder.mkdir(parents=True, exist_ok=True)
        with exclusive_lock(self._counter()):
            seq = max([self.last_seq()] + [n for n, _ in self.pending()]) + 1
            event = dict(event, seq=seq)
            write_text_atomic(self.folder / f"{seq:012d}.json", json.dumps(event, sort_keys=True) + "\n")
        return event

    def pending(self) -> list[tuple[int, Path]]:
        """``(seq, file)`` of every event waiting, oldest first."""
        if not self.folder.is_dir():
            return []
        out = []
        for path in self.folder.glob("*.json"):
            if path.stem.isdigit():
                out.append((int(path.stem), path))
        return sorted(out)

    @staticmethod
    def read(path: Path) -> bytes:
        return path.read_bytes()

    def done(self, path: Path) -> None:
        """``path`` was acknowledged: it becomes ``last-sent.json`` (in order: the numbers only grow)."""
        with contextlib.suppress(FileNotFoundError):
            os.replace(path, self._last_sent())

    @contextlib.contextmanager
    def draining(self, wait_s: float):
        """Hold the right to send, one process of the cell at a time (so the events leave in order); yields
        False when another process still held it after ``wait_s`` (its events and ours wait for the next send)."""
        import time

        self.folder.mkdir(parents=True, exist_ok=True)
        deadline = time.monotonic() + wait_s
        with open(self.folder / "drain.lock", "a+b") as handle:
            try:
                import fcntl
            except ImportError:  # pragma: no cover - not POSIX: one sender at a time is the user's to keep
                yield True
                return
            while True:
                try:
                    fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
                    break
                except OSError:
                    if time.monotonic() >= deadline:
                        yield False
                        return
                    time.sleep(0.01)
            try:
                yield True
            finally:
                fcntl.flock(handle.fileno(), fcntl.LOCK_UN)
