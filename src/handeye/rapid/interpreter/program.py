"""Linking modules into one task's program: records, data, routines, and their checks.

:func:`load_program` takes the modules of a task (program modules and system modules alike), the
I/O signals of the controller's configuration, and returns a :class:`Program` ready for a
:class:`~handeye.rapid.interpreter.runtime.Task`: every name resolved, every routine compiled into
closures, every datum initialised (module data keep their values in the program; PERS data take the
value written in their module, as when a module is loaded). Anything the interpreter cannot run is
refused here, before anything runs.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import syntax as S
from .compiler import ArrayType, Compiler
from .errors import ERROR_NUMBERS, RapidFatalError, RapidLoadError
from .frames import Frame
from .parser import parse_module
from .scope import DataSymbol, ModuleScope, ParamInfo, RoutineSymbol, SignalSymbol
from .statements import compile_routine
from .values import PREDEFINED, SIGNAL_TYPES, TYPES, TypeInfo, coerce_array, default_value, type_info

__all__ = ["Program", "load_program", "ModuleSource"]


@dataclass(frozen=True)
class ModuleSource:
    """A module's text and the name messages use for it (``HeSocket.mod``)."""

    text: str
    source: str


class _Init:
    """Evaluates module-level initial values (constant expressions) outside any task."""

    errno = 0
    attention = False
    next_due = float("inf")

    def service(self) -> None:  # pragma: no cover - initialisers run no statements
        pass


