"""Statements and routines compiled into closures: control flow, error handlers, interrupts.

Every statement runs inside a guard that (1) lets the task serve due interrupts and stop requests
between statements, as a controller runs TRAP routines between instructions, and (2) gives a
recoverable error to the routine's ``ERROR`` handler: ``RETRY`` runs the failing statement again,
``TRYNEXT`` continues after it, ``RETURN`` leaves the routine, ``RAISE`` (or the end of the
handler) passes the error to the caller. A routine without a handler passes it on too; at the top
the task stops with the error and where it happened.

A routine's ``UNDO`` handler runs when the routine is left without finishing (RAPID reference,
"Basic Characteristics": "UNDO handlers"): an ``EXIT``, an error that leaves it (raised on by its
``ERROR`` handler, or with none), or the task stopped from outside (another program loaded: its
UNDO statements run, a wait or a move among them ends the handler).
Routines further up the call chain run theirs after it, innermost first. A ``RETURN`` ends the
handler; ``RETRY``, ``TRYNEXT`` and a ``RAISE`` without a number are refused there at load; an error
inside it stops the program with that error. A normal end or ``RETURN`` of the routine runs no UNDO.
"""

from __future__ import annotations

from collections.abc import Callable
from time import monotonic

from .builtins import lookup as lookup_builtin
from .compiler import ArrayType, Compiler
from .errors import RapidFatalError, RapidRuntimeError
from .frames import RETRY, ExitSignal, Frame, ReturnSignal, RetrySignal, TaskStopped, TryNextSignal
from .operators import equal
from .scope import RoutineScope, RoutineSymbol
from .values import TYPES, default_value, to_num

__all__ = ["CompiledRoutine", "compile_routine"]

_NUM = TYPES["num"]
_INTNUM = TYPES["intnum"]


class CompiledRoutine:
    """A routine ready to run: ``run(frame)`` initialises its local data, runs its body and returns
    the value of a FUNC."""

    def __init__(self, symbol: RoutineSymbol, source: str):
        self.name, self.kind, self.source = symbol.name, symbol.kind, source
        self.line, self.end_line = symbol.line, symbol.node.end_line
        self.size = 0
        self.inits: list = []
        self.body: list = []
        self.handler: Callable[[Frame], None] | None = None
        self.error_numbers: frozenset[int] | None = None
        self.undo: Callable[[Frame], None] | None = None

    def run(self, frame):
        for init in self.inits:
            init(frame)
        try:
            for statement in self.body:
                statement(frame)
        except ReturnSignal as done:
            return done.value
        except _UNDO_CAUSES:
            if self.undo is not None:
                self.undo(frame)
            raise
        if self.kind == "FUNC":
            err = RapidFatalError(f"function {self.name} ended without RETURN")
            err.locate(self.source, self.end_line)
            raise err
        return None

    def __repr__(self) -> str:
        return f"<{self.kind} {self.name}>"


#: What leaves a routine unfinished, so that its UNDO handler runs.
_UNDO_CAUSES = (ExitSignal, TaskStopped, RapidRuntimeError, RapidFatalError)


def _undo_runner(statements):
    """The UNDO handler: its statements with errors going straight up, stop requests held off."""
    def run_undo(f):
        task = f.task
        f.in_handler = True
        task.undoing += 1
        try:
            for statement in statements:
                statement(f)
        except ReturnSignal:
            pass
        finally:
            task.undoing -= 1
    return run_undo


def _guard(core, line: int, source: str):
    """The statement runner: interrupts and stop requests first, then the error handler's rules."""
    def run(f):
        task = f.task
        if task.attention or monotonic() >= task.next_due:
            task.service()
        while True:
            try:
                core(f)
            except RapidRuntimeError as err:
                if err.line is None:
                    err.locate(source, line)
                if err.handled_in is f or f.in_handler or f.routine.handler is None:
                    raise
                if f.handle(err) == RETRY:
                    continue
                return
            except RapidFatalError as err:
                err.locate(source, line)
                raise
            if f.retries:
                f.retries = 0
            return
    return run


