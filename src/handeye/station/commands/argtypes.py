"""Value types for the command line: each turns one argument into a checked value or an argparse
error that says what was expected (argparse prints it as one line and exits 2)."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from ...base import Registry
    from ...drivers import Setting
    from ...geometry import BoardGeometry

T = TypeVar("T")


class Subcommands(Protocol):
    """What a command's ``add_parser`` gets: the ``handeye`` parser's ``add_subparsers()``, whose parsers are
    ``cli.OneLineParser`` (an ``epilog`` may be a callable that writes it when the help is printed)."""

    def add_parser(self, name: str, **options: Any) -> argparse.ArgumentParser: ...

__all__ = ["Subcommands", "registry_choice", "left_out_lines", "option_word", "load_for_flags", "corners", "positive", "non_negative", "count", "whole_between", "port", "floats", "setting_value"]


def _number(text: str, kind: Callable[[str], T] = float, what: str = "a number") -> T:
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


def whole_between(low: int, high: int, why: str = "") -> Callable[[str], int]:
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


def setting_value(setting: Setting) -> Callable[[str], object]:
    """A type for a back end's described setting (``drivers.controller.backends.LinkSetting``): its
    type (text, whole number, number) within its ``low..high``."""
    kinds = {int: (int, "a whole number"), float: (float, "a number")}

    def convert(text: str) -> object:
        if setting.type not in kinds:
            return text
        kind, what = kinds[setting.type]
        value = _number(text, kind, what)
        if not setting.low <= value <= setting.high:
            raise argparse.ArgumentTypeError(f"must be between {setting.low:g} and {setting.high:g}; got {value}")
        return value

    convert.__name__ = setting.key  # argparse names the type in its messages
    return convert


def registry_choice(choices) -> Callable[[str], str]:
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


def option_word(words: Iterable[str] | None, option: str) -> str | None:
    """The value ``words`` (a command line) gives ``option`` (``--protocol X`` or ``--protocol=X``; the
    last one wins, as argparse's): ``""`` when it gives none, ``None`` when the help is asked for (every
    choice is then described). What a parser is built for, before it parses."""
    words, found = list(words or ()), ""
    if "-h" in words or "--help" in words:
        return None
    for i, word in enumerate(words):
        if word == option and i + 1 < len(words):
            found = words[i + 1]
        elif word.startswith(option + "="):
            found = word.split("=", 1)[1]
    return found


def load_for_flags(registry: Registry, wanted: str | None) -> None:
    """Load (under the time bound, quietly: the option's check says why one fails) the plug-ins whose own
    flags a parser must offer: the one ``wanted`` names, or every one when ``wanted`` is None (the help).
    A name that is not a plug-in's loads nothing."""
    from ...base import quiet_loads

    names = registry.plugin_names() if wanted is None else [wanted.lower()] if wanted else []
    with quiet_loads():
        for name in names:
            if registry.is_plugin(name):
                registry.get(name)


def target_spec(text: str) -> BoardGeometry:
    """``--board``: ``13x8`` (checkerboard corners), ``charuco``, ``circles``, or a kind with keys
    (``charuco:squares=14x9,square_mm=30``): :func:`~handeye.geometry.targets.parse_target_spec`."""
    from ...base import CalibrationError
    from ...geometry import STATION_BOARD
    from ...geometry import parse_target_spec

    try:
        board = parse_target_spec(text)
    except CalibrationError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--board ")) from None
    if getattr(board, "kind", "checkerboard") == "checkerboard" and board.square_mm is None:
        from dataclasses import replace

        board = replace(board, square_mm=STATION_BOARD.square_mm)  # the station's 30 mm squares
    return board


def corners_or_target(text: str) -> BoardGeometry | tuple[int, int]:
    """``--board`` of ``stereo calibrate``: ``13x8`` as before (a checkerboard's inner corners), or a target kind
    (``charuco``, ``charuco:squares=10x7,...``: :func:`target_spec`)."""
    if text.split(":")[0].lower() in ("charuco", "circles", "checkerboard"):
        return target_spec(text)
    return corners(text)
