"""Tokens of RAPID source: identifiers, keywords, numbers, strings, operators, with their line.

Keywords and identifiers are case-insensitive in RAPID: a keyword token carries its upper-case word
in ``value``; an identifier keeps its spelling in ``text`` (names are compared lower-cased).
String literals are decoded: ``""`` is one quote, ``\\\\`` one backslash, ``\\hh`` the character of
hexadecimal code ``hh``. ``!`` starts a comment to the end of the line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import RapidLoadError

__all__ = ["Token", "KEYWORDS", "tokenize", "decode_string"]

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
    value: object
    line: int

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


def tokenize(text: str, module: str | None = None) -> list[Token]:
    """The tokens of ``text`` ending with an ``eof`` token.

    Raises
    ------
    RapidLoadError
        A character RAPID does not know, or a bad string literal; names the module and line.
    """
    tokens, line, pos, size = [], 1, 0, len(text)
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
