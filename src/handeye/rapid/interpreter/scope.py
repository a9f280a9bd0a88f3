"""Names of a linked program: data, routines, I/O signals, and where each is visible.

RAPID's scoping: a routine sees its parameters and local data, then the data and routines of its
module (``LOCAL`` ones included), then the global data and routines of every module of the task,
then what RAPID predefines (``tool0``, ``STR_DIGIT``, the instructions and functions), then the
I/O signals of the controller's configuration. Names are case-insensitive.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .errors import RapidLoadError
from .syntax import DataDecl, Routine
from .values import TypeInfo

if TYPE_CHECKING:
    from .statements import CompiledRoutine

__all__ = ["DataSymbol", "LocalSymbol", "RoutineSymbol", "SignalSymbol", "ParamInfo", "ModuleScope", "RoutineScope"]


@dataclass(eq=False)
class DataSymbol:
    """Module data (or predefined data): its value lives in ``box[0]``."""

    name: str
    type: TypeInfo
    storage: str  # VAR, PERS, CONST
    module: str
    line: int
    dims: tuple = ()
    local: bool = False
    box: list = field(default_factory=lambda: [None])
    predefined: bool = False
    decl: DataDecl | None = field(default=None, repr=False)  # a program's data: its declaration and scope
    scope: ModuleScope | None = field(default=None, repr=False)


@dataclass(eq=False)
class LocalSymbol:
    """A parameter, local datum or FOR variable of a routine: ``slot`` in its frame."""

    name: str
    type: TypeInfo | None
    slot: int
    storage: str = "VAR"  # VAR, CONST, PARAM, FOR
    mode: str = ""  # parameters: "", INOUT, VAR, PERS
    optional: bool = False
    dims: tuple = ()


@dataclass(frozen=True)
class ParamInfo:
    name: str
    type: TypeInfo | None  # None: switch
    mode: str
    optional: bool
    dims: int
    group: int

    @property
    def by_ref(self) -> bool:
        return self.mode in ("INOUT", "VAR", "PERS")

    @property
    def switch(self) -> bool:
        return self.type is None


@dataclass(eq=False)
class RoutineSymbol:
    """A routine of the program; ``compiled`` is set once its body is compiled."""

    name: str
    kind: str  # PROC, FUNC, TRAP
    params: tuple
    rtype: TypeInfo | None
    module: str
    line: int
    node: Routine = field(repr=False)
    local: bool = False
    compiled: CompiledRoutine | None = field(default=None, repr=False)


@dataclass(frozen=True)
class SignalSymbol:
    """An I/O signal of the controller's configuration (``signaldi`` ... ``signalao``)."""

    name: str
    type: TypeInfo


class ModuleScope:
    """What a module's code sees: its own declarations, then the task's globals, then ``fallback``."""

    def __init__(self, module: str, source: str, globals_: dict, fallback):
        self.module, self.source, self.globals = module, source, globals_
        self.names: dict = {}
        self.fallback = fallback

    def declare(self, name: str, symbol, line: int) -> None:
        key = name.lower()
        if key in self.names:
            raise RapidLoadError(self.source, line, f"{name} is declared twice in module {self.module}")
        self.names[key] = symbol

    def lookup(self, name: str):
        key = name.lower()
        symbol = self.names.get(key)
        if symbol is None:
            symbol = self.globals.get(key)
        if symbol is None:
            symbol = self.fallback(key)
        return symbol


class RoutineScope:
    """A routine's names (parameters, local data, FOR variables) in front of its module's scope."""

    def __init__(self, module_scope: ModuleScope, routine: RoutineSymbol):
        self.module_scope, self.routine = module_scope, routine
        self.source = module_scope.source
        self.names: dict = {}
        self.size = 0

    def add(self, name: str, line: int, **info) -> LocalSymbol:
        key = name.lower()
        if key in self.names:
            raise RapidLoadError(self.source, line, f"{name} is declared twice in {self.routine.name}")
        symbol = LocalSymbol(name, slot=self.size, **info)
        self.size += 1
        self.names[key] = symbol
        return symbol

    def push_loop(self, name: str, line: int, type_: TypeInfo) -> tuple:
        """A FOR variable visible inside its loop only; returns what :meth:`pop_loop` restores."""
        key = name.lower()
        hidden = self.names.pop(key, None)
        symbol = LocalSymbol(name, type_, self.size, storage="FOR")
        self.size += 1
        self.names[key] = symbol
        return key, hidden, symbol

    def pop_loop(self, saved: tuple) -> None:
        key, hidden, _ = saved
        if hidden is None:
            self.names.pop(key, None)
        else:
            self.names[key] = hidden

    def lookup(self, name: str):
        symbol = self.names.get(name.lower())
        return symbol if symbol is not None else self.module_scope.lookup(name)
