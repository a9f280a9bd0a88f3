"""Tokens of RAPID source: identifiers, keywords, numbers, strings, operators, with their line.

Keywords and identifiers are case-insensitive in RAPID: a keyword token carries its upper-case word
in ``value``; an identifier keeps its spelling in ``text`` (names are compared lower-cased).
String literals are decoded: ``""`` is one quote, ``\\\\`` one backslash, ``\\hh`` the character of
hexadecimal code ``hh``. ``!`` starts a comment to the end of the line.

What RobotStudio writes before ``MODULE`` is accepted: a UTF-8 byte order mark (as the character
U+FEFF, or as its three bytes read as Latin-1) and the file header ``%%%`` / ``VERSION:1`` /
``LANGUAGE:ENGLISH`` / ``%%%``; the header's lines count for the line numbers of messages.

This is the one RAPID lexer of the package: the interpreter's parser and the static checks of
:mod:`handeye.rapid.checks` read source through :func:`tokenize`, and :data:`KEYWORDS` is the one
list of RAPID's reserved words.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import RapidLoadError

__all__ = ["Token", "KEYWORDS", "tokenize", "decode_string", "strip_preamble"]

#: Reserved words of RAPID (Technical reference manual, RAPID kernel).
KEYWORDS = frozenset("""
    ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF ENDMODULE
    ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO IF INOUT LOCAL MOD
    MODULE NOSTEPIN NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY RETURN STEP SYSMODULE TEST THEN
    TO TRAP TRUE TRYNEXT UNDO VAR VIEWONLY WHILE WITH XOR TASK
""".split())


@dataclass(frozen=True, slots=True)
class Token:
    """One token: ``kind`` is ``id``, ``kw``, ``num``, ``str``, ``op`` or ``eof``.

    ``value`` is the number (``num``), the decoded text (``str``), the upper-case word (``kw``) or
    the operator (``op``); ``text`` is the source spelling.
    """

    kind: str
    text: str
    value: float | str | None  # None: eof
    line: int

    @property
    def word(self) -> str:
        """``value`` of a keyword, name, operator or string token."""
        if not isinstance(self.value, str):
            raise TypeError(f"the {self.kind} token {self.text!r} has no word")
        return self.value

    @property
    def number(self) -> float:
        """``value`` of a number token."""
        if not isinstance(self.value, float):
            raise TypeError(f"the {self.kind} token {self.text!r} is not a number")
        return self.value

    def is_kw(self, *words: str) -> bool:
        return self.kind == "kw" and self.value in words

    def is_op(self, *ops: str) -> bool:
        return self.kind == "op" and self.value in ops


_SCAN = re.compile(r"""
    (?P<ws>[ \t\r\f]+)
  | (?P<comment>![^\n]*)
  | (?P<nl>\n)
  | (?P<str>"(?:[^"\n]|"")*")
  | (?P<num>(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)
  | (?P<id>[A-Za-z][A-Za-z0-9_]*)
  | (?P<op>:=|<>|<=|>=|[-+*/=<>(){}\[\],;:.\\%|?])
""", re.VERBOSE)


def decode_string(body: str, module: str | None = None, line: int | None = None) -> str:
    """The characters of a string literal's body (without its quotes)."""
    out, i = [], 0
    while i < len(body):
        ch = body[i]
        if ch == '"':  # the scanner only lets "" through
            out.append('"')
            i += 2
        elif ch == "\\":
            if body.startswith("\\\\", i):
                out.append("\\")
                i += 2
            elif re.fullmatch(r"[0-9A-Fa-f]{2}", body[i + 1:i + 3]):
                out.append(chr(int(body[i + 1:i + 3], 16)))
                i += 3
            else:
                raise RapidLoadError(module, line, f"string literal: a backslash must be \\\\ or \\hh (two hex digits); "
                                                   f"got {body[i:i + 3]!r}")
        else:
            out.append(ch)
            i += 1
    return "".join(out)


_BOMS = ("\ufeff", "\xef\xbb\xbf")
_HEADER_LINE = re.compile(r"[ \t]*(?:VERSION[ \t]*:[ \t]*[0-9.]+|LANGUAGE[ \t]*:[ \t]*[A-Za-z]+)?[ \t]*\r?")


def strip_preamble(text: str, module: str | None = None) -> tuple[int, int]:
    """``(position, line)`` where the module text starts after a byte order mark and a ``%%%`` header.

    Raises
    ------
    RapidLoadError
        A header that is not closed by ``%%%`` or holds other lines than ``VERSION:n`` / ``LANGUAGE:word``.
    """
    pos = next((len(b) for b in _BOMS if text.startswith(b)), 0)
    if not text.startswith("%%%", pos):
        return pos, 1
    lines = text[pos:].split("\n")
    for i, body in enumerate(lines[1:], 1):
        if body.strip() == "%%%":
            return pos + sum(len(x) + 1 for x in lines[:i + 1]), i + 2
        if not _HEADER_LINE.fullmatch(body):
            raise RapidLoadError(module, i + 1, f"file header (%%%): expected VERSION:n, LANGUAGE:name or %%%; "
                                                f"got {body.strip()[:30]!r}")
    raise RapidLoadError(module, 1, "file header: the %%% line is never closed by another %%%")


def tokenize(text: str, module: str | None = None) -> list[Token]:
    """The tokens of ``text`` ending with an ``eof`` token (a byte order mark and a ``%%%`` header skipped).

    Raises
    ------
    RapidLoadError
        A character RAPID does not know, or a bad string literal; names the module and line.
    """
    tokens, size = [], len(text)
    pos, line = strip_preamble(text, module)
    while pos < size:
        m = _SCAN.match(text, pos)
        if m is None:
            raise RapidLoadError(module, line, f"cannot read {text[pos:pos + 12]!r}")
        kind, word = m.lastgroup, m.group()
        if kind == "nl":
            line += 1
        elif kind == "id":
            upper = word.upper()
            tokens.append(Token("kw", word, upper, line) if upper in KEYWORDS else Token("id", word, word, line))
        elif kind == "num":
            tokens.append(Token("num", word, float(word), line))
        elif kind == "str":
            tokens.append(Token("str", word, decode_string(word[1:-1], module, line), line))
        elif kind == "op":
            tokens.append(Token("op", word, word, line))
        pos = m.end()
    tokens.append(Token("eof", "end of file", None, line))
    return tokens
