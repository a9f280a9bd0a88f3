"""The instructions and functions RAPID provides that the interpreter implements.

Each is declared once with :func:`builtin`: its name, a signature in a compact form, and the Python
function doing it. The signature lists the parameters in order, separated by commas::

    "Str:string, ChPos:num, Set:string, \\\\NotInSet"

``\\\\Name`` is optional (without a type it is a switch), ``ref Name:type`` is passed by reference
(``VAR``/``INOUT`` in the manual), ``lazy Name:bool`` is passed unevaluated (``WaitUntil``'s
condition is evaluated again at every poll), a ``signal..`` type takes an I/O signal, ``any`` takes
a value of any type. The function is called as ``impl(task, args)`` with ``args`` in signature order:
values, :class:`~handeye.rapid.interpreter.frames.Ref` for ``ref``, a callable for ``lazy``, ``None``
for an absent optional, ``True``/``False`` for a switch.

A name the program calls that is neither its own routine nor here is refused at load time, naming it
and the line: the interpreter never guesses what an instruction does.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BParam", "Builtin", "BUILTINS", "builtin", "lookup"]


@dataclass(frozen=True)
class BParam:
    name: str
    type: str | None  # a type name, "any", or None for a switch
    mode: str = "in"  # in, ref, lazy, signal
    optional: bool = False

    @property
    def switch(self) -> bool:
        return self.type is None


@dataclass(frozen=True)
class Builtin:
    """An instruction (``proc``) or function (``func``) of RAPID."""

    name: str
    kind: str
    params: tuple
    impl: object
    returns: str | None = None


#: lower-case name -> Builtin, filled by the modules of this package.
BUILTINS: dict[str, Builtin] = {}


def _param(item: str) -> BParam:
    text = item.strip()
    optional = text.startswith("\\")
    text = text.lstrip("\\").strip()
    mode = "in"
    for word in ("ref", "lazy"):
        if text.startswith(word + " "):
            mode, text = word, text[len(word) + 1:].strip()
    name, _, type_name = text.partition(":")
    type_name = type_name.strip() or (None if optional else "any")
    if type_name and type_name.startswith("signal"):
        mode = "signal"
    return BParam(name.strip(), type_name, mode, optional)


def builtin(name: str, signature: str = "", returns: str | None = None):
    """Register the decorated ``impl(task, args)`` as RAPID's ``name`` (a function when ``returns``)."""
    params = tuple(_param(item) for item in signature.split(",") if item.strip())

    def register(impl):
        BUILTINS[name.lower()] = Builtin(name, "func" if returns else "proc", params, impl, returns)
        return impl

    return register


def lookup(name: str) -> Builtin | None:
    """The built-in called ``name`` (any case), after the implementation modules are loaded."""
    _load()
    return BUILTINS.get(name.lower())


_LOADED = False


def _load() -> None:
    global _LOADED
    if not _LOADED:
        from . import io, motion, moves, numbers, pendant, serial, sockets, strings, system  # noqa: F401  (they register)

        _LOADED = True
