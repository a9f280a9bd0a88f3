"""Fault injection for the mock controller servers, switchable while they run.

Set attributes from a test (or the station's demo) and the next requests feel them::

    server.faults.drop_next = 1        # close the connection instead of answering the next request
    server.faults.drop_after = 2       # answer 2 more requests, then close instead of answering
    server.faults.delay_s = 0.2        # answer every request 0.2 s late
    server.faults.garbage_next = 1     # answer the next request with garbage bytes
    server.faults.silent = True        # read requests and never answer (a hung controller)
    server.faults.robot_stalled = True # the RAPID program is held (the Modbus gateway still answers)
    server.faults.modbus_exception = 4 # Modbus: answer every request with exception code 4
    server.faults.modbus_exception_next = 1   # ... only the next request (code modbus_exception or 4)
    server.faults.busy_next = 2        # RWS: answer the next 2 requests with 503 (busy)
    server.faults.busy = True          # RWS: answer every request with 503
    server.faults.mastership_held = True   # RWS: another client (a FlexPendant) holds mastership
    server.faults.reset()
"""

from __future__ import annotations

import threading
from collections.abc import Callable

__all__ = ["Faults", "DEFAULT_GARBAGE"]

#: Bytes sent instead of a reply by ``garbage_next``: non-printable, then a line end.
DEFAULT_GARBAGE = b"\x00\xff\x13#!noise\xfe\x07 OK OK\r\n"


class Faults:
    """Fault switches of one mock server (thread-safe counters)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._watchers: list = []
        self._stalled = False
        self.reset()

    @property
    def robot_stalled(self) -> bool:
        """The RAPID program is held where it is (no statement, no interrupt runs)."""
        return self._stalled

    @robot_stalled.setter
    def robot_stalled(self, value: bool) -> None:
        self._stalled = bool(value)
        for watcher in list(self._watchers):
            watcher(self._stalled)

    def watch_stall(self, watcher: Callable[[bool], object]) -> None:
        """Call ``watcher(stalled)`` whenever :attr:`robot_stalled` is set (the server holds its task)."""
        self._watchers.append(watcher)

    def reset(self) -> None:
        """Switch every fault off."""
        self.delay_s = 0.0
        self.drop_next = 0
        self.drop_after = 0
        self.garbage_next = 0
        self.garbage = DEFAULT_GARBAGE
        self.silent = False
        self.robot_stalled = False
        self.modbus_exception = 0
        self.modbus_exception_next = 0
        self.busy = False
        self.busy_next = 0
        self.mastership_held = False
        #: How many times each fault fired (for tests).
        self.fired = {"drop": 0, "garbage": 0, "silent": 0, "modbus_exception": 0, "busy": 0}

    def take(self, name: str) -> bool:
        """Consume one unit of the counter ``name`` (e.g. ``drop_next``); True if one was left."""
        with self._lock:
            left = getattr(self, name)
            if left > 0:
                setattr(self, name, left - 1)
                return True
            return False

    def should_drop(self) -> bool:
        """True when this request is to be answered by closing the connection (drop_next / drop_after)."""
        with self._lock:
            if self.drop_after > 0:
                self.drop_after -= 1
                if self.drop_after == 0:
                    self.drop_next += 1
                return False
            if self.drop_next > 0:
                self.drop_next -= 1
                self.fired["drop"] = self.fired.get("drop", 0) + 1
                return True
            return False

    def note(self, kind: str) -> None:
        with self._lock:
            self.fired[kind] = self.fired.get(kind, 0) + 1
