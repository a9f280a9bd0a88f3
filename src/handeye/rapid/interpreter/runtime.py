"""A RAPID task: the program's ``main`` run in a thread, with interrupts, waits, stop and hold.

The task runs ``main`` in continuous mode (when ``main`` returns it starts again). Waiting
instructions (``WaitTime``, ``WaitUntil``, ``WaitDI``, a receive with ``\\Time``, a move) call
:meth:`Task.idle`, which sleeps, runs TRAP routines whose interrupts came due (``ITimer``), and
notices a stop request. Between statements the task does the same. ``hold`` freezes the program
where it is (a stopped program whose I/O gateway still answers: the heartbeat stops).

When the program stops on an error no handler took, :attr:`Task.error` says what and where.
"""

from __future__ import annotations

import logging
import math
import select
import socket
import threading
from collections import deque
from time import monotonic
from typing import TYPE_CHECKING

from .errors import RapidFatalError, RapidRuntimeError
from .frames import ExitSignal, Frame, StopSignal, TaskStopped
from .values import to_num

if TYPE_CHECKING:
    from .scope import RoutineSymbol

__all__ = ["Task", "TrapFailed"]

log = logging.getLogger(__name__)

#: Longest sleep inside a wait before the task looks again (stop requests, timers wake it sooner).
_SLICE_S = 0.25


class TrapFailed(RapidFatalError):
    """An error no handler took inside a TRAP routine: the program stops (never the main program's handler)."""


class _Timer:
    __slots__ = ("number", "period", "single", "due", "asleep")

    def __init__(self, number: int, period: float, single: bool, due: float):
        self.number, self.period, self.single, self.due, self.asleep = number, period, single, due, False


