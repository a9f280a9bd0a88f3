"""The names RAPID itself provides, as the interpreter knows them: one list for the linker and the checks.

:func:`data_types` and :func:`predefined_names` are what :mod:`handeye.rapid.checks` accepts without a
declaration; they are read from the interpreter's own tables (the data types of
:data:`~handeye.rapid.interpreter.values.TYPES`, the predefined data, the error numbers, and the
instructions and functions registered in :mod:`~handeye.rapid.interpreter.builtins`), so a name the
checks accept is one the interpreter can run, and the two cannot drift apart.
"""

from __future__ import annotations

from functools import lru_cache

from .errors import ERROR_NUMBERS
from .values import PREDEFINED, TYPES

__all__ = ["data_types", "predefined_names"]

#: Names the compiler itself handles (not in a table): the error number and the optional-argument test.
_LANGUAGE_NAMES = ("errno", "present")


@lru_cache(maxsize=1)
def data_types() -> frozenset:
    """Lower-case names of the data types RAPID provides (and ``switch``, the optional switch parameter)."""
    return frozenset(TYPES) | {"switch"}


@lru_cache(maxsize=1)
def predefined_names() -> frozenset:
    """Lower-case names usable without a declaration: data types, predefined data, error numbers,
    instructions and functions."""
    from .builtins import BUILTINS, _load

    _load()
    return (data_types() | frozenset(PREDEFINED) | frozenset(n.lower() for n in ERROR_NUMBERS)
            | frozenset(BUILTINS) | frozenset(_LANGUAGE_NAMES))
