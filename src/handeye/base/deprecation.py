"""Old module paths kept for one release: a module that moved leaves an alias at its old path.

The alias (a two-line module at the old path) warns once with a :class:`DeprecationWarning` naming the
new path, then stands for the new module itself (``sys.modules`` holds the new module under the old
name), so ``from handeye.calibration.registry import Registry`` and a monkeypatch of the old path
reach the very objects of :mod:`handeye.base.registry`.
"""

# handeye-rooms-shim: the codemod leaves this file (its docstring names an old path on purpose)

from __future__ import annotations

import importlib
import sys
import warnings
from types import ModuleType

__all__ = ["alias_module"]


def alias_module(old: str, new: str) -> ModuleType:
    """Make module ``old`` an alias of module ``new``, with a deprecation warning.

    Parameters
    ----------
    old : str
        The old dotted path (the alias module's ``__name__``).
    new : str
        The dotted path the module lives at now.

    Returns
    -------
    module
        The new module, now also ``sys.modules[old]``.
    """
    warnings.warn(f"{old} moved to {new}; import it from there ({old} goes in the next release)",
                  DeprecationWarning, stacklevel=3)
    module = importlib.import_module(new)
    sys.modules[old] = module
    return module