class _StatementCompiler(Compiler):
    def __init__(self, program, scope: RoutineScope, routine: RoutineSymbol):
        super().__init__(program, scope)
        self.routine = routine
        self.in_handler = False

    def block(self, statements) -> list:
        return [self.statement(s) for s in statements]

    def statement(self, node):
        core = getattr(self, "_" + type(node).__name__.lower() + "_stmt")(node)
        return _guard(core, node.line, self.source)

    # ------------------------------------------------------------------ simple statements
    def _assign_stmt(self, node):
        return self.store(node.target, node.value, node.line)

    def _proccall_stmt(self, node):
        symbol = self.scope.lookup(node.name)
        if isinstance(symbol, RoutineSymbol):
            if symbol.kind != "PROC":
                self.fail(node.line, f"{node.name} is a {symbol.kind}; only a PROC is called as an instruction")
            return self.user_call(symbol, node.args, node.line)
        if symbol is not None:
            self.fail(node.line, f"{node.name} is data, not an instruction")
        spec = lookup_builtin(node.name)
        if spec is None:
            self.fail(node.line, f"unknown instruction {node.name}: not a PROC of the program nor a RAPID instruction "
                                 "the interpreter supports")
        if spec.kind != "proc":
            self.fail(node.line, f"{node.name} is a function: use its value")
        return self.builtin_call(spec, node.args, node.line)

    def _return_stmt(self, node):
        kind = self.routine.kind
        if kind == "FUNC":
            if node.value is None:
                self.fail(node.line, f"RETURN in function {self.routine.name} needs a value")
            value = self.value_of(node.value, self.routine.rtype, f"RETURN of {self.routine.name}")
            def give(f):
                raise ReturnSignal(value(f))
            return give
        if node.value is not None:
            self.fail(node.line, f"RETURN in a {kind} takes no value")
        def leave(f):
            raise ReturnSignal(None)
        return leave

    def _raise_stmt(self, node):
        if node.value is None:
            if not self.in_handler:
                self.fail(node.line, "RAISE without an error number is for error handlers")
            def again(f):
                raise f.error
            return again
        number = self.value_of(node.value, _NUM, "RAISE")
        def raise_new(f):
            raise RapidRuntimeError(int(number(f)))
        return raise_new

    def _retry_stmt(self, node):
        if not self.in_handler:
            self.fail(node.line, "RETRY is for error handlers")
        def retry(f):
            raise RetrySignal()
        return retry

    def _trynext_stmt(self, node):
        if not self.in_handler:
            self.fail(node.line, "TRYNEXT is for error handlers")
        def trynext(f):
            raise TryNextSignal()
        return trynext

    def _exit_stmt(self, node):
        where = f"{self.source}:{node.line}"

        def leave(f):
            raise ExitSignal(where)
        return leave

    def _connect_stmt(self, node):
        target, t = self.ref(node.target)
        self.check(_INTNUM, t, node.line, "CONNECT")
        trap = self.scope.lookup(node.trap)
        if not isinstance(trap, RoutineSymbol) or trap.kind != "TRAP":
            self.fail(node.line, f"CONNECT ... WITH {node.trap}: not a TRAP routine of the program")
        return lambda f: f.task.connect(target(f), trap)

    # ------------------------------------------------------------------ compound statements
    def _if_stmt(self, node):
        branches = [(self.condition(c, "IF"), self.block(body)) for c, body in node.branches]
        otherwise = self.block(node.otherwise) if node.otherwise is not None else None
        def choose(f):
            for condition, body in branches:
                if condition(f):
                    for statement in body:
                        statement(f)
                    return
            if otherwise is not None:
                for statement in otherwise:
                    statement(f)
        return choose

    def _while_stmt(self, node):
        condition = self.condition(node.condition, "WHILE")
        body = self.block(node.body)
        def loop(f):
            task = f.task
            while condition(f):
                for statement in body:
                    statement(f)
                if task.attention:
                    task.service()
        return loop

    def _for_stmt(self, node):
        start = self.value_of(node.start, _NUM, "FOR ... FROM")
        stop = self.value_of(node.stop, _NUM, "FOR ... TO")
        step = self.value_of(node.step, _NUM, "FOR ... STEP") if node.step is not None else None
        saved = self.scope.push_loop(node.var, node.line, _NUM)
        slot = saved[2].slot
        body = self.block(node.body)
        self.scope.pop_loop(saved)
        def loop(f):
            first, last = start(f), stop(f)
            increment = step(f) if step is not None else (1.0 if first <= last else -1.0)
            if increment == 0:
                raise RapidFatalError("FOR ... STEP 0")
            value, slots = first, f.slots
            while (value <= last) if increment > 0 else (value >= last):
                slots[slot] = value
                for statement in body:
                    statement(f)
                value = to_num(value + increment)
        return loop

    def _test_stmt(self, node):
        subject, stype = self.expr(node.subject)
        cases = []
        for values, body in node.cases:
            compiled = []
            for v in values:
                fn, vtype = self.expr(v, stype)
                self.check(stype, vtype, v.line, "CASE")
                compiled.append(fn)
            cases.append((compiled, self.block(body)))
        default = self.block(node.default) if node.default is not None else None
        def test(f):
            value = subject(f)
            for values, body in cases:
                if any(equal(value, v(f)) for v in values):
                    for statement in body:
                        statement(f)
                    return
            if default is not None:
                for statement in default:
                    statement(f)
        return test


