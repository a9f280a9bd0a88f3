"""The gate profile's promise (``tests/conftest.py``): a property-based test draws the same cases
whatever ran before it in the worker, so the suite passes or fails on the code, not on its order."""

from __future__ import annotations

import importlib
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytestmark = pytest.mark.skipif(not settings().derandomize, reason="HANDEYE_FUZZ=explore draws new cases on purpose")


def _draws() -> list:
    """200 cases of a strategy whose draws can take literals (text, integers, floats, bytes)."""
    seen = []

    @settings(max_examples=200, database=None)
    @given(st.one_of(st.text(max_size=12), st.integers(), st.floats(), st.binary(max_size=8)))
    def case(value):
        seen.append(repr(value))

    case()
    return seen


def test_the_draws_do_not_depend_on_the_modules_loaded_before(tmp_path, monkeypatch):
    first = _draws()
    name = "fuzz_profile_literals"
    words = [f"literal_{k}" for k in range(60)]
    (tmp_path / f"{name}.py").write_text(f"WORDS = {words!r}\nNUMBERS = {list(range(7001, 7101))!r}\n"
                                         f"FLOATS = {[k + 0.25 for k in range(50)]!r}\nBLOB = {b'xyz-literal'!r}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, name, raising=False)
    importlib.import_module(name)  # a local module with literals a draw could take
    try:
        second = _draws()
    finally:
        sys.modules.pop(name, None)
    assert len(first) == len(second) == 200
    assert first == second, "the same seeded test drew other cases once another local module was loaded"
