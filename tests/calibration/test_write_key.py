"""The write key's code (base/write_key.py): one definition for the drivers and the RAPID generator."""

from __future__ import annotations

import hashlib

import pytest

import handeye.base.write_key as write_key
from handeye.base.write_key import WRITE_KEY_PATTERN, write_key_code


@pytest.mark.parametrize("key", ["right-key_42", "a" * 32, "________", "ABCdef12"])
def test_the_code_is_the_first_four_bytes_of_sha256_big_endian(key):
    assert WRITE_KEY_PATTERN.fullmatch(key)
    assert write_key_code(key) == int.from_bytes(hashlib.sha256(key.encode()).digest()[:4], "big")
    assert 0 < write_key_code(key) < 2**32


def test_a_known_code():
    # SHA-256("12345678") = ef797c81 18f02dfb ... (the published digest of that text)
    assert write_key_code("12345678") == 0xEF797C81


def test_a_zero_code_becomes_one_so_a_cleared_register_never_matches(monkeypatch):
    class Zero:
        def __init__(self, data):
            pass

        def digest(self):
            return bytes(32)

    monkeypatch.setattr(write_key.hashlib, "sha256", Zero)
    assert write_key_code("anything1") == 1


@pytest.mark.parametrize("key", ["short", "x" * 33, "has space1", "semi;colon", ""])
def test_keys_outside_the_pattern(key):
    assert not WRITE_KEY_PATTERN.fullmatch(key)


def test_the_drivers_and_the_generator_use_this_one_definition():
    from handeye.drivers.controller import protocol, types
    from handeye.rapid import generate, station

    assert types.write_key_code is protocol.write_key_code is generate.write_key_code is write_key_code
    assert types.WRITE_KEY_PATTERN is station.WRITE_KEY_PATTERN is WRITE_KEY_PATTERN
