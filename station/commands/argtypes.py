"""Value types for the command line: each turns one argument into a checked value or an argparse
error that says what was expected (argparse prints it as one line and exits 2)."""

from __future__ import annotations

import argparse

__all__ = ["corners", "positive", "non_negative", "count", "port", "floats", "six_floats"]


def _number(text: str, kind=float, what: str = "a number"):
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}") from None


def corners(text: str) -> tuple[int, int]:
    """``13x8`` -> ``(13, 8)`` (the larger count first: x runs along the long side)."""
    try:
        a, b = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"corners must look like 13x8; got {text!r}") from None
    if a < 2 or b < 2:
        raise argparse.ArgumentTypeError("a board needs at least 2x2 inner corners")
    return max(a, b), min(a, b)


def positive(text: str) -> float:
    value = _number(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0; got {text}")
    return value


def non_negative(text: str) -> float:
    value = _number(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0; got {text}")
    return value


def count(text: str) -> int:
    value = _number(text, int, "a whole number")
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0; got {text}")
    return value


def port(text: str) -> int:
    value = _number(text, int, "a port number")
    if not 0 <= value < 65536:
        raise argparse.ArgumentTypeError(f"port must be 0..65535; got {value}")
    return value


def floats(text: str) -> tuple:
    """``1,2.5,3`` -> ``(1.0, 2.5, 3.0)``."""
    try:
        return tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers; got {text!r}") from None


def six_floats(text: str) -> tuple:
    values = floats(text)
    if len(values) != 6:
        raise argparse.ArgumentTypeError(f"expected six comma-separated numbers; got {len(values)}")
    return values
