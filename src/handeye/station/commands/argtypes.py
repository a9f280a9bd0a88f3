"""Value types for the command line: each turns one argument into a checked value or an argparse
error that says what was expected (argparse prints it as one line and exits 2)."""

from __future__ import annotations

import argparse

__all__ = ["registry_choice", "left_out_lines", "corners", "positive", "non_negative", "count", "whole_between", "port", "floats", "setting_value"]


def _number(text: str, kind=float, what: str = "a number"):
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}") from None


def corners(text: str) -> tuple[int, int]:
    """``13x8`` -> ``(13, 8)``: inner corners along x, then along y; x runs along the long side, so
    the long side comes first (``8x13`` would name another corner order and is refused)."""
    try:
        a, b = (int(v) for v in text.lower().replace("×", "x").split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"corners must look like 13x8; got {text!r}") from None
    if a < 2 or b < 2:
        raise argparse.ArgumentTypeError("a board needs at least 2x2 inner corners")
    if a < b:
        raise argparse.ArgumentTypeError(f"give the long side first: {b}x{a}, not {text} (x runs along the long side; "
                                         "the corner order follows it)")
    return a, b


def whole_between(low: int, high: int, why: str = ""):
    """A type for a whole number in ``low..high`` (``why`` explains the bound in the error)."""

    def convert(text: str) -> int:
        value = _number(text, int, "a whole number")
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be between {low} and {high}; got {value}{why}")
        return value

    convert.__name__ = f"whole number {low}..{high}"
    return convert


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


def setting_value(setting):
    """A type for a back end's described setting (``drivers.controller.backends.LinkSetting``): its
    type (text, whole number, number) within its ``low..high``."""
    kinds = {int: (int, "a whole number"), float: (float, "a number")}

    def convert(text: str):
        if setting.type not in kinds:
            return text
        kind, what = kinds[setting.type]
        value = _number(text, kind, what)
        if not setting.low <= value <= setting.high:
            raise argparse.ArgumentTypeError(f"must be between {setting.low:g} and {setting.high:g}; got {value}")
        return value

    convert.__name__ = setting.key  # argparse names the type in its messages
    return convert


def registry_choice(choices):
    """A type for one name of a registry's :class:`~handeye.base.registry.Choices`: checking it loads
    that plug-in only; a name that is not a choice is refused saying why (an installed plug-in that lacks
    what the command needs, or did not load) and what the choices are."""

    def convert(text: str) -> str:
        if text in choices:
            return text
        why = choices.refusal(text)
        raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from {choices.listed()})"
                                         + (f": {why}" if why else ""))

    return convert


def left_out_lines(choices, what: str) -> str:
    """Lines for a help text: the installed plug-ins ``choices`` leave out and why (empty when none);
    ``what`` says what they were left out of (``--protocol``)."""
    left = choices.left_out()
    if not left:
        return ""
    return f"\nInstalled plug-ins left out of {what}:\n" + "\n".join(f"  {why}" for why in left.values()) + "\n"
