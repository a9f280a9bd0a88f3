"""A recursive-descent parser of RAPID modules into the tree of :mod:`~handeye.rapid.interpreter.syntax`.

The grammar (RAPID kernel; ``[]`` optional, ``{}`` repeated)::

    module    = MODULE id ["(" attr {"," attr} ")"] {record | data | routine} ENDMODULE
    record    = RECORD id {type id ";"} ENDRECORD
    data      = [LOCAL | TASK] (VAR | PERS | CONST) type id ["{" expr {"," expr} "}"] [":=" expr] ";"
    routine   = [LOCAL] (PROC id "(" params ")" | FUNC type id "(" params ")" | TRAP id)
                {data} {stmt} [ERROR ["(" expr {"," expr} ")"] {stmt}] [UNDO {stmt}] ENDPROC | ENDFUNC | ENDTRAP
    params    = [param {("," | "|") param}]      param = ["\\"] [INOUT | VAR | PERS] type id ["{" "*" {"," "*"} "}"]
    stmt      = lvalue ":=" expr ";" | id [args] ";"
              | IF expr THEN {stmt} {ELSEIF expr THEN {stmt}} [ELSE {stmt}] ENDIF | IF expr simple-stmt
              | WHILE expr DO {stmt} ENDWHILE | FOR id FROM expr TO expr [STEP expr] DO {stmt} ENDFOR
              | TEST expr {CASE expr {"," expr} ":" {stmt}} [DEFAULT ":" {stmt}] ENDTEST
              | RETURN [expr] ";" | RAISE [expr] ";" | RETRY ";" | TRYNEXT ";" | EXIT ";"
              | CONNECT lvalue WITH id ";"
    args      = arg {"," arg | "\\" id [":=" expr]}      arg = ["\\"] [id ":="] expr | "\\" id
    expr      = and {(OR | XOR) and}        and = rel {AND rel}        rel = NOT and | sum [relop sum]
    sum       = term {("+" | "-") term}     term = unary {("*" | "/" | DIV | MOD) unary}
    unary     = ("-" | "+") unary | primary
    primary   = num | string | TRUE | FALSE | "(" expr ")" | "[" expr {"," expr} "]"
              | id "(" [args] ")" | lvalue
    lvalue    = id {"{" expr {"," expr} "}" | "." id}

Operator priority is RAPID's (RAPID reference, "Basic Characteristics", section 7.7): ``* / DIV MOD``
over ``+ -`` over the comparisons over ``AND`` over ``OR XOR NOT``. ``NOT`` has the lowest priority,
so its operand runs over every ``AND`` that follows: ``NOT a AND b`` is ``NOT (a AND b)``; an ``OR`` or
``XOR`` ends it (same priority, left to right: ``NOT a OR b`` is ``(NOT a) OR b``), and so does a
closing parenthesis. ``a AND NOT b`` is ``a AND (NOT b)``. The static checks
(:mod:`handeye.rapid.checks`) warn where a ``NOT`` reaches over an ``AND``, which reads easily the other way.

What RAPID has and this parser refuses, each with the line: ``GOTO`` and labels, late binding
(``%"name"%``), ``ALIAS``, conditional arguments (``\\A?b``), ``BACKWARD`` handlers.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NoReturn

from . import syntax as S
from .errors import RapidLoadError
from .lexer import Token, tokenize

__all__ = ["parse_module", "parse_expression"]

_BLOCK_END = frozenset({"ELSEIF", "ELSE", "ENDIF", "ENDWHILE", "ENDFOR", "CASE", "DEFAULT", "ENDTEST", "ERROR",
                        "UNDO", "BACKWARD", "ENDPROC", "ENDFUNC", "ENDTRAP"})
_RELATIONS = ("=", "<>", "<", ">", "<=", ">=")
_ATTRIBUTES = ("SYSMODULE", "NOVIEW", "NOSTEPIN", "VIEWONLY", "READONLY")


class _Parser:
    def __init__(self, tokens: list[Token], source: str):
        self.tokens, self.pos, self.source = tokens, 0, source

    # ------------------------------------------------------------------ token helpers
    @property
    def tok(self) -> Token:
        return self.tokens[self.pos]

    def peek(self, ahead: int = 1) -> Token:
        return self.tokens[min(self.pos + ahead, len(self.tokens) - 1)]

    def next(self) -> Token:
        tok = self.tokens[self.pos]
        self.pos += 1
        return tok

    def fail(self, message: str, tok: Token | None = None) -> NoReturn:
        tok = tok or self.tok
        raise RapidLoadError(self.source, tok.line, message)

    def expected(self, what: str) -> NoReturn:
        self.fail(f"expected {what}, found {self.tok.text!r}")

    def op(self, symbol: str) -> Token:
        if not self.tok.is_op(symbol):
            self.expected(repr(symbol))
        return self.next()

    def kw(self, word: str) -> Token:
        if not self.tok.is_kw(word):
            self.expected(word)
        return self.next()

    def ident(self, what: str = "a name") -> str:
        if self.tok.kind != "id":
            self.expected(what)
        return self.next().text

    # ------------------------------------------------------------------ module
    def module(self) -> S.Module:
        start = self.kw("MODULE")
        name = self.ident("the module name")
        attributes = []
        if self.tok.is_op("("):
            self.next()
            while True:
                if not self.tok.is_kw(*_ATTRIBUTES):
                    self.expected(f"a module attribute ({', '.join(_ATTRIBUTES)})")
                attributes.append(self.next().value)
                if self.tok.is_op(")"):
                    self.next()
                    break
                self.op(",")
        records, data, routines = [], [], []
        while not self.tok.is_kw("ENDMODULE"):
            if self.tok.kind == "eof":
                self.expected("ENDMODULE")
            local = self.tok.is_kw("LOCAL")
            head = self.peek() if local else self.tok
            if head.is_kw("RECORD"):
                records.append(self.record())
            elif head.is_kw("PROC", "FUNC", "TRAP"):
                routines.append(self.routine())
            elif head.is_kw("VAR", "PERS", "CONST", "TASK"):
                data.append(self.data())
            elif head.is_kw("ALIAS"):
                self.fail("ALIAS declarations are not supported by the interpreter", head)
            else:
                self.expected("a declaration (VAR, PERS, CONST, RECORD, PROC, FUNC, TRAP) or ENDMODULE")
        self.next()
        if self.tok.kind != "eof":
            self.expected("the end of the file after ENDMODULE")
        return S.Module(name, tuple(attributes), tuple(records), tuple(data), tuple(routines), self.source,
                        start.line)

    def record(self) -> S.RecordDef:
        local = bool(self.tok.is_kw("LOCAL") and self.next())
        line = self.kw("RECORD").line
        name = self.ident("the record name")
        fields = []
        while not self.tok.is_kw("ENDRECORD"):
            ftype = self.ident("a component type or ENDRECORD")
            fields.append((ftype, self.ident("the component name")))
            self.op(";")
        self.next()
        return S.RecordDef(name, tuple(fields), line, local)

    def data(self) -> S.DataDecl:
        local = bool(self.tok.is_kw("LOCAL") and self.next())
        task = bool(self.tok.is_kw("TASK") and self.next())
        if not self.tok.is_kw("VAR", "PERS", "CONST"):
            self.expected("VAR, PERS or CONST")
        storage_tok = self.next()
        dtype = self.ident("a data type")
        name = self.ident("the data name")
        dims = ()
        if self.tok.is_op("{"):
            self.next()
            dims = tuple(self.comma_list(self.expr, "}"))
        init = None
        if self.tok.is_op(":="):
            self.next()
            init = self.expr()
        self.op(";")
        if storage_tok.value == "CONST" and init is None:
            self.fail(f"CONST {name} needs a value (:= ...)", storage_tok)
        return S.DataDecl(storage_tok.word, dtype, name, dims, init, storage_tok.line, local, task)

    def routine(self) -> S.Routine:
        local = bool(self.tok.is_kw("LOCAL") and self.next())
        head = self.next()
        kind, rtype, params = head.word, None, ()
        if kind == "FUNC":
            rtype = self.ident("the function's return type")
        name = self.ident("the routine name")
        if kind != "TRAP":
            self.op("(")
            params = self.params()
            self.op(")")
        decls = []
        while self.tok.is_kw("VAR", "PERS", "CONST", "LOCAL", "TASK"):
            if self.tok.is_kw("LOCAL", "TASK"):
                self.fail("LOCAL and TASK are for module data, not routine data")
            decls.append(self.data())
        body = self.block()
        error = numbers = None
        if self.tok.is_kw("BACKWARD"):
            self.fail("BACKWARD handlers are not supported by the interpreter")
        if self.tok.is_kw("ERROR"):
            self.next()
            if self.tok.is_op("("):
                self.next()
                numbers = tuple(self.comma_list(self.expr, ")"))
            error = tuple(self.block())
        undo = None
        if self.tok.is_kw("UNDO"):
            self.next()
            undo = tuple(self.block())
        end = self.kw("END" + kind)
        return S.Routine(kind, name, tuple(params), tuple(decls), tuple(body), head.line, rtype, local, error,
                         numbers, undo, end_line=end.line)

    def params(self) -> list[S.Param]:
        params, group = [], 0
        if self.tok.is_op(")"):
            return params
        while True:
            params.append(self.param(group))
            if self.tok.is_op("|"):  # alternatives \A | \B: same group
                self.next()
                continue
            group += 1
            if self.tok.is_op(")"):
                return params
            self.op(",")

    def param(self, group: int) -> S.Param:
        line = self.tok.line
        optional = bool(self.tok.is_op("\\") and self.next())
        mode = self.next().word if self.tok.is_kw("INOUT", "VAR", "PERS") else ""
        ptype = self.ident("a parameter type")
        name = self.ident("the parameter name")
        dims = 0
        if self.tok.is_op("{"):
            self.next()
            while True:
                self.op("*")
                dims += 1
                if self.tok.is_op("}"):
                    self.next()
                    break
                self.op(",")
        return S.Param(name, ptype, mode, optional, dims, line, group)

    # ------------------------------------------------------------------ statements
    def block(self) -> list:
        out = []
        while not (self.tok.kind == "kw" and self.tok.value in _BLOCK_END):
            if self.tok.kind == "eof":
                self.expected("the end of the block")
            if self.tok.is_kw("VAR", "PERS", "CONST"):
                self.fail("data must be declared at the top of the routine, before its statements")
            out.append(self.statement())
        return out

    def statement(self):
        tok = self.tok
        if tok.kind == "kw":
            handler = _STATEMENTS.get(tok.word)
            if handler is None:
                self.fail(f"{tok.value} cannot start a statement")
            return handler(self)
        if tok.is_op("%"):
            self.fail("late binding (%...%) is not supported by the interpreter")
        if tok.kind != "id":
            self.expected("a statement")
        after = self.peek()
        if after.is_op(":"):
            self.fail(f"labels ({tok.text}:) and GOTO are not supported by the interpreter")
        if after.is_op(":=", "{", "."):
            target = self.lvalue()
            self.op(":=")
            value = self.expr()
            self.op(";")
            return S.Assign(target, value, tok.line)
        name = self.next().text
        args = () if self.tok.is_op(";") else tuple(self.args(";"))
        self.op(";")
        return S.ProcCall(name, args, tok.line)

    def if_stmt(self):
        line = self.next().line
        condition = self.expr()
        if not self.tok.is_kw("THEN"):  # compact IF: one simple statement
            if self.tok.kind == "kw" and self.tok.value in ("IF", "WHILE", "FOR", "TEST"):
                self.fail("a compact IF takes one simple statement")
            return S.If(((condition, (self.statement(),)),), None, line)
        self.next()
        branches = [(condition, tuple(self.block()))]
        otherwise = None
        while self.tok.is_kw("ELSEIF"):
            self.next()
            cond = self.expr()
            self.kw("THEN")
            branches.append((cond, tuple(self.block())))
        if self.tok.is_kw("ELSE"):
            self.next()
            otherwise = tuple(self.block())
        self.kw("ENDIF")
        return S.If(tuple(branches), otherwise, line)

    def while_stmt(self):
        line = self.next().line
        condition = self.expr()
        self.kw("DO")
        body = tuple(self.block())
        self.kw("ENDWHILE")
        return S.While(condition, body, line)

    def for_stmt(self):
        line = self.next().line
        var = self.ident("the loop variable")
        self.kw("FROM")
        start = self.expr()
        self.kw("TO")
        stop = self.expr()
        step = None
        if self.tok.is_kw("STEP"):
            self.next()
            step = self.expr()
        self.kw("DO")
        body = tuple(self.block())
        self.kw("ENDFOR")
        return S.For(var, start, stop, step, body, line)

    def test_stmt(self):
        line = self.next().line
        subject = self.expr()
        cases, default = [], None
        while self.tok.is_kw("CASE"):
            self.next()
            values = self.comma_list(self.expr, ":")
            cases.append((tuple(values), tuple(self.block())))
        if self.tok.is_kw("DEFAULT"):
            self.next()
            self.op(":")
            default = tuple(self.block())
        if not cases and default is None:
            self.expected("CASE")
        self.kw("ENDTEST")
        return S.Test(subject, tuple(cases), default, line)

    def return_stmt(self):
        line = self.next().line
        value = None if self.tok.is_op(";") else self.expr()
        self.op(";")
        return S.Return(value, line)

    def raise_stmt(self):
        line = self.next().line
        value = None if self.tok.is_op(";") else self.expr()
        self.op(";")
        return S.Raise(value, line)

    def simple(self, node):
        line = self.next().line
        self.op(";")
        return node(line)

    def connect_stmt(self):
        line = self.next().line
        target = self.lvalue()
        self.kw("WITH")
        trap = self.ident("a TRAP routine")
        self.op(";")
        return S.Connect(target, trap, line)

    # ------------------------------------------------------------------ arguments
    def args(self, closer: str) -> list[S.Arg]:
        out = [self.arg()]
        while not self.tok.is_op(closer):
            if self.tok.is_op(","):
                self.next()
                out.append(self.arg())
            elif self.tok.is_op("\\"):
                out.append(self.arg())
            else:
                self.expected(f"',' or {closer!r}")
        return out

    def arg(self) -> S.Arg:
        line = self.tok.line
        if self.tok.is_op("\\"):
            self.next()
            name = self.ident("an optional argument name")
            if self.tok.is_op("?"):
                self.fail("conditional arguments (\\Name?data) are not supported by the interpreter")
            if self.tok.is_op(":="):
                self.next()
                return S.Arg(self.expr(), line, name, True)
            return S.Arg(None, line, name, True)
        if self.tok.kind == "id" and self.peek().is_op(":="):
            name = self.next().text
            self.next()
            return S.Arg(self.expr(), line, name, False)
        return S.Arg(self.expr(), line)

    def comma_list(self, item, closer: str) -> list:
        out = [item()]
        while self.tok.is_op(","):
            self.next()
            out.append(item())
        self.op(closer)
        return out

    # ------------------------------------------------------------------ expressions
    def expr(self):
        left = self.conjunction()
        while self.tok.is_kw("OR", "XOR"):
            tok = self.next()
            left = S.Binary(tok.word, left, self.conjunction(), tok.line)
        return left

    def conjunction(self):
        left = self.relation()
        while self.tok.is_kw("AND"):
            tok = self.next()
            left = S.Binary("AND", left, self.relation(), tok.line)
        return left

    def relation(self):
        if self.tok.is_kw("NOT"):  # the lowest priority: its operand takes every AND that follows
            tok = self.next()
            return S.Unary("NOT", self.conjunction(), tok.line)
        left = self.sum()
        if self.tok.kind == "op" and self.tok.value in _RELATIONS:
            tok = self.next()
            left = S.Binary(tok.word, left, self.sum(), tok.line)
            if self.tok.kind == "op" and self.tok.value in _RELATIONS:
                self.fail("comparisons cannot be chained; use AND")
        return left

    def sum(self):
        left = self.term()
        while self.tok.is_op("+", "-"):
            tok = self.next()
            left = S.Binary(tok.word, left, self.term(), tok.line)
        return left

    def term(self):
        left = self.unary()
        while self.tok.is_op("*", "/") or self.tok.is_kw("DIV", "MOD"):
            tok = self.next()
            left = S.Binary(tok.word, left, self.unary(), tok.line)
        return left

    def unary(self):
        if self.tok.is_op("-", "+"):
            tok = self.next()
            return S.Unary(tok.word, self.unary(), tok.line)
        if self.tok.is_kw("NOT"):
            self.fail("NOT inside arithmetic: write the parentheses")
        return self.primary()

    def primary(self):
        tok = self.tok
        if tok.kind == "num":
            self.next()
            return S.Num(tok.number, tok.line, tok.text)
        if tok.kind == "str":
            self.next()
            return S.Str(tok.word, tok.line)
        if tok.is_kw("TRUE", "FALSE"):
            self.next()
            return S.Bool(tok.value == "TRUE", tok.line)
        if tok.is_op("("):
            self.next()
            inner = self.expr()
            self.op(")")
            return inner
        if tok.is_op("["):
            self.next()
            return S.Aggregate(tuple(self.comma_list(self.expr, "]")), tok.line)
        if tok.kind == "id":
            if self.peek().is_op("("):
                name = self.next().text
                self.next()
                args = () if self.tok.is_op(")") else tuple(self.args(")"))
                self.op(")")
                return S.Call(name, args, tok.line)
            return self.lvalue()
        self.expected("an expression")

    def lvalue(self):
        tok = self.tok
        node = S.Name(self.ident(), tok.line)
        while True:
            if self.tok.is_op("{"):
                line = self.next().line
                node = S.Index(node, tuple(self.comma_list(self.expr, "}")), line)
            elif self.tok.is_op("."):
                line = self.next().line
                node = S.Field(node, self.ident("a component name"), line)
            else:
                return node


_STATEMENTS = {
    "IF": _Parser.if_stmt,
    "WHILE": _Parser.while_stmt,
    "FOR": _Parser.for_stmt,
    "TEST": _Parser.test_stmt,
    "RETURN": _Parser.return_stmt,
    "RAISE": _Parser.raise_stmt,
    "RETRY": lambda p: p.simple(S.Retry),
    "TRYNEXT": lambda p: p.simple(S.TryNext),
    "EXIT": lambda p: p.simple(S.Exit),
    "CONNECT": _Parser.connect_stmt,
    "GOTO": lambda p: p.fail("GOTO is not supported by the interpreter"),
}


@lru_cache(maxsize=256)
def parse_module(text: str, source: str = "module") -> S.Module:
    """The syntax tree of one module's text (cached: the tree is immutable).

    Parameters
    ----------
    text : str
        The module source (``MODULE ... ENDMODULE``).
    source : str
        How messages name it (``HeSocket.mod``).

    Raises
    ------
    RapidLoadError
        Naming ``source`` and the line.
    """
    return _Parser(tokenize(text, source), source).module()


def parse_expression(text: str, source: str = "expression"):
    """One expression (``StrToVal`` reads literals with it)."""
    parser = _Parser(tokenize(text, source), source)
    node = parser.expr()
    if parser.tok.kind != "eof":
        parser.expected("the end of the expression")
    return node
