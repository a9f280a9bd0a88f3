"""Reading and writing files safely: every way a path can be wrong becomes one line that says what to do.

Reading (:func:`read_text_file`, :func:`read_file_bytes`, :func:`check_regular_file`): the path must
name a regular file (not a folder, a named pipe, a device or a socket), be readable, be no larger
than a limit (64 MB by default; no input of the package comes near it) and, for text, hold UTF-8.
The path is checked with ``os.stat`` before it is opened, and opened with ``O_NONBLOCK`` and checked
again on the open descriptor, so a named pipe can never hang a reader. :func:`parse_yaml` turns
everything PyYAML can raise into the same kind of one-line error (it lives in :mod:`.yaml_text`:
duplicated keys are refused, ``1e30`` is a number).

Writing (:func:`write_text_atomic`, :func:`make_folder`): a temporary file in the target's folder,
flushed, renamed over the target. Any ``OSError`` (permission denied, a read-only file system, a file
where a folder should be, a full disk) becomes an :class:`~.errors.OutputError` naming the path, the
reason and the next step, and no temporary file is left behind.

Every reader and writer of the package goes through here; callers pass the error class of their
room (``SessionError``, ``ConfigError``, ...) so the message reaches the operator as one line.
"""

from __future__ import annotations

import codecs
import errno
import os
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path

from .errors import OutputError, SessionError
from .yaml_text import parse_yaml

__all__ = [
    "MAX_FILE_BYTES",
    "HEAD_BYTES",
    "binary_offset",
    "check_regular_file",
    "read_file_bytes",
    "read_text_file",
    "parse_yaml",
    "write_failure",
    "make_folder",
    "write_text_atomic",
    "write_bytes_atomic",
]

#: Largest file a reader accepts unless told otherwise (sessions, configs, imports are kilobytes).
MAX_FILE_BYTES = 64 * 1024 * 1024
#: How much of a text file is looked at before it is read whole: a binary file, or one in another
#: encoding, is refused from these first bytes (a 50 MB image is not read to find its first byte wrong).
HEAD_BYTES = 64 * 1024
_UTF8_BOM = b"\xef\xbb\xbf"
_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words (``None`` for a regular file)."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _megabytes(size: int) -> str:
    return f"{size / 2**20:.0f} MB" if size >= 2**20 else f"{size} bytes"


def _describe(what: str, path) -> str:
    return f"{what} {path}" if what else str(path)


def _read_failure(exc: OSError, what: str, path, error, missing: str | None) -> Exception:
    """The one-line error for an ``OSError`` raised while looking at or opening an input."""
    if exc.errno == errno.ENOENT:
        return error(missing or f"{_describe(what, path)} not found")
    if exc.errno == errno.ENOTDIR:
        return error(missing or f"{_describe(what, path)} not found (a part of the path is a file, not a folder)")
    if exc.errno in (errno.EACCES, errno.EPERM):
        return error(f"cannot read {_describe(what, path)}: permission denied; make it readable or copy it somewhere "
                     f"readable")
    if exc.errno == errno.EISDIR:
        return error(f"{_describe(what, path)} is a folder, not a file; give the file itself")
    if exc.errno == errno.ENAMETOOLONG:
        return error(f"cannot read {_describe(what, path)}: the name is too long")
    return error(f"cannot read {_describe(what, path)}: {(exc.strerror or str(exc)).lower()}")


def check_regular_file(path: str | os.PathLike[str], what: str = "file", error: type[Exception] = SessionError, *, missing: str | None = None,
                       max_bytes: int | None = MAX_FILE_BYTES) -> os.stat_result:
    """Refuse anything but an existing regular file of at most ``max_bytes`` (``None``: no limit).

    Parameters
    ----------
    path : str or Path
    what : str
        What the file is, for the message (``"posture file"``, ``"station configuration"``).
    error : type
        Exception class raised (one of the package's ``HandEyeError`` subclasses, or ``ValueError``
        where the caller turns it into one).
    missing : str, optional
        The whole message when the file does not exist (default ``"<what> <path> not found"``).
    max_bytes : int or None

    Returns
    -------
    os.stat_result

    Raises
    ------
    error
        Missing, a folder, a named pipe / device / socket, unreadable, or too large.
    """
    try:
        info = os.stat(path)
    except OSError as exc:
        raise _read_failure(exc, what, path, error, missing) from None
    except ValueError:  # an embedded NUL character
        raise error(f"{_describe(what, repr(str(path)))} is not a valid file name") from None
    _check_stat(info, what, path, error, max_bytes)
    return info


