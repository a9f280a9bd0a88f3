"""A client of the standalone mock controller's pendant port (``handeye mock controller --pendant-port``).

:class:`PendantClient` speaks the port's line protocol (``src/handeye/mocks/controller/pendant.py``: ``JOG``,
``START``, ``KEY``, ``STATE``); ``handeye mock pendant`` sends its requests through it.
"""

from __future__ import annotations

import socket
import time

__all__ = ["PendantClient", "PendantState"]


class PendantState:
    """A ``STATE`` reply: ``execution`` (running, prompt, stopped, ended, error, none), ``keys`` (number ->
    label of the answers offered) and ``text`` (the last pendant line)."""

    def __init__(self, reply: str):
        head, _, self.text = reply.partition(" | ")
        words = head.split()
        if len(words) < 3 or words[0] != "OK":
            raise ValueError(f"not a STATE reply: {reply!r}")
        self.execution = words[1]
        self.keys = {} if words[2] == "-" else {int(k): v for k, v in (item.split("=", 1) for item in words[2].split(","))}

    def key(self, label: str) -> int:
        """The key number of the answer ``label`` (KeyError when not offered)."""
        return next(k for k, v in self.keys.items() if v == label)


class PendantClient:
    """One connection to a pendant port ``HOST:PORT``."""

    def __init__(self, address: str, timeout_s: float = 120.0):
        host, _, port = address.rpartition(":")
        self._sock = socket.create_connection((host, int(port)), timeout=timeout_s)
        self._file = self._sock.makefile("rb")

    def ask(self, line: str) -> str:
        self._sock.sendall(line.encode("ascii") + b"\n")
        reply = self._file.readline()
        if not reply:
            raise ConnectionError("the pendant port closed the connection")
        return reply.decode("ascii", "replace").rstrip("\n")

    def state(self) -> PendantState:
        return PendantState(self.ask("STATE"))

    def wait(self, execution: str, timeout_s: float, poll_s: float = 0.02) -> PendantState:
        """Poll ``STATE`` until the execution is ``execution``; TimeoutError after ``timeout_s``."""
        end = time.monotonic() + timeout_s
        while True:
            state = self.state()
            if state.execution == execution:
                return state
            if time.monotonic() > end:  # (ended, error, none: a program being loaded, for a moment)
                raise TimeoutError(f"the pendant is {state.execution}, not {execution}, after {timeout_s:g} s: "
                                   f"{state.text}")
            time.sleep(poll_s)

    def jog(self, joints) -> str:
        return self.ask("JOG " + " ".join(f"{float(v):.4f}" for v in joints))

    def close(self) -> None:
        self._file.close()
        self._sock.close()
