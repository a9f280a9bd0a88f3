"""One side's numbers as a log holds them, before any reading: the unit every layout reader hands on."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Group"]


@dataclass
class Group:
    """The numbers of one side: ``values (n, width)``, where each row came from, and what names say."""

    values: np.ndarray
    labels: list
    names: list = field(default_factory=list)
    conventions: list | None = None
    declared: list = field(default_factory=list)
    direction: str | None = None
    keys: list | None = None

    @property
    def width(self) -> int:
        return int(self.values.shape[1])