def _check_stat(info: os.stat_result, what: str, path, error, max_bytes: int | None) -> None:
    kind = _kind(info.st_mode)
    if kind == "a folder":
        raise error(f"{_describe(what, path)} is a folder, not a file; give the file itself")
    if kind is not None:
        raise error(f"{_describe(what, path)} is {kind}, not a regular file; give a regular file")
    if max_bytes is not None and info.st_size > max_bytes:
        raise error(f"{_describe(what, path)} is {_megabytes(info.st_size)}; files over {_megabytes(max_bytes)} are "
                    f"refused: is it the right file?")


def read_file_bytes(path: str | os.PathLike[str], what: str = "file", error: type[Exception] = SessionError, *, missing: str | None = None,
                    max_bytes: int | None = MAX_FILE_BYTES, head: int | None = None) -> bytes:
    """The bytes of a regular file (all of them, or the first ``head``), or a one-line ``error``.

    The path is checked (:func:`check_regular_file`) before it is opened; it is opened without
    blocking and checked again on the descriptor, so a path swapped for a named pipe cannot hang.
    With ``head`` the size limit does not apply (only ``head`` bytes are read).
    """
    limit = None if head is not None else max_bytes
    check_regular_file(path, what, error, missing=missing, max_bytes=limit)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise _read_failure(exc, what, path, error, missing) from None
    try:
        _check_stat(os.fstat(fd), what, path, error, limit)
        wanted = head if head is not None else (max_bytes + 1 if max_bytes is not None else -1)
        with os.fdopen(fd, "rb", closefd=False) as handle:
            data = handle.read(wanted)
    except OSError as exc:
        raise _read_failure(exc, what, path, error, missing) from None
    finally:
        os.close(fd)
    if head is None and max_bytes is not None and len(data) > max_bytes:  # grew while being read
        raise error(f"{_describe(what, path)} is over {_megabytes(max_bytes)}: is it the right file?")
    return data


def binary_offset(data: bytes) -> int | None:
    """The offset of the first NUL byte in the first 8 KB of ``data`` (text never holds one), else None."""
    offset = data.find(b"\0", 0, 8192)
    return None if offset < 0 else offset


def _text_problem(data: bytes, complete: bool) -> str | None:
    """Why ``data`` is not UTF-8 text, in words for a message; None when it is.

    ``complete`` False: ``data`` is only the file's head, so a character cut at its end is no fault.
    """
    start = len(_UTF8_BOM) if data.startswith(_UTF8_BOM) else 0
    try:
        codecs.getincrementaldecoder("utf-8")().decode(data[start:], final=complete)
    except UnicodeDecodeError as exc:
        offset = start + exc.start
        where = f"byte 0x{data[offset]:02x} at offset {offset}"
        if data.startswith(_UTF16_BOMS):
            return "is UTF-16 text: save it as UTF-8"
        if binary_offset(data) is not None:
            return f"is a binary file, not text ({where}): give the text file itself"
        return f"is not UTF-8 text ({where}): save it as UTF-8"
    return None


