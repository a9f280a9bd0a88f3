"""The station's write key (``controller.write_key``) and its 32-bit code: one definition for the
PC's drivers (the line protocol's ``KEY`` word, the Modbus ``tool_key`` register) and for the RAPID
generator (``HeKey.sys``), which must compute the same code and may not import each other
(ARCHITECTURE.md). Standard library only.
"""

from __future__ import annotations

import hashlib
import re

__all__ = ["WRITE_KEY_PATTERN", "write_key_code"]

#: A write key: 8 to 32 letters, digits, ``_`` or ``-`` (one protocol word and a RAPID string).
WRITE_KEY_PATTERN = re.compile(r"[A-Za-z0-9_-]{8,32}")


def write_key_code(key: str) -> int:
    """The 32-bit code of a write key: what the PC writes to the Modbus ``tool_key`` register and
    ``HeKey.sys`` holds as ``HE_WRITE_CODE``.

    Parameters
    ----------
    key : str
        The write key (ASCII, :data:`WRITE_KEY_PATTERN`).

    Returns
    -------
    int
        The first 4 bytes of SHA-256 of the key as an unsigned big-endian integer, in [1, 2**32);
        0 becomes 1, so that a cleared register never matches.
    """
    code = int.from_bytes(hashlib.sha256(key.encode("ascii")).digest()[:4], "big")
    return code or 1
