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
