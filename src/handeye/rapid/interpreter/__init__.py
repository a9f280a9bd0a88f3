"""A RAPID interpreter: the language of the modules ``handeye rapid generate`` writes, run for real.

Layers, each usable alone::

    lexer -> parser (syntax tree) -> program (link: names, types, closures) -> runtime (a task thread)
                                         builtins/ (instructions and functions)    bindings (the world)

Typical use (the mock controller does this with its own bindings)::

    from handeye.rapid.interpreter import Bindings, Task, load_program
    program = load_program([(text, "HeMain.mod"), ...], signals={"diStart": "signaldi"})
    task = Task(program, Bindings(sockets=..., io=..., motion=...)).start()
    ...
    task.stop()

Anything the interpreter cannot run (syntax, an unknown name, an instruction it does not implement,
a type mismatch) is refused by :func:`load_program` with the module and line.
"""

from __future__ import annotations

from .bindings import Bindings, FixedArm, IoBinding, MemoryIo, MotionBinding, SerialBinding, SocketBinding
from .errors import ERROR_NUMBERS, RapidFatalError, RapidLoadError, RapidRuntimeError
from .parser import parse_module
from .program import ModuleSource, Program, load_program
from .runtime import Task

__all__ = ["Bindings", "FixedArm", "IoBinding", "MemoryIo", "MotionBinding", "SerialBinding", "SocketBinding",
           "ERROR_NUMBERS", "RapidFatalError", "RapidLoadError", "RapidRuntimeError", "parse_module",
           "ModuleSource", "Program", "load_program", "Task", "supported_builtins"]


def supported_builtins() -> list[str]:
    """The names of the RAPID instructions and functions the interpreter implements."""
    from .builtins import BUILTINS, _load

    _load()
    return sorted(b.name for b in BUILTINS.values())
