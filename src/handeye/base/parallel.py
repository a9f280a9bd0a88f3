"""Run numpy work on batches in a few threads.

numpy releases the interpreter lock inside its array loops and LAPACK calls, so splitting a large
batch (e.g. 161,700 small eigenproblems) over the machine's cores in threads gives a real speed-up
without processes or copies.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

__all__ = ["WORKERS", "map_chunks"]

T = TypeVar("T")
R = TypeVar("R")

#: Threads used for batch work (at most 4; 1 disables threading).
WORKERS = max(1, min(4, os.cpu_count() or 1))


def map_chunks(fn: Callable[[T], R], items: list[T]) -> list[R]:
    """``[fn(item) for item in items]``, in threads when there is more than one item.

    The threads live for this call only (starting them costs well under a millisecond), so no
    worker outlives the work or keeps a process from exiting.
    """
    if WORKERS == 1 or len(items) < 2:
        return [fn(item) for item in items]
    with ThreadPoolExecutor(max_workers=min(WORKERS, len(items)), thread_name_prefix="handeye-batch") as pool:
        return list(pool.map(fn, items))
