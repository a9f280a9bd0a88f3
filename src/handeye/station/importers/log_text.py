"""Text tables of pose numbers: CSV, TSV, semicolons or spaces, with or without a header.

:func:`parse_table` turns the text into numeric rows grouped in blocks (a block ends at a text
line, a blank line or a change of width) and finds the header (the text line just above the first
block with one name per column). A line may carry a label (``robot:``, ``pose 3:``) and brackets;
``1,5;2,5`` (decimal commas between semicolons) reads as ``1.5; 2.5``. Rows of 4 (or 3) numbers are
matrix rows: :func:`matrices_from_rows` groups them into 4x4 (or 3x4) matrices.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Row", "Table", "parse_table", "matrices_from_rows", "MAX_COLUMNS"]

#: Longer rows are not pose logs (a pose pair is 32 numbers at most, with a few extra columns).
MAX_COLUMNS = 64
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf|infinity)", re.IGNORECASE)
_LABEL = re.compile(r"^\s*[A-Za-z_][\w .\-]*:\s*")
_DECIMAL_COMMA = re.compile(r"^[-+]?\d+,\d+$")


@dataclass(frozen=True)
class Row:
    """One line of numbers: its line number (1-based), the values and the block it belongs to."""

    line: int
    values: tuple
    block: int


@dataclass
class Table:
    """The numeric rows of a text, their blocks, the header names (if any) and the text lines."""

    rows: list
    header: list | None = None
    labels: dict = field(default_factory=dict)  # block -> the text line above it

    @property
    def widths(self) -> set:
        return {len(r.values) for r in self.rows}

    def blocks(self) -> list:
        """Rows grouped by block, in order."""
        out: dict = {}
        for r in self.rows:
            out.setdefault(r.block, []).append(r)
        return list(out.values())


def _fields(line: str) -> list:
    text = line.strip().strip("[](){}").strip()
    if ";" in text:
        parts = [p.strip().strip("[](){}") for p in text.split(";")]
        return [p.replace(",", ".") if _DECIMAL_COMMA.match(p) else p for p in parts if p != ""]
    return [p for p in re.split(r"[,\s\t]+", text.replace("[", " ").replace("]", " ")) if p != ""]


def _numbers(line: str):
    """The numbers of a line, or ``None`` when it holds anything else (after an optional label)."""
    body = _LABEL.sub("", line, count=1) if _LABEL.match(line) and not _NUMBER.fullmatch(line.split(":")[0].strip()) else line
    parts = _fields(body)
    if not parts or len(parts) > MAX_COLUMNS:
        return None
    values = []
    for part in parts:
        if not _NUMBER.fullmatch(part):
            return None
        try:
            values.append(float(part))
        except (ValueError, OverflowError):
            return None
    return tuple(values)


def _names(line: str) -> list:
    text = line.strip().lstrip("#%/").strip()
    parts = [p.strip().strip("\"'") for p in re.split(r"[,;\t]|\s+", text) if p.strip()]
    return parts


def parse_table(text: str) -> Table:
    """Numeric rows, blocks and header of a text (module docstring)."""
    rows, header, labels = [], None, {}
    block, last_width, pending = 0, None, None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            if last_width is not None:
                block, last_width = block + 1, None
            continue
        values = _numbers(line) if not line.lstrip().startswith(("#", "//", "%")) else None
        if values is None:
            if last_width is not None:
                block, last_width = block + 1, None
            pending = line
            continue
        if last_width is not None and len(values) != last_width:
            block += 1
        if last_width is None and pending is not None:
            labels[block] = pending
            names = _names(pending)
            if header is None and not rows and len(names) == len(values):
                header = names
        pending = None
        last_width = len(values)
        rows.append(Row(number, values, block))
    return Table(rows, header, labels)


def matrices_from_rows(rows: list) -> list:
    """Group consecutive rows of 4 numbers into matrices: ``(first line, 16 or 12 values, block)``.

    Four rows make a 4x4 matrix when the fourth is ``0 0 0 1``; otherwise three rows make a 3x4
    matrix. Returns an empty list when the rows do not group evenly.
    """
    if any(len(r.values) != 4 for r in rows):
        return []
    out, k = [], 0
    while k < len(rows):
        group = rows[k:k + 4]
        if len(group) == 4 and np.allclose(group[3].values, (0.0, 0.0, 0.0, 1.0), atol=1e-6) and len(
                {r.block for r in group}) == 1:
            out.append((group[0].line, sum((r.values for r in group), ()), group[0].block))
            k += 4
            continue
        group = rows[k:k + 3]
        if len(group) == 3 and len({r.block for r in group}) == 1:
            out.append((group[0].line, sum((r.values for r in group), ()), group[0].block))
            k += 3
            continue
        return []
    return out