def read_text_file(path: str | os.PathLike[str], what: str = "file", error: type[Exception] = SessionError, *, missing: str | None = None,
                   max_bytes: int | None = MAX_FILE_BYTES) -> str:
    """The UTF-8 text of a regular file (a leading byte-order mark dropped), or a one-line ``error``.

    The first :data:`HEAD_BYTES` are checked before the file is read whole, so a large binary file is
    refused from its head.

    Parameters
    ----------
    path : str or Path
    what : str
        What the file is, for the messages.
    error : type
        Exception class raised.
    missing : str, optional
        The whole message when the file does not exist.
    max_bytes : int or None
        Largest accepted size (default :data:`MAX_FILE_BYTES`).

    Raises
    ------
    error
        Everything :func:`read_file_bytes` refuses, and text that is not UTF-8 (the message names the
        first bad byte and its offset, and tells UTF-16 text and binary files apart).
    """
    data = read_file_bytes(path, what, error, missing=missing, head=HEAD_BYTES)
    whole = len(data) < HEAD_BYTES and (max_bytes is None or len(data) <= max_bytes)
    problem = _text_problem(data, complete=whole)
    if problem is None and not whole:
        data = read_file_bytes(path, what, error, missing=missing, max_bytes=max_bytes)
        problem = _text_problem(data, complete=True)
    if problem is not None:
        raise error(f"{_describe(what, path)} {problem}")
    start = len(_UTF8_BOM) if data.startswith(_UTF8_BOM) else 0
    return data[start:].decode("utf-8")


# --------------------------------------------------------------------------- writing


def _first_existing(path: Path) -> Path | None:
    for candidate in (path, *path.parents):
        try:
            os.stat(candidate)
        except OSError:
            continue
        return candidate
    return None


def write_failure(path: str | os.PathLike[str], exc: OSError, action: str = "write") -> OutputError:
    """An :class:`OutputError` for an ``OSError`` raised while writing ``path``: path, reason, what to do.

    Parameters
    ----------
    path : str or Path
        The file or folder being written.
    exc : OSError
    action : str
        The verb of the message: ``cannot <action> <path>: <reason>; <what to do>``; ``"write"``
        for a file, ``"create folder"`` for a folder.
    """
    path = Path(path)
    code = exc.errno
    reason = (exc.strerror or str(exc)).lower()
    todo = "choose a writable folder"
    if code in (errno.EACCES, errno.EPERM):
        reason = "permission denied"
    elif code == errno.EROFS:
        reason = "the file system is read-only"
    elif code in (errno.ENOSPC, getattr(errno, "EDQUOT", -1)):
        reason, todo = "no space left on the device", "free some space or choose another disk"
    elif code == errno.ENAMETOOLONG:
        reason, todo = "the name is too long", "choose a shorter name"
    elif code == errno.EISDIR:
        reason, todo = "it is a folder", "give a file name"
    elif code in (errno.ENOTDIR, errno.EEXIST):
        existing = _first_existing(path if action == "create folder" else path.parent)
        if existing is not None and not existing.is_dir():
            reason = f"{existing} is a file, not a folder"
    elif code == errno.ENOENT:
        reason = "a folder on the way does not exist"
    return OutputError(f"cannot {action} {path}: {reason}; {todo}")


def make_folder(path: str | os.PathLike[str]) -> Path:
    """``mkdir -p path``, or an :class:`OutputError` naming the path, the reason and what to do."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise write_failure(path, exc, "create folder") from None
    return path


def _temporary_prefix(path: Path) -> str:
    return f".{path.name}."


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files :func:`write_text_atomic` leaves when its process is killed between
    writing and renaming (``.NAME.*.tmp``), in ``folder`` and below; returns the paths removed.

    Call it only where no other process writes (e.g. when a session is resumed): the targets
    themselves are always whole, the old version or the new one.
    """
    removed = []
    for path in Path(folder).rglob(".*.tmp"):
        if path.is_file():
            path.unlink(missing_ok=True)
            removed.append(path)
    return removed


