"""Package re-exports that import their module on first use (PEP 562).

Every room's ``__init__`` re-exports its public names, yet ``import handeye.<room>`` stays cheap:
``handeye --help`` and a bare ``import handeye.drivers`` load neither numpy's solvers nor OpenCV,
pymodbus or pyserial until a name that needs them is used.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: dict[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for a package that re-exports names of its modules lazily.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict
        Public name -> module defining it: relative to ``package`` (``"controller.interface"``), or
        absolute (``"handeye.base.errors"``) for a name another room defines.

    Returns
    -------
    tuple of callable
        ``(__getattr__, __dir__)`` to assign at the package's top level.

    Example
    -------
    >>> __getattr__, __dir__ = lazy_exports(__name__, {"calibrate": "solve"})  # doctest: +SKIP
    """

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module if module.startswith("handeye.") else f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)  # the next look-up is a plain attribute
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
