"""The 32-bit code of a station's write key: what ``HeKey.sys`` holds and what the PC sends.

One definition for both sides: ``rapid.generate`` writes it into ``HeKey.sys`` (``HE_WRITE_CODE``)
and the Modbus client (``drivers.controller``) writes it into the ``tool_key`` register. Standard
library only, so the drivers import it without loading the RAPID generator.
"""

from __future__ import annotations

import hashlib

__all__ = ["write_key_code"]


def write_key_code(key: str) -> int:
    """The 32-bit code of a write key for the Modbus ``tool_key`` register and ``HeKey.sys``.

    The first 4 bytes of SHA-256 of the key (ASCII) as an unsigned big-endian integer; 0 becomes 1
    so that a cleared register never matches.
    """
    code = int.from_bytes(hashlib.sha256(key.encode("ascii")).digest()[:4], "big")
    return code or 1