def write_text_atomic(path: str | os.PathLike[str], text: str, encoding: str = "utf-8", newline: str | None = None) -> Path:
    """Write ``text`` to ``path`` atomically: a temporary file in the same folder, flushed to disk,
    renamed over the target (and the rename itself synced). The file gets the user's usual
    permissions (umask), not a temporary file's 0600. Used for every file the package writes.

    Raises
    ------
    OutputError
        The folder cannot be created or written (permission, read-only, a file in the way, full
        disk), or ``path`` is a folder; one line naming the path. Nothing is left behind.
    """
    return _write_atomic(path, lambda fd: os.fdopen(fd, "w", encoding=encoding, newline=newline), text, encoding)


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` (an image) to ``path`` atomically, as :func:`write_text_atomic` writes text."""
    return _write_atomic(path, lambda fd: os.fdopen(fd, "wb"), bytes(data), "bytes")


def write_texts_atomic(files: Iterable[tuple[str | os.PathLike[str], str]], encoding: str = "utf-8") -> list[Path]:
    """Write many files as :func:`write_text_atomic` writes one (temporary file, flushed to disk,
    renamed over the target), with one flush to disk for all of them instead of one per file: every
    temporary file is written first, then the data synced at once (``os.sync`` where it exists, else
    each file), then each renamed, then each folder synced once. A session of 10,000 postures is
    written in seconds, not minutes. A file that cannot be written stops the batch before any rename, and
    no temporary file is left behind.

    Parameters
    ----------
    files : iterable of (path, str)

    Returns
    -------
    list of Path

    Raises
    ------
    OutputError
        As :func:`write_text_atomic`, naming the first file that cannot be written.
    """
    written = []  # (temporary, target)
    opener = lambda fd: os.fdopen(fd, "w", encoding=encoding)  # noqa: E731
    try:
        for path, text in files:
            written.append((_write_temporary(Path(path), opener, text, encoding, sync=False), Path(path)))
        if hasattr(os, "sync"):
            os.sync()
        else:  # pragma: no cover - platforms without sync(2)
            for tmp, _ in written:
                _fsync_path(tmp, os.O_RDWR)
        for tmp, path in written:
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise write_failure(path, exc) from None
    finally:
        for tmp, _ in written:
            if os.path.exists(tmp):
                os.unlink(tmp)
    for folder in {path.parent for _, path in written}:
        try:  # make the renames durable
            _fsync_path(folder, os.O_RDONLY)
        except OSError:
            pass
    return [path for _, path in written]


def _fsync_path(path, flags: int) -> None:
    fd = os.open(path, flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_temporary(path: Path, opener, content, encoding: str, sync: bool) -> str:
    """``content`` in a new temporary file beside ``path``, with the permissions a new file gets,
    flushed to disk when ``sync``: its name. Nothing is left behind when it cannot be written.

    ``opener(fd)`` opens the descriptor for writing (text in ``encoding``, or bytes).
    """
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=_temporary_prefix(path), suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise write_failure(path, exc) from None
    try:
        with opener(fd) as handle:
            umask = os.umask(0)
            os.umask(umask)
            os.fchmod(handle.fileno(), 0o666 & ~umask)
            handle.write(content)
            if sync:
                handle.flush()
                os.fsync(handle.fileno())
    except BaseException as exc:
        os.unlink(tmp)
        _raise_write_error(path, exc, encoding)
    return tmp


def _raise_write_error(path: Path, exc: BaseException, encoding: str) -> None:
    """Re-raise what writing ``path`` raised: an ``OSError`` or a character ``encoding`` cannot store as
    a one-line :class:`OutputError`, anything else (KeyboardInterrupt ...) as it is."""
    if isinstance(exc, OSError):
        raise write_failure(path, exc) from None
    if isinstance(exc, UnicodeEncodeError):
        raise OutputError(f"cannot write {path}: it would hold {exc.object[exc.start:exc.end]!r}, which "
                          f"{encoding} cannot store; remove that character") from None
    raise exc


def _write_atomic(path, opener, content, encoding: str) -> Path:
    path = Path(path)
    tmp = _write_temporary(path, opener, content, encoding, sync=True)
    try:
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        _raise_write_error(path, exc, encoding)
    try:  # make the rename itself durable
        _fsync_path(path.parent, os.O_RDONLY)
    except OSError:
        pass
    return path
