"""The fleet's history in SQLite: every event of every cell once, in its cell's order.

Table ``events``: one row per ``(cell, seq)`` (the primary key: an event the broker delivers again, or
a cell sends again after a crash, is kept once), with the arrival order (``rowid``), the time it
arrived and the event's JSON as published. A cell is its topic prefix (enterprise/site/area/line/cell),
taken from the topic it published on (which the broker's ACL ties to its credentials), never from the
payload. Table ``states``: the retained last state of each cell. One connection, shared by the
subscriber's thread and the page's, behind a lock.
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from pathlib import Path

__all__ = ["History"]

_SCHEMA = """
CREATE TABLE IF NOT EXISTS events (
    cell TEXT NOT NULL, seq INTEGER NOT NULL, kind TEXT, time TEXT, received REAL NOT NULL, payload TEXT NOT NULL,
    PRIMARY KEY (cell, seq));
CREATE TABLE IF NOT EXISTS states (cell TEXT PRIMARY KEY, seq INTEGER, received REAL NOT NULL, payload TEXT NOT NULL);
"""


class History:
    """The history database at ``path`` (``":memory:"`` for none on disk), created when missing."""

    def __init__(self, path):
        self.path = path if path == ":memory:" else Path(path)
        if self.path != ":memory:":
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(str(self.path), check_same_thread=False, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.executescript(_SCHEMA)
        self._lock = threading.Lock()
        self.version = 0  # bumped at every change: the page redraws

    def add(self, cell: str, event: dict, received: float | None = None) -> bool:
        """Keep ``event`` of ``cell`` (True), or not when its ``seq`` is already kept (False: a duplicate)."""
        seq = int(event["seq"])
        with self._lock:
            cursor = self._db.execute(
                "INSERT OR IGNORE INTO events (cell, seq, kind, time, received, payload) VALUES (?, ?, ?, ?, ?, ?)",
                (cell, seq, event.get("kind"), event.get("time"), time.time() if received is None else received,
                 json.dumps(event, sort_keys=True)))
            added = cursor.rowcount == 1
            if added:
                self.version += 1
            return added

    def set_state(self, cell: str, event: dict) -> None:
        with self._lock:
            self._db.execute("INSERT OR REPLACE INTO states (cell, seq, received, payload) VALUES (?, ?, ?, ?)",
                             (cell, event.get("seq"), time.time(), json.dumps(event, sort_keys=True)))
            self.version += 1

    def cells(self) -> list[str]:
        with self._lock:
            rows = self._db.execute("SELECT cell FROM events UNION SELECT cell FROM states ORDER BY cell").fetchall()
        return [row[0] for row in rows]

    def events(self, cell: str, by_arrival: bool = False) -> list[dict]:
        """The events of ``cell``, by ``seq`` (or in the order they arrived), each with ``_received`` (s since 1970)."""
        order = "rowid" if by_arrival else "seq"
        with self._lock:
            rows = self._db.execute(f"SELECT payload, received FROM events WHERE cell = ? ORDER BY {order}",  # noqa: S608
                                    (cell,)).fetchall()
        return [dict(json.loads(payload), _received=received) for payload, received in rows]

    def state(self, cell: str) -> dict | None:
        with self._lock:
            row = self._db.execute("SELECT payload, received FROM states WHERE cell = ?", (cell,)).fetchone()
        return None if row is None else dict(json.loads(row[0]), _received=row[1])

    def count(self) -> int:
        with self._lock:
            return int(self._db.execute("SELECT COUNT(*) FROM events").fetchone()[0])

    def close(self) -> None:
        with self._lock:
            self._db.close()
