"""Checks of our own on generated RAPID, beside the grammar check of ``rapidchecker``.

- every string literal holds at most 80 characters (RAPID's ``string`` limit);
- every identifier has at most 32 characters;
- module attributes (``MODULE HeKey(SYSMODULE, NOVIEW)``) are ones RAPID knows;
- every name is declared before it is used: data of a module before the routines that use it and
  locals at the top of their routine; routines and global data of the other modules in any order;
  what RAPID itself provides (instructions, functions, data types, ``tool0`` ...) is listed in
  :data:`RAPID_BUILTINS` (the interpreter's own tables), I/O signals from the I/O configuration are
  passed in as ``external``;
- a warning where ``NOT`` reaches over an ``AND`` (``NOT a AND b`` is ``NOT (a AND b)``: NOT has the
  lowest priority in RAPID, and the line reads easily as ``(NOT a) AND b``);
- motion: the only move instruction is ``MoveAbsJ``, always to a ``CONST jointtarget`` whose value
  is one of the approved postures (and inside the joint limits), with zone ``fine`` and ``tool0``
  (or a tool named in ``move_tools``: with world zones, the camera's nominal tool of ``HeCell``,
  whose TCP the zones watch; a jointtarget move goes to the same joints whatever the tool).

The tokens come from the interpreter's lexer (the package's one RAPID lexer); the checks walk them
and are not a full RAPID parser.
"""

from __future__ import annotations

from collections.abc import Iterable
from collections.abc import Sequence
import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..robot import load_robot
from .interpreter.errors import RapidLoadError
from .interpreter.lexer import KEYWORDS
from .interpreter.lexer import tokenize as rapid_tokens
from .interpreter.names import data_types, predefined_names

__all__ = ["Finding", "RAPID_KEYWORDS", "RAPID_BUILTINS", "MODULE_ATTRIBUTES", "MOVE_INSTRUCTIONS", "check_program",
           "for_rapidchecker", "string_length", "tokenize"]

MAX_STRING = 80
MAX_IDENTIFIER = 32

#: RAPID's reserved words: the lexer's one list.
RAPID_KEYWORDS = KEYWORDS
_DATA_TYPES = data_types()
#: Names RAPID provides (instructions, functions, data types, predefined data, error numbers), read from
#: the interpreter's tables (lower case): what the interpreter runs is what the checks accept.
RAPID_BUILTINS = predefined_names()
#: Module attributes RAPID knows (RobotWare manual; rapidchecker 0.1.x's grammar lacks NOVIEW).
MODULE_ATTRIBUTES = {"SYSMODULE", "NOVIEW", "NOSTEPIN", "VIEWONLY", "READONLY"}
#: Instructions that move the robot; only MoveAbsJ may appear, and only to approved targets.
MOVE_INSTRUCTIONS = {"MoveAbsJ", "MoveJ", "MoveL", "MoveC", "MoveExtJ", "MoveAbsJDO", "MoveJDO", "MoveLDO",
                     "MoveCDO", "MoveJSync", "MoveLSync", "MoveCSync", "MoveAbsJSync", "SearchL", "SearchC",
                     "TriggJ", "TriggL", "TriggC", "MToolRotCalib", "MoveJAO", "MoveLAO"}
_MOVE_LOWER = {name.lower() for name in MOVE_INSTRUCTIONS}
_KEYWORDS_UPPER = {k.upper() for k in RAPID_KEYWORDS}
_BUILTINS_LOWER = RAPID_BUILTINS
#: What ends the operand of a NOT (at its parenthesis depth) for the priority warning.
_NOT_ENDS = {"OR", "XOR", "THEN", "DO", "TO", "FROM", "STEP", ";", ",", ":=", ":"}


@dataclass(frozen=True)
class Finding:
    """One finding; ``severity`` is ``error`` (the module must change) or ``warning`` (it reads one way and
    runs another)."""

    module: str
    line: int
    message: str
    severity: str = "error"

    def __str__(self) -> str:
        return f"{self.module}:{self.line}: {'warning: ' if self.severity == 'warning' else ''}{self.message}"


@dataclass(frozen=True)
class Token:
    kind: str  # "id" (keywords included), "num", "str", "op"
    text: str
    line: int


