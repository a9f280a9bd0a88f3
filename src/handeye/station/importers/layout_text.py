"""Any text as rows of numbers with their tags and positions: the raw material of the layout search.

Every line is split at any separator (spaces, tabs, ``,`` ``;`` ``:`` ``|`` ``=``, brackets). A line
whose first field is not a number carries a *tag*: its leading words (``hand``, ``Eye:``, ``P``,
``robot:``, ``image7.png``), compared in lower case without digits and punctuation (``C1`` and ``c``
are one tag; the digits, when there are some, are kept as the row's posture *key*: ``image7.png`` ->
7). Lines that hold no number, or start with ``#``, ``//`` or ``%``, are *text lines* (comments,
headers, labels); a line holding one whole number alone is a *count line* (``12`` before a list of
twelve matrices). An XML-like element on one line (``<Position X="812.4" Y="-120.3" ... C="30"/>``,
``<X>812.4</X>``) is a row tagged by its element name, its values the numbers of its attributes and
text, in order (words such as ``Mode="AUTO"`` skipped; an element without a number is a text
line). Both, and blank lines, are recorded as breaks between the numeric rows:
``section`` counts text and count lines, ``run`` counts every break (blank lines too), so that a
layout can read blocks either way.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["TextRow", "tokenise"]

_SPLIT = re.compile(r"[\s,;:|=\[\](){}]+")
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf|infinity)", re.IGNORECASE)
_DIGITS = re.compile(r"\d+")
_ELEMENT = re.compile(r"^<\s*([A-Za-z_][\w:.\-]*)")
_ELEMENT_VALUES = re.compile(r"""=\s*"([^"]*)"|=\s*'([^']*)'|>([^<]+)<""")
#: Longer rows are no pose log's (a camera-calibration row with intrinsics, R, t and 14 distortion
#: coefficients is under 40 numbers).
MAX_NUMBERS = 96


@dataclass(frozen=True)
class TextRow:
    """One line of numbers.

    Attributes
    ----------
    line : int
        1-based line number.
    tag : str
        The leading words normalised (lower case, letters only); ``""`` when the line starts with a number.
    key : int or None
        The digits in the leading words (a posture or image number), if any.
    values : tuple of float
    section : int
        Index of the stretch between text lines and count lines.
    run : int
        Index of the stretch between any breaks (blank lines included).
    label : str
        The text line last seen before this row's section (``""`` when none).
    """

    line: int
    tag: str
    key: int | None
    values: tuple
    section: int
    run: int
    label: str = ""


def _element(line: str) -> tuple[list, list] | None:
    """(element name, numbers of its attributes and text) of an XML-like line, ``None`` for other lines."""
    found = _ELEMENT.match(line)
    if not found:
        return None
    numbers = []
    for match in _ELEMENT_VALUES.finditer(line + "<"):
        for field in (next(g for g in match.groups() if g is not None)).split():
            if _NUMBER.fullmatch(field):
                try:
                    numbers.append(float(field))
                except (ValueError, OverflowError):
                    return [found.group(1)], []
    return [found.group(1)], numbers


def _split(line: str) -> tuple[list, list]:
    """(leading words, numbers) of a line; the numbers are ``None`` when words follow the first number
    and are not all units or names between numbers (then the line is text)."""
    element = _element(line.strip())
    if element is not None:
        return element
    fields = [f for f in _SPLIT.split(line.strip()) if f]
    words, numbers = [], []
    for f in fields:
        if _NUMBER.fullmatch(f):
            try:
                numbers.append(float(f))
            except (ValueError, OverflowError):
                return words, []
        elif not numbers:
            words.append(f)
        # a word among the numbers (``x 1 y 2``, ``fx``) is a field name: skipped
    return words, numbers


def tokenise(text: str) -> list:
    """The numeric rows of ``text`` (module docstring), in order."""
    rows, section, run, label, broke, last_text = [], 0, 0, "", False, False
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            broke = True
            continue
        words, values = _split(stripped) if not stripped.startswith(("#", "//", "%")) else ([], [])
        if not values or len(values) > MAX_NUMBERS:
            section, run, label, broke, last_text = section + 1, run + 1, stripped, False, True
            continue
        if not words and len(values) == 1 and float(values[0]).is_integer():  # a count line
            section, run, broke = section + 1, run + 1, False
            label, last_text = (label if last_text else ""), False
            continue
        last_text = False
        if broke:
            run, broke = run + 1, False
        head = "".join(words)
        tag = re.sub(r"[^a-z]+", "", head.lower())
        digits = _DIGITS.findall(head)
        key = int(digits[-1]) if digits else None
        rows.append(TextRow(number, tag, key, tuple(values), section, run, label))
    return rows