class Program:
    """A linked program (see the module docstring).

    Attributes
    ----------
    modules : list of syntax.Module
    records : dict
        The program's own record types (lower-case name -> TypeInfo).
    globals : dict
        Global data and routines (lower-case name -> symbol).
    scopes : dict
        Module name (lower case) -> its :class:`ModuleScope`.
    data : list of DataSymbol
        Module data in declaration order.
    signals : dict
        I/O signals the program may use (lower-case name -> SignalSymbol).
    """

    def __init__(self, modules, signals=None):
        self.modules = list(modules)
        self.records: dict = {}
        self.globals: dict = {}
        self.scopes: dict = {}
        self.data: list[DataSymbol] = []
        self.routines: list[tuple] = []  # (module scope, RoutineSymbol)
        self.signals = {}
        for name, type_name in (signals or {}).items():
            t = TYPES.get(str(type_name).lower())
            if t is None or t.name not in SIGNAL_TYPES:
                raise RapidLoadError(None, None, f"I/O signal {name}: unknown signal type {type_name!r}")
            self.signals[name.lower()] = SignalSymbol(name, t)
        self._link()

    # ------------------------------------------------------------------ lookups
    def fallback(self, key: str):
        """What RAPID and the controller provide: predefined data, error numbers, I/O signals."""
        if key in PREDEFINED:
            t, value = PREDEFINED[key]
            return DataSymbol(key, t, "CONST", "RAPID", 0, box=[value], predefined=True)
        if key.upper() in ERROR_NUMBERS:
            return ("errnum", ERROR_NUMBERS[key.upper()])
        return self.signals.get(key)

    def routine(self, name: str, module: str | None = None) -> RoutineSymbol | None:
        """A routine by name (global, or LOCAL of ``module``)."""
        scope = self.scopes.get(module.lower()) if module else None
        symbol = scope.lookup(name) if scope else self.globals.get(name.lower())
        return symbol if isinstance(symbol, RoutineSymbol) else None

    def datum(self, name: str, module: str | None = None) -> DataSymbol | None:
        """Module data by name (global, or LOCAL of ``module``)."""
        scope = self.scopes.get(module.lower()) if module else None
        symbol = scope.lookup(name) if scope else self.globals.get(name.lower())
        return symbol if isinstance(symbol, DataSymbol) and not symbol.predefined else None

    @property
    def main(self) -> RoutineSymbol | None:
        symbol = self.globals.get("main")
        return symbol if isinstance(symbol, RoutineSymbol) and symbol.kind == "PROC" else None

    # ------------------------------------------------------------------ constant expressions
    def constant(self, compiler: Compiler, node, expected):
        fn = compiler.value_of(node, expected, "constant")
        return fn(Frame(_Init(), None, 0))

    def constant_dims(self, compiler: Compiler, decl) -> tuple:
        dims = []
        for node in decl.dims:
            value = self.constant(compiler, node, TYPES["num"])
            if value != int(value) or value < 1:
                compiler.fail(decl.line, f"{decl.name}: array size must be a whole number >= 1; got {value:g}")
            dims.append(int(value))
        return tuple(dims)

    # ------------------------------------------------------------------ linking
    def _link(self) -> None:
        names = [m.name.lower() for m in self.modules]
        for m in self.modules:
            if names.count(m.name.lower()) > 1:
                raise RapidLoadError(m.source, m.line, f"module {m.name} is loaded twice")
        self._collect_records()
        for m in self.modules:
            scope = ModuleScope(m.name, m.source, self.globals, self.fallback)
            self.scopes[m.name.lower()] = scope
            for decl in m.data:
                self._declare_data(m, scope, decl)
            for routine in m.routines:
                self._declare_routine(m, scope, routine)
        self._initialise_data()
        for scope, symbol in self.routines:
            compile_routine(self, scope, symbol)

    def _collect_records(self) -> None:
        for m in self.modules:
            for rec in m.records:
                key = rec.name.lower()
                if key in self.records or key in TYPES:
                    raise RapidLoadError(m.source, rec.line, f"record type {rec.name} is declared twice")
                self.records[key] = TypeInfo(rec.name, "record", fields=tuple((n, t) for t, n in rec.fields))
        for m in self.modules:
            for rec in m.records:
                for ftype, fname in rec.fields:
                    if type_info(ftype, self.records) is None:
                        raise RapidLoadError(m.source, rec.line, f"record {rec.name}.{fname}: unknown type {ftype!r}")

    def _register(self, m, scope: ModuleScope, name: str, symbol, local: bool, line: int) -> None:
        if local:
            scope.declare(name, symbol, line)
            return
        key = name.lower()
        other = self.globals.get(key)
        if other is not None:
            where = getattr(other, "module", "?")
            raise RapidLoadError(m.source, line, f"{name} is declared in module {where} and again in {m.name}")
        self.globals[key] = symbol

    def _declare_data(self, m, scope: ModuleScope, decl: S.DataDecl) -> None:
        t = type_info(decl.type, self.records)
        if t is None:
            raise RapidLoadError(m.source, decl.line, f"unknown data type {decl.type!r}")
        if decl.storage != "VAR" and t.kind == "handle":
            raise RapidLoadError(m.source, decl.line, f"a {t.name} can only be a VAR")
        symbol = DataSymbol(decl.name, t, decl.storage, m.name, decl.line, local=decl.local)
        symbol.decl, symbol.scope = decl, scope
        self._register(m, scope, decl.name, symbol, decl.local, decl.line)
        self.data.append(symbol)

    def _declare_routine(self, m, scope: ModuleScope, node: S.Routine) -> None:
        params = []
        for p in node.params:
            if p.type.lower() == "switch":
                if not p.optional:
                    raise RapidLoadError(m.source, p.line, f"parameter {p.name}: a switch must be optional (\\)")
                t = None
            else:
                t = type_info(p.type, self.records)
                if t is None:
                    raise RapidLoadError(m.source, p.line, f"parameter {p.name}: unknown data type {p.type!r}")
            params.append(ParamInfo(p.name, t, p.mode, p.optional, p.dims, p.group))
        rtype = None
        if node.kind == "FUNC":
            rtype = type_info(node.rtype, self.records) if node.rtype is not None else None
            if rtype is None:
                raise RapidLoadError(m.source, node.line, f"function {node.name}: unknown return type {node.rtype!r}")
        symbol = RoutineSymbol(node.name, node.kind, tuple(params), rtype, m.name, node.line, node, node.local)
        self._register(m, scope, node.name, symbol, node.local, node.line)
        self.routines.append((scope, symbol))

    def _initialise_data(self) -> None:
        done, active = set(), set()

        def initialise(symbol: DataSymbol) -> None:
            if id(symbol) in done:
                return
            decl, scope = symbol.decl, symbol.scope
            if decl is None or scope is None:  # _declare_data sets both for every entry of self.data
                raise RapidFatalError(f"{symbol.name} is not data of the program")
            if id(symbol) in active:
                raise RapidLoadError(scope.source, decl.line, f"the value of {decl.name} depends on itself")
            active.add(id(symbol))
            compiler = Compiler(self, scope)
            for name in _names(decl.init) + [n for d in decl.dims for n in _names(d)]:
                used = scope.lookup(name)
                if isinstance(used, DataSymbol) and not used.predefined:
                    if used.storage != "CONST":
                        raise RapidLoadError(scope.source, decl.line, f"the value of {decl.name} must be a constant "
                                                                      f"expression; {used.name} is a {used.storage}")
                    initialise(used)
            symbol.dims = self.constant_dims(compiler, decl)
            symbol.box[0] = self._initial_value(compiler, symbol, decl)
            active.discard(id(symbol))
            done.add(id(symbol))

        for symbol in self.data:
            initialise(symbol)

    def _initial_value(self, compiler: Compiler, symbol: DataSymbol, decl: S.DataDecl):
        t = symbol.type
        if symbol.dims:
            if decl.init is None:
                return default_value(t, self.records, symbol.dims)
            value = self.constant(compiler, decl.init, ArrayType(t, len(symbol.dims)))
            return coerce_array(value, t, symbol.dims, self.records, decl.name)
        if decl.init is None:
            return default_value(t, self.records)
        return self.constant(compiler, decl.init, t)


def _names(node) -> list[str]:
    """The names an expression reads."""
    if node is None:
        return []
    if isinstance(node, S.Name):
        return [node.name]
    out = []
    for value in (getattr(node, f, None) for f in getattr(node, "__dataclass_fields__", {})):
        if isinstance(value, tuple):
            for item in value:
                out += _names(item.value if isinstance(item, S.Arg) else item)
        elif hasattr(value, "__dataclass_fields__"):
            out += _names(value)
    return out


def load_program(sources, signals=None) -> Program:
    """Parse and link the modules of one task.

    Parameters
    ----------
    sources : iterable of ModuleSource, (text, source) pairs, or syntax.Module
    signals : dict, optional
        I/O signals of the controller: name -> ``signaldi`` ... ``signalao``.

    Raises
    ------
    RapidLoadError
        Naming the module and line of the first problem.
    """
    modules = []
    for item in sources:
        if isinstance(item, S.Module):
            modules.append(item)
        else:
            text, source = (item.text, item.source) if isinstance(item, ModuleSource) else item
            modules.append(parse_module(text, source))
    return Program(modules, signals)