def tokenize(text: str) -> list[Token]:
    """Tokens of RAPID text (comments, blanks, a byte order mark and a ``%%%`` header dropped), read by the
    interpreter's lexer (:func:`handeye.rapid.interpreter.lexer.tokenize`); keywords come as ``id``
    tokens. ValueError on what RAPID cannot read (a character, a bad string escape), naming the line."""
    try:
        tokens = rapid_tokens(text)
    except RapidLoadError as exc:
        raise ValueError(f"line {exc.line}: {exc.detail}") from None
    return [Token("id" if t.kind == "kw" else t.kind, t.text, t.line) for t in tokens if t.kind != "eof"]


def for_rapidchecker(text: str) -> str:
    """``text`` as ``rapidchecker`` 0.1.x can parse it: its grammar lacks the NOVIEW module attribute.

    Only the ``NOVIEW`` word of the ``MODULE`` line is removed (our own checks verify the module
    attributes against :data:`MODULE_ATTRIBUTES`); everything else is checked as written.
    """
    first, newline, rest = text.partition("\n")
    first = re.sub(r"\s*,\s*NOVIEW\b|\bNOVIEW\s*,\s*", "", first)
    first = re.sub(r"\(\s*NOVIEW\s*\)", "", first)
    return first + newline + rest


def string_length(literal: str) -> int:
    """Characters a RAPID string literal holds: ``""`` is one quote, ``\\\\`` one backslash, ``\\hh`` one byte."""
    body = literal[1:-1]
    count, i = 0, 0
    while i < len(body):
        if body.startswith('""', i):
            i += 2
        elif body[i] == "\\" and i + 1 < len(body) and body[i + 1] == "\\":
            i += 2
        elif body[i] == "\\" and re.fullmatch(r"[0-9A-Fa-f]{2}", body[i + 1:i + 3] or ""):
            i += 3
        else:
            i += 1
        count += 1
    return count


def _parse_literal_numbers(tokens: list[Token], start: int) -> tuple[list[float], int]:
    """Numbers of an aggregate literal starting at ``tokens[start] == '['``; returns (values, index after)."""
    depth, values, i, sign = 0, [], start, 1.0
    while i < len(tokens):
        t = tokens[i]
        if t.text == "[":
            depth += 1
        elif t.text == "]":
            depth -= 1
            if depth == 0:
                return values, i + 1
        elif t.text == "-":
            sign = -1.0
        elif t.kind == "num":
            values.append(sign * float(t.text))
            sign = 1.0
        i += 1
    return values, i


def _collect_globals(modules) -> tuple[dict, dict]:
    """Global data and routine names of every module (``(name, tokens)`` pairs): name -> module."""
    data, routines = {}, {}
    for name, tokens in modules:
        depth = 0
        for i, t in enumerate(tokens):
            upper = t.text.upper() if t.kind == "id" else ""
            if upper in ("PROC", "FUNC", "TRAP"):
                j = i + (2 if upper == "FUNC" else 1)
                if j < len(tokens):
                    routines[tokens[j].text.lower()] = name
                depth += 1
            elif upper in ("ENDPROC", "ENDFUNC", "ENDTRAP"):
                depth -= 1
            elif upper in ("VAR", "PERS", "CONST") and depth == 0:
                local = i > 0 and tokens[i - 1].text.upper() == "LOCAL"
                if i + 2 < len(tokens) and not local:
                    data[tokens[i + 2].text.lower()] = name
    return data, routines


def check_program(modules: Sequence[tuple[str, str]], approved: ArrayLike | None = None, robot: str = "IRB1400", external: Iterable[str] = (), move_tools: Iterable[str] = ("tool0",)) -> list[Finding]:
    """Findings of the checks on a set of modules (empty: all pass).

    Parameters
    ----------
    modules : sequence of (name, text)
        The modules loaded together into one task.
    approved : array-like, shape (n, 6), optional
        The approved postures; when given every ``CONST jointtarget`` must be one of them.
    robot : str
        Robot model for the joint-limit check of the jointtargets.
    external : iterable of str
        Names declared outside RAPID code (I/O signals of the I/O configuration).
    move_tools : iterable of str
        Tools ``MoveAbsJ`` may use (``tool0``; with world zones also the camera's nominal tool).
    """
    modules = [(str(n), str(t)) for n, t in modules]
    findings: list[Finding] = []
    model = load_robot(robot)
    approved_arr = None if approved is None else np.asarray(approved, dtype=float).reshape(-1, model.dof)
    tokenized = []  # each module read once, for the globals and for its own checks
    for name, text in modules:
        try:
            tokenized.append((name, tokenize(text)))
        except ValueError as exc:  # the names of the other modules cannot be known: nothing else is checked
            return [Finding(name, 0, str(exc))]
    global_data, routines = _collect_globals(tokenized)
    known_external = {e.lower() for e in external}
    for name, tokens in tokenized:
        findings += _check_module(name, tokens, global_data, routines, known_external, approved_arr, model,
                                  tuple(move_tools))
    return findings