class Task:
    """One RAPID task running a linked :class:`~handeye.rapid.interpreter.program.Program`.

    Parameters
    ----------
    program : Program
    bindings : Bindings
        The world the program talks to (sockets, serial channels, I/O, the arm, the pendant).
    name : str
        The task's name (``T_ROB1``).

    Attributes
    ----------
    state : str
        ``ready``, ``running``, ``stopped`` (asked to, or a ``Stop`` instruction), ``exited``
        (``EXIT``) or ``error``.
    error : str or None
        Why the program stopped on an error (``HeSocket.mod:123: ERR_SOCK_CLOSED ...``).
    ended : str or None
        How the program ended by itself other than on an error (``EXIT at HeMain.mod:4``, ``a Stop
        instruction``); None while it runs, after an error, or when it was asked to stop.
    main_returns : int
        How many times ``main`` ran to its end (continuous run mode starts it again).
    pendant : collections.deque
        The last lines ``TPWrite`` wrote.
    """

    def __init__(self, program, bindings, name: str = "T_ROB1"):
        self.program, self.bindings, self.name = program, bindings, name
        self.errno = 0
        self.undoing = 0  # UNDO handlers running: a stop request waits for them
        self.attention = False
        self.next_due = math.inf
        self.state, self.error, self.ended = "ready", None, None
        self.main_returns = 0
        self.halted = False  # stopped by Stop \NoRegain, waiting for Start
        self.pendant: deque = deque(maxlen=200)
        self.resources: list = []  # what bindings opened for this task (closed when it ends)
        self._timers: dict[int, _Timer] = {}
        self._traps: dict[int, RoutineSymbol] = {}
        self._pending: deque = deque()
        self._next_interrupt = 0
        self._in_trap = False
        self._stop = threading.Event()
        self._held = threading.Event()
        self._waiting = threading.Event()
        self._finished = threading.Event()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._thread: threading.Thread | None = None
        self.clock = monotonic

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> "Task":
        """Run ``main`` in a thread of its own."""
        main = self.program.main
        if main is None:
            raise RapidFatalError("the program has no PROC main")
        self.state = "running"
        self._thread = threading.Thread(target=self._run, name=f"rapid-{self.name}", daemon=True)
        self._thread.start()
        return self

    def _run(self) -> None:
        main = self.program.main.compiled
        try:
            while True:  # continuous run mode: main starts again when it returns
                main.run(Frame(self, main, main.size))
                self.main_returns += 1
                self.service()
        except TaskStopped:
            self.state = "stopped"
        except StopSignal:
            self.state, self.ended = "stopped", "a Stop instruction"
            log.warning("RAPID task %s: stopped by the Stop instruction", self.name)
        except ExitSignal as signal:
            self.state = "exited"
            self.ended = f"EXIT at {signal.args[0]}" if signal.args else "EXIT"
        except (RapidRuntimeError, RapidFatalError) as err:
            self.state, self.error = "error", str(err)
            log.error("RAPID task %s stopped: %s", self.name, err)
        except Exception as exc:  # a binding failed: the program stops, the message says what
            self.state, self.error = "error", f"internal error: {type(exc).__name__}: {exc}"
            log.exception("RAPID task %s stopped on an internal error", self.name)
        finally:
            self._release()
            for sock in (self._wake_r, self._wake_w):
                sock.close()
            self._waiting.set()
            self._finished.set()

    def _release(self) -> None:
        for resource in reversed(self.resources):
            try:
                resource.close()
            except Exception:  # pragma: no cover - best effort at the end of a task
                log.debug("closing %r failed", resource, exc_info=True)
        self.resources.clear()

    def stop(self, timeout: float = 10.0) -> None:
        """Ask the program to stop and wait for its thread (its sockets and channels are closed)."""
        self._stop.set()
        self.attention = True
        self._wake()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)
        for sock in (self._wake_r, self._wake_w):
            sock.close()

    def wait_idle(self, timeout: float) -> bool:
        """Wait until the program first waits for something (ready to serve) or ends; True if so."""
        return self._waiting.wait(timeout)

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def finished(self) -> threading.Event:
        return self._finished

    def hold(self, held: bool) -> None:
        """Freeze (True) or release (False) the program: nothing runs, no interrupt fires meanwhile."""
        if held:
            self._held.set()
            self.attention = True
        else:
            self._held.clear()
            self.attention = self._stop.is_set()
            now = self.clock()
            for timer in self._timers.values():  # missed periods do not fire in a burst
                timer.due = max(timer.due, now)
            self._reschedule()
        self._wake()

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"x")
        except OSError:
            pass

    # ------------------------------------------------------------------ between statements
    def service(self) -> None:
        """Stop, hold, and the TRAP routines of interrupts that came due (a stop waits for UNDO handlers)."""
        if self._stop.is_set():
            if self.undoing:
                return
            raise TaskStopped()
        while self._held.is_set():
            self._held_wait()
        now = self.clock()
        if now >= self.next_due:
            for timer in list(self._timers.values()):
                if timer.due <= now:
                    if not timer.asleep:
                        self._pending.append(timer.number)
                    if timer.single:
                        del self._timers[timer.number]
                    else:
                        timer.due = max(timer.due + timer.period, now + timer.period * 0.5)
            self._reschedule()
        if self._pending and not self._in_trap:
            self._run_traps()

    def halt(self, resumed: threading.Event) -> None:
        """``Stop \\NoRegain``: execution stops at this instruction (the program pointer stays) until
        ``resumed`` is set (the pendant's Start); nothing runs meanwhile, no interrupt fires, missed timer
        periods do not fire in a burst. A stop request ends the wait (``TaskStopped``)."""
        self.halted = True
        try:
            while not resumed.is_set():
                if self._stop.is_set():
                    raise TaskStopped()
                select.select([self._wake_r], [], [], 0.02)
                self._drain()
        finally:
            self.halted = False
        now = self.clock()
        for timer in self._timers.values():
            timer.due = max(timer.due, now)
        self._reschedule()

    def _held_wait(self) -> None:
        if self._stop.is_set():
            raise TaskStopped()
        select.select([self._wake_r], [], [], _SLICE_S)
        self._drain()

    def _drain(self) -> None:
        try:
            while self._wake_r.recv(64):
                pass
        except OSError:
            pass

    def _reschedule(self) -> None:
        self.next_due = min((t.due for t in self._timers.values()), default=math.inf)

    def _run_traps(self) -> None:
        self._in_trap = True
        try:
            while self._pending:
                number = self._pending.popleft()
                trap = self._traps.get(number)
                if trap is None:
                    continue
                routine = trap.compiled
                if routine is None:  # Program compiles every routine before a task runs
                    raise RapidFatalError(f"TRAP {trap.name} is not compiled")
                try:
                    routine.run(Frame(self, routine, routine.size))
                except RapidRuntimeError as err:
                    raise TrapFailed(f"TRAP {routine.name}: {err}") from None
        finally:
            self._in_trap = False

    # ------------------------------------------------------------------ waiting
    def idle(self, seconds: float | None, readable=()) -> bool:
        """Wait ``seconds`` (None: for ever) or until one of ``readable`` (sockets) has data.

        Interrupts are served meanwhile; a stop request ends the wait (``TaskStopped``). Returns True
        when a socket became readable, False when the time ran out.
        """
        self._waiting.set()
        if self._stop.is_set() and self.undoing:  # a stopped task's UNDO handler does not wait (nor move)
            raise TaskStopped()
        end = math.inf if seconds is None else self.clock() + max(0.0, seconds)
        while True:
            self.service()
            now = self.clock()
            if now >= end:
                return False
            wait = min(end - now, self.next_due - now, _SLICE_S)
            ready, _, _ = select.select([self._wake_r, *readable], [], [], max(wait, 0.0))
            if self._wake_r in ready:
                self._drain()
            if any(r is not self._wake_r for r in ready):
                self.service()
                return True

    def poll_until(self, condition, seconds: float | None, poll: float) -> bool:
        """Evaluate ``condition()`` now and every ``poll`` seconds; True when it held, False after ``seconds``."""
        end = math.inf if seconds is None else self.clock() + seconds
        while True:
            if condition():
                return True
            left = end - self.clock()
            if left <= 0:
                return False
            self.idle(min(poll, left))

    # ------------------------------------------------------------------ interrupts
    def connect(self, ref, trap) -> None:
        """``CONNECT ref WITH trap``: a new interrupt number in ``ref``."""
        if ref.get() and int(ref.get()) in self._traps:
            raise RapidRuntimeError("ERR_ALRDYCNT", "the interrupt variable is already connected")
        self._next_interrupt += 1
        number = self._next_interrupt
        self._traps[number] = trap
        ref.set(to_num(number))

    def interrupt(self, ref):
        """The interrupt number held by ``ref`` (0 when not connected)."""
        value = ref.get() if hasattr(ref, "get") else ref
        number = int(value or 0)
        return number if number in self._traps else 0

    def delete_interrupt(self, ref) -> None:
        """``IDelete``: forget the interrupt (no error when it was not connected)."""
        number = self.interrupt(ref)
        if number:
            self._traps.pop(number, None)
            self._timers.pop(number, None)
            self._reschedule()
        if hasattr(ref, "set"):
            ref.set(0.0)

    def order_timer(self, number: int, period: float, single: bool) -> None:
        """``ITimer``: the interrupt every ``period`` seconds (once with ``\\Single``)."""
        self._timers[number] = _Timer(number, period, single, self.clock() + period)
        self._reschedule()

    def sleep_interrupt(self, number: int, asleep: bool) -> None:
        timer = self._timers.get(number)
        if timer is not None:
            timer.asleep = asleep

    # ------------------------------------------------------------------ the world
    def io_read(self, name: str) -> float:
        io = self.bindings.io
        if io is None:
            raise RapidFatalError(f"signal {name}: this controller has no I/O")
        return float(io.read(name))

    def write_pendant(self, text: str) -> None:
        self.pendant.append(text)
        self.bindings.write_pendant(text)
