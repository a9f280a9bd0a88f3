"""The cell's outbox: events not yet acknowledged by the broker, one file each, numbered in order.

A folder (``plant.outbox``) holding ``seq`` (the last sequence number given) and one
``<seq:012d>.json`` per event waiting. :meth:`Outbox.add` gives the next number and writes the event
under the folder's lock (``station.file_lock``: two commands at one cell never share a number), each
file atomically (temporary file, flushed, renamed: a killed command leaves the whole event or none).
:meth:`Outbox.pending` lists them in order; :meth:`Outbox.done` removes one once the broker has
acknowledged it (QoS 1). A crash between the acknowledgement and the removal sends that event again:
the fleet keeps it once, by its number (``station.plant.store``).
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path

from ...calibration.files import write_text_atomic
from ..file_lock import exclusive_lock

__all__ = ["Outbox"]


class Outbox:
    """The outbox folder ``folder`` (created when missing)."""

    def __init__(self, folder):
        self.folder = Path(folder)

    def _counter(self) -> Path:
        return self.folder / "seq"

    def last_seq(self) -> int:
        try:
            return int(self._counter().read_text().strip() or 0)
        except FileNotFoundError:
            return 0

    def add(self, event: dict) -> dict:
        """Give ``event`` the cell's next sequence number and keep it until delivered; returns it numbered."""
        self.folder.mkdir(parents=True, exist_ok=True)
        with exclusive_lock(self._counter()):
            seq = max([self.last_seq()] + [n for n, _ in self.pending()]) + 1  # a file a crash left counts
            event = dict(event, seq=seq)
            write_text_atomic(self.folder / f"{seq:012d}.json", json.dumps(event, sort_keys=True) + "\n")
            write_text_atomic(self._counter(), f"{seq}\n")  # after the event: a crash between reuses no number
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

    @staticmethod
    def done(path: Path) -> None:
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)

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
