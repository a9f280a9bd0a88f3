"""The basement every room stands on: the package's errors, safe files, the one YAML reader, the
extension registries, lazy exports, the write key, threads for numpy batches and time bounds.

Standard library and PyYAML only.

The names below load on first use (importing the room is cheap)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .lazy import lazy_exports

_EXPORTS = {
    "alias_module": "deprecation",
    "CalibrationError": "errors",
    "ConfigError": "errors",
    "HandEyeError": "errors",
    "OutputError": "errors",
    "SessionError": "errors",
    "SessionUsageError": "errors",
    "UsageError": "errors",
    "brief": "errors",
    "exception_line": "errors",
    "with_backend": "errors",
    "HEAD_BYTES": "files",
    "binary_offset": "files",
    "check_regular_file": "files",
    "make_folder": "files",
    "parse_yaml": "files",
    "read_file_bytes": "files",
    "read_text_file": "files",
    "remove_stale_temporaries": "files",
    "write_bytes_atomic": "files",
    "write_failure": "files",
    "write_text_atomic": "files",
    "write_texts_atomic": "files",
    "lazy_exports": "lazy",
    "WORKERS": "parallel",
    "map_chunks": "parallel",
    "Choices": "registry",
    "Registry": "registry",
    "load_target": "registry",
    "quiet_loads": "registry",
    "unusable_clause": "registry",
    "OutOfTime": "time_bound",
    "TIME_VARIABLE": "time_bound",
    "call_within": "time_bound",
    "plugin_time_s": "time_bound",
    "WRITE_KEY_PATTERN": "write_key",
    "write_key_code": "write_key",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
    from .deprecation import alias_module  # noqa: F401
    from .errors import CalibrationError, ConfigError, HandEyeError, OutputError, SessionError, SessionUsageError, UsageError, brief, exception_line, with_backend  # noqa: F401
    from .files import HEAD_BYTES, binary_offset, check_regular_file, make_folder, parse_yaml, read_file_bytes, read_text_file, remove_stale_temporaries, write_bytes_atomic, write_failure, write_text_atomic, write_texts_atomic  # noqa: F401
    from .lazy import lazy_exports  # noqa: F401
    from .parallel import WORKERS, map_chunks  # noqa: F401
    from .registry import Choices, Registry, load_target, quiet_loads, unusable_clause  # noqa: F401
    from .time_bound import OutOfTime, TIME_VARIABLE, call_within, plugin_time_s  # noqa: F401
    from .write_key import WRITE_KEY_PATTERN, write_key_code  # noqa: F401
