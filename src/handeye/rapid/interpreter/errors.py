"""What can go wrong when RAPID is loaded or run, and the error numbers a program can handle.

- :class:`RapidLoadError`: the program cannot be loaded (syntax, an unknown name, a construct or a
  built-in the interpreter does not support, a type mismatch); the message names the module and line,
  as a controller refuses to load such a module.
- :class:`RapidRuntimeError`: a *recoverable* error with an error number (``ERR_SOCK_TIMEOUT`` ...),
  which the routine's ``ERROR`` handler may take (``ERRNO``).
- :class:`RapidFatalError`: an execution error with no error number (an argument outside its range,
  a function that ends without ``RETURN``); no handler sees it, the task stops.

The numbers of the ``ERR_*`` constants are the interpreter's own: a program compares ``ERRNO`` with
the names, never with literal numbers.
"""

from __future__ import annotations

from ..errors import RapidError

__all__ = ["RapidLoadError", "RapidRuntimeError", "RapidFatalError", "ERROR_NUMBERS", "ERROR_NAMES", "where"]

#: Recoverable errors a RAPID error handler can take (``ERRNO``), by name.
ERROR_NUMBERS = {
    name: 41000 + i for i, name in enumerate((
        "ERR_SOCK_TIMEOUT", "ERR_SOCK_CLOSED", "ERR_SOCK_ADDR_INUSE", "ERR_SOCK_NET_UNREACH", "ERR_DEV_MAXTIME",
        "ERR_WAIT_MAXTIME", "ERR_STRTOOLNG", "ERR_DIVZERO", "ERR_FILEOPEN", "ERR_FILEACC", "ERR_FILNOTFND",
        "ERR_ALRDYCNT", "ERR_ALRDY_MOVING", "ERR_GO_LIM", "ERR_AO_LIM", "ERR_INOMAX", "ERR_NORUNUNIT",
        "ERR_SIG_NOT_VALID", "ERR_ARGVALERR", "ERR_CALLPROC", "ERR_WZ_OUTSIDE", "ERR_INT_NOTVAL",
        "ERR_INT_MAXVAL", "ERR_NOTINTVAL", "ERR_OVERFLOW", "ERR_ILLDIM", "ERR_ORIENT_VALUE", "ERR_TP_MAXTIME"), 1)
}
ERROR_NAMES = {number: name for name, number in ERROR_NUMBERS.items()}


def where(module: str | None, line: int | None) -> str:
    """``HeSocket:12`` (or what is known of it)."""
    if module and line:
        return f"{module}:{line}"
    return module or (f"line {line}" if line else "?")


class RapidLoadError(RapidError):
    """A module cannot be loaded: ``str()`` is ``MODULE:LINE: message``.

    Attributes
    ----------
    module : str
    line : int
    detail : str
        The message without the position.
    """

    def __init__(self, module: str | None, line: int | None, detail: str):
        self.module, self.line, self.detail = module, line, detail
        super().__init__(f"{where(module, line)}: {detail}")


class _Located(RapidError):
    """An execution error that learns where it happened as it leaves the statement."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message
        self.module: str | None = None
        self.line: int | None = None

    def locate(self, module: str, line: int) -> None:
        if self.line is None:
            self.module, self.line = module, line

    def __str__(self) -> str:
        if self.line is None:
            return self.message
        return f"{where(self.module, self.line)}: {self.message}"


class RapidRuntimeError(_Located):
    """A recoverable RAPID error: ``errno`` is one of :data:`ERROR_NUMBERS` (or a program's own).

    Attributes
    ----------
    errno : int
    handled_in : object or None
        The routine frame whose error handler raised it on (the same frame does not take it again).
    """

    def __init__(self, errno, message: str = ""):
        number = ERROR_NUMBERS[errno] if isinstance(errno, str) else int(errno)
        self.errno = number
        self.handled_in: object | None = None  # a frames.Frame (which imports this module)
        name = ERROR_NAMES.get(number, str(number))
        super().__init__(f"{name}{': ' + message if message else ''}")

    @property
    def name(self) -> str:
        return ERROR_NAMES.get(self.errno, str(self.errno))


class RapidFatalError(_Located):
    """An execution error no error handler can take: the task stops with this message."""
