"""The values of a CSV of numbers (joint angles, poses), read by one set of rules wherever such a file is read.

- A field is a number as a person writes one in a CSV: ``-30``, ``60.5``, ``1e-3``. Refused, with what is
  wrong: ``nan``, ``inf`` and values beyond the float range (``1e400``: "not finite"), digit separators
  (``1_000``, which Python's ``float`` would read as 1000) and anything else ``float`` does not read
  (``6O``: a letter O for a zero).
- A header may only be a line none of whose fields looks like a number (:func:`is_header`): ``a1,a2,a3``
  is one; ``0,-30,6O,0,90,0`` (a typo), ``0 -30 60 0 90 0`` (spaces for commas) and ``0,10,0 # note``
  (a trailing comment) are rows with a bad value, refused, never silently skipped as a header.
"""

from __future__ import annotations

import math
import re

__all__ = ["is_header", "looks_like_number", "parse_value", "value_problem"]

#: The start of a field that is meant as a number: a sign, then a digit, a decimal point and digit, or nan/inf.
_NUMBER_START = re.compile(r"^[+-]?(\d|\.\d|nan|inf)", re.IGNORECASE)
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def looks_like_number(field: str) -> bool:
    """True when ``field`` starts as a number does (``6O``, ``0 -30 60``, ``nan``, ``1_000`` do; ``a1`` does not)."""
    return bool(_NUMBER_START.match(str(field).strip()))


def is_header(fields) -> bool:
    """True when a line of ``fields`` may be a header: no field of it looks like a number."""
    return not any(looks_like_number(f) for f in fields)


def value_problem(field: str) -> str:
    """What is wrong with ``field`` as a number, or ``""`` when it is a finite number (see the module docstring)."""
    text = str(field).strip()
    shown = repr(text[:40] + ("..." if len(text) > 40 else ""))
    if _NUMBER.match(text):
        return "" if math.isfinite(float(text)) else f"not finite: {shown} is beyond the float range"
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is not None and not math.isfinite(value):
        return f"not finite: {shown} (nan or inf); give a number"
    if "_" in text:
        return f"not a number: {shown} (write it without digit separators '_')"
    if "#" in text:
        return f"not a number: {shown} (a comment is a line of its own, starting with '#')"
    if looks_like_number(text) and re.search(r"\s", text):
        return f"not one number: {shown} (separate the values by commas)"
    return f"not a number: {shown}"


def parse_value(field: str) -> float:
    """``field`` as a finite float; ValueError saying what is wrong otherwise (:func:`value_problem`)."""
    problem = value_problem(field)
    if problem:
        raise ValueError(problem)
    return float(str(field).strip())