def _local_init(compiler: Compiler, symbol, decl, records):
    slot, t = symbol.slot, symbol.type
    if symbol.dims:
        dims = symbol.dims
        if decl.init is not None:
            value = compiler.value_of(decl.init, ArrayType(t, len(dims)), f"{decl.name} :=")
            return lambda f: f.slots.__setitem__(slot, value(f))
        return lambda f: f.slots.__setitem__(slot, default_value(t, records, dims))
    if decl.init is not None:
        value = compiler.value_of(decl.init, t, f"{decl.name} :=")
        return lambda f: f.slots.__setitem__(slot, value(f))
    return lambda f: f.slots.__setitem__(slot, default_value(t, records))


def compile_routine(program, module_scope, symbol: RoutineSymbol) -> CompiledRoutine:
    """Compile one routine of the program (its body, local data, error handler)."""
    node = symbol.node
    scope = RoutineScope(module_scope, symbol)
    compiled = CompiledRoutine(symbol, module_scope.source)
    compiler = _StatementCompiler(program, scope, symbol)
    for p in symbol.params:
        scope.add(p.name, node.line, type=p.type if p.type is not None else TYPES["bool"], storage="PARAM",
                  mode=p.mode, optional=p.optional, dims=(0,) * p.dims)
    for decl in node.decls:
        if decl.storage == "PERS":
            compiler.fail(decl.line, "PERS data belong to a module, not a routine")
        t = compiler.type_named(decl.type, decl.line)
        dims = program.constant_dims(compiler, decl)
        local = scope.add(decl.name, decl.line, type=t, storage=decl.storage, dims=dims)
        compiled.inits.append(_local_init(compiler, local, decl, program.records))
    compiled.body = compiler.block(node.body)
    if node.error is not None:
        compiler.in_handler = True
        handler = compiler.block(node.error)
        compiler.in_handler = False
        def run_handler(f):
            for statement in handler:
                statement(f)
        compiled.handler = run_handler
        if node.error_numbers is not None:
            compiled.error_numbers = frozenset(int(program.constant(compiler, n, _NUM)) for n in node.error_numbers)
    if node.undo is not None:
        compiled.undo = _undo_runner(compiler.block(node.undo))
    compiled.size = scope.size
    symbol.compiled = compiled
    return compiled
