"""The syntax tree of a RAPID module, as :mod:`~handeye.rapid.interpreter.parser` builds it.

Nodes are frozen dataclasses (a parsed module may be shared by several tasks); every node that can
fail at run time carries its source ``line``. Names keep their spelling; they are compared
lower-cased.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = [
    "Num", "Str", "Bool", "Name", "Index", "Field", "Aggregate", "Unary", "Binary", "Call", "Arg",
    "Assign", "ProcCall", "If", "While", "For", "Test", "Return", "Raise", "Retry", "TryNext", "Exit",
    "Connect", "DataDecl", "Param", "Routine", "RecordDef", "Module",
]


# ---------------------------------------------------------------------------------------- expressions
@dataclass(frozen=True, slots=True)
class Num:
    value: float
    line: int
    text: str = ""


@dataclass(frozen=True, slots=True)
class Str:
    value: str
    line: int


@dataclass(frozen=True, slots=True)
class Bool:
    value: bool
    line: int


@dataclass(frozen=True, slots=True)
class Name:
    name: str
    line: int


@dataclass(frozen=True, slots=True)
class Index:
    base: object
    indices: tuple
    line: int


@dataclass(frozen=True, slots=True)
class Field:
    base: object
    name: str
    line: int


@dataclass(frozen=True, slots=True)
class Aggregate:
    items: tuple
    line: int


@dataclass(frozen=True, slots=True)
class Unary:
    op: str  # "-", "+", "NOT"
    operand: object
    line: int


@dataclass(frozen=True, slots=True)
class Binary:
    op: str  # "+", "-", "*", "/", "DIV", "MOD", "=", "<>", "<", ">", "<=", ">=", "AND", "OR", "XOR"
    left: object
    right: object
    line: int


@dataclass(frozen=True, slots=True)
class Arg:
    """One argument: ``value`` (``None`` for a switch ``\\Name``); ``name`` for ``\\Name:=`` or ``Name:=``;
    ``optional`` when written with a backslash."""

    value: object
    line: int
    name: str | None = None
    optional: bool = False


@dataclass(frozen=True, slots=True)
class Call:
    name: str
    args: tuple
    line: int


# ---------------------------------------------------------------------------------------- statements
@dataclass(frozen=True, slots=True)
class Assign:
    target: object
    value: object
    line: int


@dataclass(frozen=True, slots=True)
class ProcCall:
    name: str
    args: tuple
    line: int


@dataclass(frozen=True, slots=True)
class If:
    branches: tuple  # ((condition, statements), ...)
    otherwise: tuple | None
    line: int


@dataclass(frozen=True, slots=True)
class While:
    condition: object
    body: tuple
    line: int


@dataclass(frozen=True, slots=True)
class For:
    var: str
    start: object
    stop: object
    step: object | None
    body: tuple
    line: int


@dataclass(frozen=True, slots=True)
class Test:
    subject: object
    cases: tuple  # ((values, statements), ...)
    default: tuple | None
    line: int


@dataclass(frozen=True, slots=True)
class Return:
    value: object | None
    line: int


@dataclass(frozen=True, slots=True)
class Raise:
    value: object | None
    line: int


@dataclass(frozen=True, slots=True)
class Retry:
    line: int


@dataclass(frozen=True, slots=True)
class TryNext:
    line: int


@dataclass(frozen=True, slots=True)
class Exit:
    line: int


@dataclass(frozen=True, slots=True)
class Connect:
    target: object
    trap: str
    line: int


# ---------------------------------------------------------------------------------------- declarations
@dataclass(frozen=True, slots=True)
class DataDecl:
    """``[LOCAL|TASK] VAR|PERS|CONST type name [{dims}] [:= init];``"""

    storage: str  # VAR, PERS, CONST
    type: str
    name: str
    dims: tuple  # expressions, () for a scalar
    init: object | None
    line: int
    local: bool = False
    task: bool = False


@dataclass(frozen=True, slots=True)
class Param:
    """A routine parameter; ``alternatives`` groups optional ones written ``\\A | \\B``."""

    name: str
    type: str
    mode: str  # "" (value), "INOUT", "VAR", "PERS"
    optional: bool
    dims: int  # 0, or the number of "*" of an open array
    line: int
    group: int = 0


@dataclass(frozen=True, slots=True)
class Routine:
    kind: str  # PROC, FUNC, TRAP
    name: str
    params: tuple
    decls: tuple
    body: tuple
    line: int
    rtype: str | None = None
    local: bool = False
    error: tuple | None = None  # statements of the ERROR handler
    error_numbers: tuple | None = None  # ERROR (n, ...) restricts the handler to these
    undo: tuple | None = None
    backward: tuple | None = None
    end_line: int = 0


@dataclass(frozen=True, slots=True)
class RecordDef:
    name: str
    fields: tuple  # ((type, name), ...)
    line: int
    local: bool = False


@dataclass(frozen=True)
class Module:
    """A parsed module; ``source`` is the file (or module) name used in messages."""

    name: str
    attributes: tuple
    records: tuple
    data: tuple
    routines: tuple
    source: str
    line: int = 1
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def is_system(self) -> bool:
        return "SYSMODULE" in self.attributes
