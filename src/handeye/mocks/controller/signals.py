"""The cell's I/O signals of a mock controller: a door switch, a ready input, a lamp, as a station has.

A program a station engineer edits waits for the cell (``WaitDI diCellDoor, 1 \\MaxTime:=30;``) and
sets outputs (``SetDO doCellLamp, 1;``). :class:`CellSignals` is the mock's table of such signals,
beside the link's own (the Modbus gateway's registers, which it passes through): the program reads and
writes them as I/O signals; a test or the pendant sets a digital input with :meth:`CellSignals.set`
(over the mock's cell port: ``{"cmd": "signal", "name": "diCellDoor", "value": 0}``). A ``WaitDI`` with
``\\MaxTime`` on an input that does not come raises ``ERR_WAIT_MAXTIME``, as on a controller.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Mapping

from ...rapid import IoBinding

__all__ = ["CellSignals", "CELL_SIGNALS", "parse_signal"]

#: The cell signals every mock controller has: name -> (type, value at start).
CELL_SIGNALS = {
    "diCellDoor": ("signaldi", 1.0),  # the cell door is closed (1) or open (0)
    "diCellReady": ("signaldi", 1.0),  # the cell (a PLC) lets the robot work
    "doCellLamp": ("signaldo", 0.0),  # the lamp at the cell door
    "doCellBusy": ("signaldo", 0.0),  # the robot works in the cell
}
_TYPES = ("signaldi", "signaldo", "signalgi", "signalgo", "signalai", "signalao")


def parse_signal(text: str) -> tuple:
    """``NAME:TYPE=VALUE`` (``diFence:signaldi=1``) as ``(name, type, value)``; ValueError saying the form."""
    head, _, value = text.partition("=")
    name, _, kind = head.partition(":")
    try:
        number = float(value)
    except ValueError:
        number = None
    if not name.isidentifier() or kind.lower() not in _TYPES or number is None:
        raise ValueError(f"--signal {text!r}: expected NAME:TYPE=VALUE with TYPE one of {', '.join(_TYPES)} "
                         "(diFence:signaldi=1)")
    return name, kind.lower(), number


class CellSignals(IoBinding):
    """The cell's signals (see the module docstring) in front of the link's own I/O (``inner``).

    Parameters
    ----------
    table : dict, optional
        name -> (type, value at start); default :data:`CELL_SIGNALS`. Extra signals add to it.
    """

    def __init__(self, table: Mapping[str, tuple[str, float]] | None = None,
                 extra: Iterable[tuple[str, str, float]] = ()):
        self._table = dict(CELL_SIGNALS if table is None else table)
        for name, kind, value in extra:
            self._table[name] = (kind, value)
        self._types = {name: kind for name, (kind, _) in self._table.items()}
        self._values = {name: float(value) for name, (_, value) in self._table.items()}
        self._lock = threading.Lock()
        self.inner: IoBinding | None = None

    def over(self, inner: IoBinding | None) -> "CellSignals":
        """These signals in front of ``inner`` (the link's I/O, or None); returns self."""
        self.inner = inner
        return self

    def _inner(self, name: str) -> IoBinding:
        """The link's I/O, for a signal that is not the cell's (KeyError, as a dict of signals: none such)."""
        if self.inner is None:
            raise KeyError(name)
        return self.inner

    def signals(self) -> dict:
        return {**(self.inner.signals() if self.inner is not None else {}), **self._types}

    def read(self, name: str) -> float:
        if name in self._values:
            with self._lock:
                return self._values[name]
        return self._inner(name).read(name)

    def write(self, name: str, value: float) -> None:
        if name in self._values:
            with self._lock:
                self._values[name] = float(value)
            return
        self._inner(name).write(name, value)

    def bits(self, name: str) -> int:
        return 16 if name in self._values else self._inner(name).bits(name)

    def set(self, name: str, value: float) -> None:
        """Set a cell input from outside (a test, the pendant): a digital input takes 0 or 1.

        Raises
        ------
        ValueError
            Not a cell input, or a digital value other than 0 and 1.
        """
        kind = self._types.get(name)
        if kind is None or not kind.endswith("i"):  # signaldi, signalgi, signalai
            known = ", ".join(n for n, k in self._types.items() if k.endswith("i"))
            raise ValueError(f"{name!r} is not an input of the mock cell (its inputs: {known})")
        if kind == "signaldi" and value not in (0, 1):
            raise ValueError(f"{name} is a digital input: 0 or 1, not {value:g}")
        with self._lock:
            self._values[name] = float(value)

    def value(self, name: str) -> float:
        """The signal's value now (a test reads an output the program set)."""
        return self.read(name)
