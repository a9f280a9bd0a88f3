"""Expressions and references compiled into Python closures, with RAPID's static checks.

:class:`Compiler` turns a syntax node into ``fn(frame) -> value`` and knows its static type, so
the program is checked as a controller checks a module it loads: every name declared, every
routine known (its own or a built-in the interpreter implements), argument counts and optional
argument names, types of operands, assignments and arguments (aggregates included), CONSTs and
loop variables never written, by-reference arguments that are data. A failure is a
:class:`~handeye.rapid.interpreter.errors.RapidLoadError` naming the module and line.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NoReturn

from . import syntax as S
from .builtins import lookup as lookup_builtin
from .errors import RapidFatalError, RapidLoadError
from .frames import ABSENT, Frame, Ref
from .operators import OPERATORS, logical_not, negate
from .scope import DataSymbol, LocalSymbol, RoutineSymbol, SignalSymbol
from .values import (NUM_TYPES, TYPES, Aggregate, Array, Record, TypeInfo, coerce, compatible, copy_value,
                     type_info)

__all__ = ["Compiler", "ArrayType", "same_type"]


@dataclass(frozen=True)
class ArrayType:
    """The static type of a whole array."""

    element: TypeInfo
    ndims: int
    kind: str = "array"

    @property
    def name(self) -> str:
        return f"{self.element.name}{{{','.join('*' * self.ndims)}}}"

    @property
    def key(self) -> str:
        return "array"


def same_type(target, source) -> bool:
    """Whether static ``source`` may go where ``target`` is expected (``None``: unknown, accepted)."""
    if isinstance(target, ArrayType) or isinstance(source, ArrayType):
        if target is None or source is None:
            return True
        return (isinstance(target, ArrayType) and isinstance(source, ArrayType) and target.ndims == source.ndims
                and compatible(target.element, source.element))
    return compatible(target, source)


_NUM = TYPES["num"]
_DNUM = TYPES["dnum"]
_BOOL = TYPES["bool"]
_STRING = TYPES["string"]
_ERRNUM = TYPES["errnum"]


def _arith_type(op: str, a, b):
    """Static result of an arithmetic operator, or "bad"."""
    ka, kb = getattr(a, "key", None), getattr(b, "key", None)
    if ka in NUM_TYPES and kb in NUM_TYPES:
        return _DNUM if "dnum" in (ka, kb) else _NUM
    if op == "+" and ka == kb == "string":
        return _STRING
    if op in "+-" and ka == kb == "pos":
        return TYPES["pos"]
    if op == "*" and {ka, kb} == {"num", "pos"}:
        return TYPES["pos"]
    if op == "*" and ka == kb == "orient":
        return TYPES["orient"]
    if op == "/" and ka == "pos" and kb in NUM_TYPES:
        return TYPES["pos"]
    if a is None or b is None:
        return None
    return "bad"


class Compiler:
    """Compiles the expressions and references of one routine (or module initialisers).

    Parameters
    ----------
    program : Program
        The program being linked (records, the task-independent symbol tables).
    scope : RoutineScope or ModuleScope
    """

    def __init__(self, program, scope):
        self.program, self.scope, self.source = program, scope, scope.source

    # ------------------------------------------------------------------ helpers
    def fail(self, line: int, message: str) -> NoReturn:
        raise RapidLoadError(self.source, line, message)

    def type_named(self, name: str, line: int) -> TypeInfo:
        t = type_info(name, self.program.records)
        if t is None:
            self.fail(line, f"unknown data type {name!r}")
        return t

    def check(self, expected, actual, line: int, what: str) -> None:
        if not same_type(expected, actual):
            self.fail(line, f"{what}: expected {expected.name}, got {actual.name}")

    def resolve(self, name: str, line: int):
        symbol = self.scope.lookup(name)
        if symbol is None:
            self.fail(line, f"{name!r} is not declared (no data, routine, RAPID built-in or I/O signal of that name)")
        return symbol

    # ------------------------------------------------------------------ expressions
    def expr(self, node, expected=None):
        """``(fn, static type)`` of an expression; ``expected`` types aggregates."""
        method = getattr(self, "_" + type(node).__name__.lower())
        return method(node, expected)

    def value_of(self, node, expected, what: str) -> Callable[[Frame], Any]:
        """A closure giving ``node``'s value converted to ``expected`` (copied, float32 for num).

        The value is a RAPID value (Any to Python: its type is the RAPID type this compiler checked)."""
        fn, actual = self.expr(node, expected)
        self.check(expected, actual, node.line, what)
        if isinstance(expected, ArrayType):
            element = expected.element
            def whole_array(f):
                value = fn(f)
                return copy_value(value) if isinstance(value, Array) else _array_from(value, element)
            return whole_array
        if expected is None:
            return fn
        records = self.program.records
        return lambda f: coerce(fn(f), expected, records, what)

    def condition(self, node, what: str):
        fn, t = self.expr(node, _BOOL)
        self.check(_BOOL, t, node.line, what)
        return fn

    def _num(self, node, expected):
        value = node.value
        return (lambda f: value), _NUM

    def _str(self, node, expected):
        if len(node.value) > 80:
            self.fail(node.line, f"string literal of {len(node.value)} characters (RAPID holds 80)")
        value = node.value
        return (lambda f: value), _STRING

    def _bool(self, node, expected):
        value = node.value
        return (lambda f: value), _BOOL

    def _name(self, node, expected):
        if node.name.lower() == "errno":
            return (lambda f: f.task.errno), _ERRNUM
        symbol = self.resolve(node.name, node.line)
        if isinstance(symbol, LocalSymbol):
            return self._local_value(symbol, node), _static(symbol.type, symbol.dims)
        if isinstance(symbol, DataSymbol):
            box = symbol.box
            return (lambda f: box[0]), _static(symbol.type, symbol.dims)
        if isinstance(symbol, SignalSymbol):
            name = symbol.name
            return (lambda f: f.task.io_read(name)), _NUM
        if isinstance(symbol, tuple) and symbol[0] == "errnum":
            number = symbol[1]
            return (lambda f: number), _ERRNUM
        self.fail(node.line, f"{node.name} is a routine, not data")

    def _local_value(self, symbol: LocalSymbol, node):
        slot, name = symbol.slot, symbol.name
        if symbol.mode in ("INOUT", "VAR", "PERS"):
            if symbol.optional:
                def by_ref_optional(f):
                    ref = f.slots[slot]
                    if ref is ABSENT:
                        raise RapidFatalError(f"optional parameter {name} was not passed (test it with Present)")
                    return ref.get()
                return by_ref_optional
            return lambda f: f.slots[slot].get()
        if symbol.optional:
            def optional(f):
                value = f.slots[slot]
                if value is ABSENT:
                    raise RapidFatalError(f"optional parameter {name} was not passed (test it with Present)")
                return value
            return optional
        return lambda f: f.slots[slot]

    def _index(self, node, expected):
        base, btype = self.expr(node.base)
        if btype is not None and not isinstance(btype, ArrayType):
            self.fail(node.line, f"{_text(node.base)} is not an array")
        indices = [self.value_of(i, _NUM, "array index") for i in node.indices]
        element = btype.element if btype else None
        rest = (btype.ndims - len(indices)) if btype else 0
        if btype is not None and rest < 0:
            self.fail(node.line, f"{_text(node.base)} has {btype.ndims} dimension(s)")
        def read(f):
            value = base(f)
            for index in indices:
                value = value[_position(value, index(f))]
            return value
        return read, (ArrayType(element, rest) if rest and element is not None else element)  # rest: btype known

    def _field(self, node, expected):
        base, btype = self.expr(node.base)
        ftype = self._field_type(btype, node)
        key = node.name.lower()
        def read(f):
            record = base(f)
            if not isinstance(record, Record):
                raise RapidFatalError(f".{node.name}: not a record")
            return record.fields[key]
        return read, ftype

    def _field_type(self, btype, node):
        if btype is None:
            return None
        if isinstance(btype, ArrayType) or btype.kind != "record":
            self.fail(node.line, f"{btype.name} has no component {node.name!r}")
        name = btype.field_type(node.name)
        if name is None:
            self.fail(node.line, f"{btype.name} has no component {node.name!r} "
                                 f"(it has {', '.join(n for n, _ in btype.fields)})")
        return self.type_named(name, node.line)

    def _aggregate(self, node, expected):
        if isinstance(expected, TypeInfo) and expected.kind == "record":
            if len(node.items) != len(expected.fields):
                self.fail(node.line, f"a {expected.name} has {len(expected.fields)} components; the aggregate has "
                                     f"{len(node.items)}")
            parts = [(fname.lower(), self.value_of(item, self.type_named(ftype, node.line), f"{expected.name}.{fname}"))
                     for (fname, ftype), item in zip(expected.fields, node.items)]
            return (lambda f: Record(expected, {k: fn(f) for k, fn in parts})), expected
        if isinstance(expected, ArrayType):
            inner = expected.element if expected.ndims == 1 else ArrayType(expected.element, expected.ndims - 1)
            items = [self.value_of(item, inner, "array element") for item in node.items]
            return (lambda f: Aggregate(fn(f) for fn in items)), None
        items = [self.expr(item)[0] for item in node.items]
        return (lambda f: Aggregate(fn(f) for fn in items)), None

    def _unary(self, node, expected):
        operand, t = self.expr(node.operand, _BOOL if node.op == "NOT" else expected)
        if node.op == "NOT":
            self.check(_BOOL, t, node.line, "NOT")
            return (lambda f: logical_not(operand(f))), _BOOL
        if t is not None and t.key not in NUM_TYPES and t.key != "pos":
            self.fail(node.line, f"unary {node.op} cannot take a {t.name}")
        if node.op == "+":
            return operand, t
        return (lambda f: negate(operand(f))), t

    def _binary(self, node, expected):
        op = node.op
        left, lt = self.expr(node.left)
        right, rt = self.expr(node.right)
        function = OPERATORS[op]
        if op in ("AND", "OR", "XOR"):
            self.check(_BOOL, lt, node.left.line, op)
            self.check(_BOOL, rt, node.right.line, op)
            return (lambda f: function(left(f), right(f))), _BOOL
        if op in ("=", "<>"):
            if lt is not None and rt is not None and not (same_type(lt, rt) or same_type(rt, lt)):
                self.fail(node.line, f"cannot compare a {lt.name} with a {rt.name}")
            return (lambda f: function(left(f), right(f))), _BOOL
        if op in ("<", ">", "<=", ">="):
            for side, t in ((node.left, lt), (node.right, rt)):
                if t is not None and t.key not in NUM_TYPES:
                    self.fail(side.line, f"{op} compares numbers; got a {t.name}")
            return (lambda f: function(left(f), right(f))), _BOOL
        if op in ("DIV", "MOD"):
            for side, t in ((node.left, lt), (node.right, rt)):
                if t is not None and t.key not in NUM_TYPES:
                    self.fail(side.line, f"{op} takes numbers; got a {t.name}")
            result = _arith_type("-", lt, rt) if lt is not None and rt is not None else _NUM
        else:
            result = _arith_type(op, lt, rt)
        if result == "bad" and lt is not None and rt is not None:  # "bad": two known types that do not combine
            self.fail(node.line, f"operator {op} cannot combine a {lt.name} and a {rt.name}")
        return (lambda f: function(left(f), right(f))), result

    def _call(self, node, expected):
        lname = node.name.lower()
        if lname == "present":
            return self._present(node)
        symbol = self.scope.lookup(node.name)
        if isinstance(symbol, RoutineSymbol):
            if symbol.kind != "FUNC":
                self.fail(node.line, f"{node.name} is a {symbol.kind}, not a function")
            return self.user_call(symbol, node.args, node.line), symbol.rtype
        spec = lookup_builtin(node.name)
        if spec is None or spec.kind != "func":
            what = "an instruction, not a function" if spec else "not a function of the program nor a RAPID " \
                   "function the interpreter supports"
            self.fail(node.line, f"{node.name}() is {what}")
        call = self.builtin_call(spec, node.args, node.line)
        return call, self.type_named(spec.returns, node.line) if spec.returns is not None and spec.returns != "any" else None

    def _present(self, node):
        if len(node.args) != 1 or not isinstance(node.args[0].value, S.Name):
            self.fail(node.line, "Present takes one optional parameter")
        symbol = self.scope.lookup(node.args[0].value.name)
        if not isinstance(symbol, LocalSymbol) or not symbol.optional:
            self.fail(node.line, f"Present({node.args[0].value.name}): not an optional parameter of this routine")
        slot = symbol.slot
        return (lambda f: f.slots[slot] is not ABSENT), _BOOL

    # ------------------------------------------------------------------ references
    def ref(self, node, writing: bool = True):
        """``(fn(frame) -> Ref, static type)`` of data written (or passed by reference)."""
        if isinstance(node, S.Name):
            return self._name_ref(node, writing)
        if isinstance(node, S.Index):
            base, btype = self.ref(node.base, writing)
            if btype is not None and not isinstance(btype, ArrayType):
                self.fail(node.line, f"{_text(node.base)} is not an array")
            indices = [self.value_of(i, _NUM, "array index") for i in node.indices]
            rest = btype.ndims - len(indices) if btype else 0
            if btype is not None and rest < 0:
                self.fail(node.line, f"{_text(node.base)} has {btype.ndims} dimension(s)")
            element = btype.element if btype else None
            def index_ref(f):
                holder = base(f).get()
                for index in indices[:-1]:
                    holder = holder[_position(holder, index(f))]
                return Ref(holder, _position(holder, indices[-1](f)), element)
            return index_ref, (ArrayType(element, rest) if rest and element is not None else element)
        if isinstance(node, S.Field):
            base, btype = self.ref(node.base, writing)
            ftype = self._field_type(btype, node)
            key = node.name.lower()
            return (lambda f: Ref(base(f).get().fields, key, ftype)), ftype
        self.fail(node.line, "expected data (a variable, persistent, component or element)")

    def _name_ref(self, node, writing: bool):
        symbol = self.resolve(node.name, node.line)
        if isinstance(symbol, LocalSymbol):
            if writing and symbol.storage in ("CONST", "FOR"):
                self.fail(node.line, f"{symbol.name} is a {'loop variable' if symbol.storage == 'FOR' else 'CONST'} "
                                     "and cannot be written")
            static = _static(symbol.type, symbol.dims)
            slot = symbol.slot
            if symbol.mode in ("INOUT", "VAR", "PERS"):
                return (lambda f: f.slots[slot]), static
            if symbol.storage == "PARAM" and writing and self.scope.routine.kind == "FUNC":
                # RAPID reference, Basic Characteristics 3.2: a FUNC sees an IN parameter as a constant; a
                # PROC's is a routine variable (a copy: the caller's argument does not change)
                self.fail(node.line, f"{symbol.name} is an input parameter of function {self.scope.routine.name}, "
                                     "a constant there: copy it into a local VAR to change it")
            t, dims = symbol.type, symbol.dims
            return (lambda f: Ref(f.slots, slot, t, dims, symbol.name)), static
        if isinstance(symbol, DataSymbol):
            if writing and symbol.storage == "CONST":
                self.fail(node.line, f"{symbol.name} is a CONST and cannot be written")
            ref = Ref(symbol.box, 0, symbol.type, symbol.dims, symbol.name)
            return (lambda f: ref), _static(symbol.type, symbol.dims)
        self.fail(node.line, f"{node.name} is not data that can be written")

    def store(self, node, value_node, line: int):
        """A closure that assigns ``value_node`` to the data ``node`` (checked like RAPID's ``:=``)."""
        target, ttype = self.ref(node)
        if ttype is not None and not isinstance(ttype, ArrayType) and ttype.kind == "handle":
            self.fail(line, f"a {ttype.name} cannot be assigned")
        value = self.value_of(value_node, ttype, f"{_text(node)} :=")
        def assign(f):
            target(f).set(value(f))
        return assign

    # ------------------------------------------------------------------ calls
    def user_call(self, routine: RoutineSymbol, args, line: int):
        """A closure calling a routine of the program (its value for a FUNC)."""
        producers = self.bind_args(routine.name, routine.params, args, line)
        target = routine  # its body may be compiled later (recursion, forward calls)
        def call(f):
            compiled = target.compiled
            if compiled is None:  # Program compiles every routine before a task runs
                raise RapidFatalError(f"{target.name} is called before it is compiled")
            frame = Frame(f.task, compiled, compiled.size)
            slots = frame.slots
            for i, produce in producers:
                slots[i] = produce(f)
            return compiled.run(frame)
        return call

    def bind_args(self, name: str, params, args, line: int) -> list:
        """``[(slot, producer)]`` for a user routine's parameters (slots are the parameter order)."""
        matched = self._match(name, [(p.name, p.optional, p.switch) for p in params], args, line)
        producers = []
        for i, param in enumerate(params):
            arg = matched.get(i)
            if arg is None:
                producers.append((i, (lambda f: False) if param.switch else (lambda f: ABSENT)))
                continue
            if param.switch:
                if arg.value is not None:
                    self.fail(arg.line, f"\\{param.name} is a switch: it takes no value")
                producers.append((i, lambda f: True))
            elif param.by_ref:
                producers.append((i, self._ref_arg(arg, param.type, param.dims, f"{name} {param.name}")))
            else:
                expected = ArrayType(param.type, param.dims) if param.dims else param.type
                producers.append((i, self.value_of(arg.value, expected, f"argument {param.name} of {name}")))
        return producers

    def _ref_arg(self, arg, ptype, dims: int, what: str):
        if arg.value is None:
            self.fail(arg.line, f"{what}: needs data")
        node = arg.value
        if not isinstance(node, (S.Name, S.Index, S.Field)):
            self.fail(arg.line, f"{what}: passed by reference, the argument must be data, not an expression")
        fn, t = self.ref(node, writing=True)
        expected = ArrayType(ptype, dims) if dims else ptype
        self.check(expected, t, arg.line, what)
        return fn

    def _match(self, name: str, params, args, line: int) -> dict:
        """Argument of each parameter index: positional ones in order, ``\\Name`` and ``Name:=`` by name."""
        out, positional = {}, [i for i, (_, optional, _) in enumerate(params) if not optional]
        by_name = {pname.lower(): i for i, (pname, _, _) in enumerate(params)}
        cursor = 0
        for arg in args:
            if arg.name is not None:
                index = by_name.get(arg.name.lower())
                if index is None or params[index][1] != arg.optional:
                    spelled = ("optional argument \\" if arg.optional else "argument ") + arg.name
                    self.fail(arg.line, f"{name} has no {spelled}")
            else:
                if cursor >= len(positional):
                    self.fail(arg.line, f"{name} takes {len(positional)} argument(s); too many given")
                index = positional[cursor]
                cursor += 1
            if index in out:
                self.fail(arg.line, f"{name}: {params[index][0]} given twice")
            out[index] = arg
        missing = [params[i][0] for i in positional if i not in out]
        if missing:
            self.fail(line, f"{name}: missing argument(s) {', '.join(missing)}")
        return out

    def builtin_call(self, spec, args, line: int):
        """A closure calling a built-in: ``spec.impl(task, values)``."""
        matched = self._match(spec.name, [(p.name, p.optional, p.switch) for p in spec.params], args, line)
        producers = [self._builtin_arg(spec, p, matched.get(i), line) for i, p in enumerate(spec.params)]
        impl = spec.impl
        return lambda f: impl(f.task, [produce(f) for produce in producers])

    def _builtin_arg(self, spec, param, arg, line: int):
        what = f"{spec.name} {param.name}"
        if arg is None:
            return _ABSENT_NONE if not param.switch else _FALSE
        if param.switch:
            if arg.value is not None:
                self.fail(arg.line, f"\\{param.name} of {spec.name} is a switch: it takes no value")
            return _TRUE
        if arg.value is None:
            self.fail(arg.line, f"{what} needs a value")
        expected = None if param.type == "any" else self.type_named(param.type, line)
        if param.mode == "signal":
            return self._signal_arg(arg, param, what)
        if param.mode == "ref":
            if expected is not None and expected.kind == "handle":
                fn, t = self.ref(arg.value, writing=False)
                self.check(expected, t, arg.line, what)
                return lambda f: fn(f).get()
            return self._ref_arg(arg, expected, 0, what)
        if param.mode == "lazy":
            fn, t = self.expr(arg.value, expected)
            self.check(expected, t, arg.line, what)
            return lambda f: (lambda: fn(f))
        if expected is not None and expected.kind == "handle":
            fn, t = self.ref(arg.value, writing=False)
            self.check(expected, t, arg.line, what)
            return lambda f: fn(f).get()
        fn, t = self.expr(arg.value, expected)
        if expected is not None:
            self.check(expected, t, arg.line, what)
            records = self.program.records
            def converted(f):
                value = fn(f)
                return value if isinstance(value, Array) else coerce(value, expected, records, what)
            return converted
        return fn

    def _signal_arg(self, arg, param, what: str):
        node = arg.value
        symbol = self.scope.lookup(node.name) if isinstance(node, S.Name) else None
        if not isinstance(symbol, SignalSymbol):
            self.fail(arg.line, f"{what}: expected an I/O signal ({param.type}); {_text(node)} is not one")
        if symbol.type.name.lower() != param.type.lower():
            self.fail(arg.line, f"{what}: {symbol.name} is a {symbol.type.name}, expected a {param.type}")
        name = symbol.name
        return lambda f: name


def _static(t, dims):
    return ArrayType(t, len(dims)) if dims else t


def _position(array, index) -> int:
    if index != int(index):
        raise RapidFatalError(f"array index {index:g} is not an integer")
    i = int(index)
    if not 1 <= i <= len(array):
        raise RapidFatalError(f"array index {i} outside 1..{len(array)}")
    return i - 1


def _array_from(value, element):
    if isinstance(value, (Aggregate, list)):
        return Array(list(value), element)
    raise RapidFatalError("expected an array")


def _text(node) -> str:
    if isinstance(node, S.Name):
        return node.name
    if isinstance(node, S.Field):
        return f"{_text(node.base)}.{node.name}"
    if isinstance(node, S.Index):
        return f"{_text(node.base)}{{...}}"
    return "expression"


_ABSENT_NONE = lambda f: None  # noqa: E731
_TRUE = lambda f: True  # noqa: E731
_FALSE = lambda f: False  # noqa: E731
