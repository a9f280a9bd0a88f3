"""Stops a test run at once, with one line saying what to do, when ``handeye`` is not installed.

The rooms (``calibration/``, ``drivers/`` ...) import as ``handeye.<room>`` only once the package
is installed (``setup.py`` maps them); a plain checkout would otherwise fail in every test file.
"""

import pytest

try:
    import handeye.calibration  # noqa: F401
except ImportError as exc:
    pytest.exit(f"handeye is not importable ({exc}): install it first, from the repository folder: "
                'pip install -e ".[test]"', returncode=4)
