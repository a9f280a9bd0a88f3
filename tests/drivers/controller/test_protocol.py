"""The line-protocol codec: exact encodings, limits, and parsers fuzzed with hypothesis."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handeye.drivers.controller import protocol as P
from handeye.drivers.controller.errors import ProtocolError


def test_request_and_reply_encodings():
    assert P.encode_request(17, "GOTO", 3) == b"17 GOTO 3\n"
    assert P.encode_request(999, "TOOLROT", 0.70710678, 0, -0.70710678, 0) == b"999 TOOLROT 0.707107 0 -0.707107 0\n"
    req = P.parse_request(b"5 JOINTS\r\n")
    assert req == P.Request(5, "JOINTS", ())
    assert P.encode_ok(req, 1, -2.5, 3.14159265, 0, 0, -300) == b"5 OK 1 -2.5 3.1416 0 0 -300\n"
    assert P.encode_error(5, P.E_BUSY, "busy: acknowledge posture 2 first") == b"5 ERR 5 busy: acknowledge posture 2 first\n"
    reply = P.parse_reply(b"5 OK 1 -2.5 3.1416 0 0 -300\n")
    assert P.decode_values("JOINTS", reply) == (1.0, -2.5, 3.1416, 0.0, 0.0, -300.0)
    err = P.parse_reply(b"12 ERR 4 posture not approved\n")
    assert (err.id, err.ok, err.code, err.message) == (12, False, 4, "posture not approved")


def test_format_number_never_writes_minus_zero():
    assert P.format_number(-0.00000001, 6) == "0"
    assert P.format_number(2.0, 4) == "2"
    assert P.format_number(-1.23456789, 4) == "-1.2346"


def _worst_value(field):
    if isinstance(field, P.NumField):
        return -(field.limit - 10.0 ** -field.decimals * 0.3) if not field.positive else field.limit - 0.0004
    if isinstance(field, P.IntField):
        return field.high
    if isinstance(field, P.KeyField):
        return "k-" * 16
    return max(field.choices or ("ABCDEFGHIJKLMNOP",), key=len)


@pytest.mark.parametrize("command", sorted(P.SPECS))
def test_every_message_fits_a_rapid_string(command):
    spec = P.SPECS[command]
    request = P.encode_request(P.MAX_ID, command, *[_worst_value(f) for f in spec.args])
    reply = P.encode_ok(P.Request(P.MAX_ID, command, ()), *[_worst_value(f) for f in spec.reply])
    for message in (request, reply):
        assert len(message) - 1 <= P.MAX_MESSAGE < 80
    assert len(P.encode_error(P.MAX_ID, 99, "x" * 200)) - 1 <= P.MAX_MESSAGE


@pytest.mark.parametrize("field", [P.ANGLE, P.POSITION, P.QUATERNION, P.MASS])
def test_last_digit_survives_float32(field):
    # RAPID num is float32: the largest value carried keeps its last decimal
    rng = np.random.default_rng(1)
    values = rng.uniform(-field.limit, field.limit, 2000)
    if field.positive:
        values = np.abs(values) + 10.0 ** -field.decimals
    written = np.array([float(field.format(v)) for v in values])
    through_rapid = written.astype(np.float32).astype(float)
    back = np.array([float(P.format_number(v, field.decimals)) for v in through_rapid])
    assert np.array_equal(back, written)


def test_values_outside_the_protocol_are_refused_when_encoding():
    with pytest.raises(ValueError):
        P.encode_request(1, "TOOLPOS", math.nan, 0, 0)
    with pytest.raises(ValueError):
        P.encode_request(1, "TOOLPOS", 5000, 0, 0)
    with pytest.raises(ValueError):
        P.encode_request(0, "PING")
    with pytest.raises(ValueError):
        P.encode_request(1, "GOTO")
    with pytest.raises(ValueError):
        P.encode_request(1, "FLY")


@pytest.mark.parametrize("line, code", [
    (b"PING\n", P.E_SYNTAX),
    (b"0 PING\n", P.E_SYNTAX),
    (b"007 PING\n", P.E_SYNTAX),
    (b"3 FLY\n", P.E_UNKNOWN),
    (b"3 GOTO\n", P.E_ARGS),
    (b"3 GOTO 2.5\n", P.E_ARGS),
    (b"3 TOOLPOS 1 2 x\n", P.E_ARGS),
    (b"3 PING \xff\n", P.E_SYNTAX),
    (b"3 " + b"A" * 80 + b"\n", P.E_SYNTAX),
])
def test_malformed_requests_get_the_right_error_code(line, code):
    with pytest.raises(P.RequestError) as info:
        P.parse_request(line)
    assert info.value.code == code


@pytest.mark.parametrize("line", [
    b"", b"\n", b"OK\n", b"1 YES\n", b"1 ERR\n", b"1 ERR x\n", b"1  OK\n", b"1 OK  2\n", b"-1 OK\n",
    b"1 OK \x00\n", b"1 OK " + b"9" * 80 + b"\n",
])
def test_malformed_replies_raise_protocol_error(line):
    with pytest.raises(ProtocolError):
        P.parse_reply(line)


@pytest.mark.parametrize("line", [b"1 OK 1 2 3\n", b"1 OK 1 2 3 4 5 x\n", b"1 OK 1 2 3 4 5 1e400\n", b"1 OK 1 2 3 4 5 500\n"])
def test_wrong_values_raise_protocol_error(line):
    with pytest.raises(ProtocolError):
        P.decode_values("JOINTS", P.parse_reply(line))


@settings(max_examples=400, deadline=None)
@given(st.binary(max_size=120))
def test_fuzz_reply_parser_raises_only_protocol_error(data):
    try:
        reply = P.parse_reply(data)
    except ProtocolError:
        return
    for command in P.SPECS:
        try:
            P.decode_values(command, reply)
        except ProtocolError:
            pass


@settings(max_examples=400, deadline=None)
@given(st.lists(st.sampled_from(list("0123456789 .-+eEKRAT\n\r") + ["OK", "ERR", " 1", "GOTO", " "]), max_size=40))
def test_fuzz_reply_parser_on_near_valid_text(pieces):
    try:
        reply = P.parse_reply("".join(pieces).encode())
    except ProtocolError:
        return
    for command in P.SPECS:
        try:
            values = P.decode_values(command, reply)
        except ProtocolError:
            continue
        assert all(isinstance(v, (int, float, str)) for v in values)


@settings(max_examples=400, deadline=None)
@given(st.one_of(st.binary(max_size=120), st.text(max_size=100).map(str.encode)))
def test_fuzz_request_parser_raises_only_request_error(data):
    try:
        request = P.parse_request(data)
    except P.RequestError as exc:
        assert 0 <= exc.request_id <= P.MAX_ID and exc.code in P.ERROR_CODES
        return
    assert request.command in P.SPECS
    assert len(request.args) == len(P.SPECS[request.command].args)


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(sorted(P.SPECS)), st.integers(1, P.MAX_ID), st.data())
def test_roundtrip_of_every_command(command, request_id, data):
    spec = P.SPECS[command]

    def draw(field):
        if isinstance(field, P.NumField):
            low = 10.0 ** -field.decimals if field.positive else -field.limit
            return data.draw(st.floats(low, field.limit, allow_nan=False))
        if isinstance(field, P.IntField):
            return data.draw(st.integers(field.low, field.high))
        if isinstance(field, P.KeyField):
            return data.draw(st.from_regex(r"[A-Za-z0-9_-]{8,32}", fullmatch=True))
        return data.draw(st.sampled_from(field.choices or ("RAPID", "MOCK")))

    args = [draw(f) for f in spec.args]
    request = P.parse_request(P.encode_request(request_id, command, *args))
    assert request.id == request_id and request.command == command
    for field, sent, got in zip(spec.args, args, request.args):
        if isinstance(field, P.NumField):
            assert abs(got - sent) <= 0.5 * 10.0 ** -field.decimals + 1e-12
        else:
            assert got == sent
    values = [draw(f) for f in spec.reply]
    decoded = P.decode_values(command, P.parse_reply(P.encode_ok(request, *values)))
    for field, sent, got in zip(spec.reply, values, decoded):
        if isinstance(field, P.NumField):
            assert abs(got - sent) <= 0.5 * 10.0 ** -field.decimals + 1e-12
        else:
            assert got == sent
