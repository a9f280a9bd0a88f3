"""A progress bar for long work (rich), quiet when the output is not a terminal."""

from __future__ import annotations

import sys
from contextlib import contextmanager


@contextmanager
def progress_bar(title: str):
    """Yield ``update(done, total, label)``; draws a rich progress bar with time left."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    progress = Progress(TextColumn(f"[bold]{title}[/]"), BarColumn(), MofNCompleteColumn(),
                        TextColumn("{task.description}"), TimeRemainingColumn(),
                        transient=False, disable=not sys.stderr.isatty(), console=None)
    with progress:
        task = progress.add_task("", total=None)

        def update(done, total, label=""):
            progress.update(task, completed=done, total=total, description=label)

        yield update


@contextmanager
def delayed_progress(title: str, delay_s: float = 1.0):
    """Yield ``update(done, total, label)`` that shows a progress bar only once ``delay_s`` has passed.

    A calibration that takes less than a second prints nothing; a longer one (hundreds of postures)
    shows its stages. Quiet when the output is not a terminal.
    """
    import time

    started = time.monotonic()
    state: dict = {}
    try:
        def update(done, total, label=""):
            if "bar" not in state:
                if time.monotonic() - started < delay_s or not sys.stderr.isatty():
                    return
                state["context"] = progress_bar(title)
                state["bar"] = state["context"].__enter__()
            state["bar"](done, total, label)

        yield update
    finally:
        if "context" in state:
            state["context"].__exit__(None, None, None)