def _module_attributes(module, tokens, i: int, out: list) -> int:
    """Check the attributes ``(SYSMODULE, NOVIEW, ...)`` that may follow a module's name at ``tokens[i]``;
    findings go to ``out``; returns the index after them."""
    n = len(tokens)
    if i < n and tokens[i].text == "(":
        i += 1
        while i < n and tokens[i].text != ")":
            word = tokens[i]
            if word.kind == "id" and word.text.upper() not in MODULE_ATTRIBUTES:
                out.append(Finding(module, word.line, f"unknown module attribute {word.text!r} "
                                                      f"(RAPID knows {', '.join(sorted(MODULE_ATTRIBUTES))})"))
            elif word.kind != "id" and word.text != ",":
                out.append(Finding(module, word.line, f"unexpected {word.text!r} in the module attributes"))
            i += 1
        i += 1
    return i


def _routine_parameters(module, tokens, i: int, local_scope: set, out: list) -> int:
    """Check a routine's parameters ``([\\][INOUT|VAR|PERS] type name [{*}], ...)`` at ``tokens[i]``: their
    types go to ``out`` when unknown, their names into ``local_scope``; returns the index after them."""
    n = len(tokens)
    if i < n and tokens[i].text == "(":
        i += 1
        while i < n and tokens[i].text != ")":
            if tokens[i].kind == "id" and tokens[i].text.upper() not in ("INOUT", "VAR", "PERS"):
                if tokens[i].text.lower() not in _DATA_TYPES:
                    out.append(Finding(module, tokens[i].line, f"unknown data type {tokens[i].text!r}"))
                if i + 1 < n and tokens[i + 1].kind == "id":
                    local_scope.add(tokens[i + 1].text.lower())
                    i += 1
            i += 1
        i += 1
    return i


def _check_module(module, tokens, global_data, routines, external, approved, model, move_tools=("tool0",)) -> list[Finding]:
    out: list[Finding] = []
    module_scope: set = set()
    local_scope: set | None = None
    jointtargets: dict = {}  # CONST jointtarget name -> values
    in_routine = False
    i = 0
    n = len(tokens)

    def known(word: str) -> bool:
        w = word.lower()
        if local_scope is not None and w in local_scope:
            return True
        if w in module_scope or w in routines or w in _BUILTINS_LOWER or w in external:
            return True
        return w in global_data and global_data[w] != module

    while i < n:
        t = tokens[i]
        if t.kind != "id":
            out += _literal_findings(module, t)
            i += 1
            continue
        if len(t.text) > MAX_IDENTIFIER:
            out.append(Finding(module, t.line, f"identifier {t.text!r} has {len(t.text)} characters (limit {MAX_IDENTIFIER})"))
        upper = t.text.upper()
        prev = tokens[i - 1].text if i > 0 else ""
        if upper == "MODULE":
            i = _module_attributes(module, tokens, i + 2, out)
            continue
        if upper in ("PROC", "FUNC", "TRAP"):
            in_routine, local_scope = True, set()
            i += 3 if upper == "FUNC" else 2
            if upper != "TRAP":
                i = _routine_parameters(module, tokens, i, local_scope, out)
            continue
        if upper in ("ENDPROC", "ENDFUNC", "ENDTRAP"):
            in_routine, local_scope = False, None
            i += 1
            continue
        if upper in ("VAR", "PERS", "CONST"):
            if i + 2 >= n:
                break
            dtype, var = tokens[i + 1], tokens[i + 2]
            if dtype.text.lower() not in _DATA_TYPES:
                out.append(Finding(module, dtype.line, f"unknown data type {dtype.text!r}"))
            scope = local_scope if local_scope is not None else module_scope  # set exactly while in_routine
            if var.text.lower() in scope:
                out.append(Finding(module, var.line, f"{var.text!r} declared twice"))
            if len(var.text) > MAX_IDENTIFIER:
                out.append(Finding(module, var.line, f"identifier {var.text!r} has {len(var.text)} characters (limit {MAX_IDENTIFIER})"))
            if upper == "CONST" and dtype.text.lower() == "jointtarget" and i + 4 < n and tokens[i + 3].text == ":=":
                values, _ = _parse_literal_numbers(tokens, i + 4)
                jointtargets[var.text.lower()] = (var.text, var.line, values)
            i += 3
            scope.add(var.text.lower())  # declared from here on (its initial value may not use itself)
            continue
        if upper == "FOR" and i + 1 < n and local_scope is not None:
            local_scope.add(tokens[i + 1].text.lower())
            i += 2
            continue
        if upper == "NOT":
            out += _not_over_and(module, tokens, i)
        if upper in _KEYWORDS_UPPER:
            i += 1
            continue
        if prev in (".", "\\"):  # record component or optional argument name
            i += 1
            continue
        if t.text.lower() in _MOVE_LOWER:
            out += _check_move(module, tokens, i, jointtargets, move_tools)
        if not known(t.text):
            out.append(Finding(module, t.line, f"{t.text!r} is used before it is declared (or never declared)"))
        i += 1
    for key, (name, line, values) in jointtargets.items():
        out += _check_jointtarget(module, name, line, values, approved, model)
    return out


def _literal_findings(module, t: Token) -> list[Finding]:
    """A string literal longer than RAPID holds."""
    length = string_length(t.text) if t.kind == "str" else 0
    if length > MAX_STRING:
        return [Finding(module, t.line, f"string literal of {length} characters (RAPID holds {MAX_STRING})")]
    return []


def _not_over_and(module, tokens, i: int) -> list[Finding]:
    """A warning when the operand of the ``NOT`` at ``tokens[i]`` holds an ``AND`` outside parentheses."""
    depth = 0
    for tok in tokens[i + 1:]:
        word = tok.text.upper() if tok.kind in ("id", "op") else ""
        if word in ("(", "[", "{"):
            depth += 1
        elif word in (")", "]", "}"):
            depth -= 1
            if depth < 0:
                return []
        elif depth == 0 and word in _NOT_ENDS:
            return []
        elif depth == 0 and word == "AND":
            return [Finding(module, tokens[i].line, "NOT ... AND: RAPID gives NOT the lowest priority, so this is "
                                                    "NOT (... AND ...); write the parentheses you mean",
                            severity="warning")]
    return []


def _check_move(module, tokens, i, jointtargets, move_tools=("tool0",)) -> list[Finding]:
    t = tokens[i]
    if t.text != "MoveAbsJ":
        return [Finding(module, t.line, f"{t.text} is not allowed: the robot moves only with MoveAbsJ to approved postures")]
    args, depth, current, j = [], 0, [], i + 1
    while j < len(tokens) and not (depth == 0 and tokens[j].text == ";"):
        tok = tokens[j]
        if tok.text in "([{":
            depth += 1
        elif tok.text in ")]}":
            depth -= 1
        if depth == 0 and tok.text == ",":
            args.append(current)
            current = []
        else:
            current.append(tok)
        j += 1
    args.append(current)
    out = []
    target = args[0] if args else []
    if len(target) != 1 or target[0].kind != "id" or target[0].text.lower() not in jointtargets:
        text = " ".join(x.text for x in target)
        out.append(Finding(module, t.line, f"MoveAbsJ to {text!r}: only CONST jointtargets of the approved postures "
                                           "declared in this module may be targets"))
    if len(args) < 4 or [x.text for x in args[2]] != ["fine"]:
        out.append(Finding(module, t.line, "MoveAbsJ must stop exactly at the posture: zone 'fine'"))
    if len(args) < 4 or not args[3] or args[3][0].text not in move_tools:
        out.append(Finding(module, t.line, f"MoveAbsJ must use {' or '.join(dict.fromkeys(move_tools))} (the postures "
                                           "are flange configurations)"))
    return out


def _check_jointtarget(module, name, line, values, approved, model) -> list[Finding]:
    out = []
    if len(values) != 12:
        return [Finding(module, line, f"jointtarget {name} must hold 6 robot and 6 external axes; got {len(values)} values")]
    joints = np.array(values[:6])
    problems = model.limit_violations(joints)
    if problems:
        out.append(Finding(module, line, f"jointtarget {name} outside the {model.name} limits: {'; '.join(problems)}"))
    if any(v != 9e9 for v in values[6:]):
        out.append(Finding(module, line, f"jointtarget {name}: external axes must be 9E9 (unused)"))
    if approved is not None and not np.any(np.all(np.abs(approved - joints) <= 5e-5, axis=1)):
        out.append(Finding(module, line, f"jointtarget {name} = {joints.tolist()} is not an approved posture"))
    return out
