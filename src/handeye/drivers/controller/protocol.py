"""The handeye line protocol: THE codec, used by the PC clients and by the mock controller alike.

One request, one reply, each an ASCII line ended by LF (``\\n``; a CR before it is ignored):

    request:  <id> <COMMAND>[ <arg>...]          e.g.  ``17 GOTO 3``
    reply:    <id> OK[ <value>...]               e.g.  ``17 OK 3``
              <id> ERR <code> <text>             e.g.  ``17 ERR 5 busy: acknowledge posture 2 first``

``id`` is 1..999 (the PC counts up and wraps); the reply repeats it, so a late reply to a request
that timed out is recognised and skipped. ``0`` is used only by the controller when it could not read
the id of a malformed request. Every message is at most :data:`MAX_MESSAGE` characters before the
LF, well under the 80 characters a RAPID ``string`` holds. Numbers are fixed-point decimals with
the precision calibration needs and RAPID's 32-bit ``num`` can hold (see :data:`ANGLE` etc.).
The full table is :data:`SPECS`; ``src/handeye/rapid/PROTOCOL.md`` documents it for the RAPID side.

Parsers raise :class:`ProtocolError` on anything malformed and nothing else.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from .errors import ProtocolError
from .types import STATES, WRITE_KEY_PATTERN, write_key_code

__all__ = [
    "PROTOCOL_VERSION",
    "MAX_MESSAGE",
    "MAX_ID",
    "ERROR_CODES",
    "NumField",
    "IntField",
    "WordField",
    "KeyField",
    "CommandSpec",
    "SPECS",
    "Request",
    "Reply",
    "RequestError",
    "decode_line",
    "encode_request",
    "parse_request",
    "encode_ok",
    "encode_error",
    "parse_reply",
    "decode_values",
    "format_number",
    "write_key_code",
    "E_AUTH",
    "KEY_TRIES",
    "GUIDED_COMMANDS",
]

PROTOCOL_VERSION = 1
#: Longest message in characters, LF excluded (RAPID strings hold 80).
MAX_MESSAGE = 72
MAX_ID = 999

E_SYNTAX, E_UNKNOWN, E_ARGS, E_RANGE, E_BUSY, E_TOOL, E_STATE, E_FAULT, E_AUTH = 1, 2, 3, 4, 5, 6, 7, 8, 9
#: Wrong keys a session may send before the program refuses further KEY requests (socket: closes it).
KEY_TRIES = 3
#: Error codes of ``ERR`` replies.
ERROR_CODES = {
    E_SYNTAX: "malformed request (no id, bad characters, too long)",
    E_UNKNOWN: "unknown command",
    E_ARGS: "wrong number or format of arguments",
    E_RANGE: "posture index outside the approved list",
    E_BUSY: "robot busy (moving, or the current posture is not acknowledged)",
    E_TOOL: "tool data invalid or incomplete",
    E_STATE: "request not valid now (QUAT without POSE, ACK of another posture)",
    E_FAULT: "robot fault (program stopped or motion error)",
    E_AUTH: "not authorised: tool writes need KEY with the station's write key first",
}

_NUMBER = re.compile(r"-?\d{1,7}(\.\d{1,9})?([eE][-+]?\d{1,2})?")
_DIGITS = re.compile(r"0|[1-9]\d{0,2}")
_WORD = re.compile(r"[A-Z][A-Z0-9_]{0,15}")


def format_number(value: float, decimals: int) -> str:
    """Fixed ``decimals``, trailing zeros trimmed, never ``-0``: ``12.5``, ``-0.707107``, ``1``."""
    text = f"{value:.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


@dataclass(frozen=True)
class NumField:
    """A decimal number with ``decimals`` digits after the point and ``|value| <= limit``.

    ``limit`` keeps the last digit inside float32 precision: a RAPID ``num`` has a 24-bit
    mantissa, so ``limit * 2**-24 < 0.5 * 10**-decimals`` holds for every field.
    """

    name: str
    decimals: int
    limit: float
    positive: bool = False

    def format(self, value: float) -> str:
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"{self.name} must be finite; got {v}")
        if abs(v) > self.limit or (self.positive and v <= 0):
            bound = f"0 < {self.name} <= {self.limit:g}" if self.positive else f"|{self.name}| <= {self.limit:g}"
            raise ValueError(f"{self.name} {v:g} cannot be sent: the protocol carries {bound}")
        return format_number(v, self.decimals)

    def parse(self, token: str) -> float:
        if not _NUMBER.fullmatch(token):
            raise ProtocolError(f"expected a number for {self.name}; got {token[:20]!r}")
        v = float(token)
        if abs(v) > self.limit * (1 + 1e-9) + 10.0 ** -self.decimals or (self.positive and v <= 0):
            raise ProtocolError(f"{self.name} {token} is out of range (|value| <= {self.limit:g})")
        return v


@dataclass(frozen=True)
class IntField:
    """A non-negative integer in ``[low, high]`` (at most 3 digits)."""

    name: str
    low: int
    high: int

    def format(self, value: float) -> str:
        if isinstance(value, bool) or int(value) != value:
            raise ValueError(f"{self.name} must be an integer; got {value!r}")
        v = int(value)
        if not self.low <= v <= self.high:
            raise ValueError(f"{self.name} {v} outside {self.low}..{self.high}")
        return str(v)

    def parse(self, token: str) -> int:
        if not _DIGITS.fullmatch(token):
            raise ProtocolError(f"expected an integer for {self.name}; got {token[:20]!r}")
        v = int(token)
        if not self.low <= v <= self.high:
            raise ProtocolError(f"{self.name} {v} outside {self.low}..{self.high}")
        return v


@dataclass(frozen=True)
class WordField:
    """An upper-case word, one of ``choices`` when given."""

    name: str
    choices: tuple | None = None

    def format(self, value: object) -> str:
        text = str(value)
        if not _WORD.fullmatch(text) or (self.choices and text not in self.choices):
            raise ValueError(f"{self.name} {text!r} is not a protocol word")
        return text

    def parse(self, token: str) -> str:
        if not _WORD.fullmatch(token) or (self.choices and token not in self.choices):
            allowed = f" (one of {', '.join(self.choices)})" if self.choices else ""
            raise ProtocolError(f"unexpected {self.name} {token[:20]!r}{allowed}")
        return token


@dataclass(frozen=True)
class KeyField:
    """The station's write key: 8 to 32 letters, digits, ``_`` or ``-`` (one word, case kept).

    Errors never echo the value: it is a secret.
    """

    name: str = "write key"

    def format(self, value: object) -> str:
        text = value if isinstance(value, str) else ""
        if not WRITE_KEY_PATTERN.fullmatch(text):
            raise ValueError(f"the {self.name} must be 8 to 32 letters, digits, '_' or '-'")
        return text

    def parse(self, token: str) -> str:
        if not WRITE_KEY_PATTERN.fullmatch(token):
            raise ProtocolError(f"the {self.name} must be 8 to 32 letters, digits, '_' or '-'")
        return token


ANGLE = NumField("joint angle (deg)", 4, 400.0)
POSITION = NumField("position (mm)", 3, 4000.0)
QUATERNION = NumField("quaternion component", 6, 1.0)
MASS = NumField("mass (kg)", 3, 1000.0, positive=True)
POSTURE = IntField("posture index", 0, 999)  # the program answers ERR 4 outside its list
COUNT = IntField("posture count", 0, 255)
VERSION = IntField("protocol version", 0, 999)
STATE = WordField("state", STATES)
PROGRAM = WordField("program name")
KEY = KeyField()
#: The guided program's verdict and hint codes (their names and pendant texts: ``src/handeye/rapid/guided.py``, which
#: keeps the same ranges; a test checks they agree).
VERDICT = IntField("verdict", 1, 6)
HINT = IntField("hint", 0, 15)
#: Commands only the guided program (``rapid generate --guided``) serves.
GUIDED_COMMANDS = ("GUIDE",)


@dataclass(frozen=True)
class CommandSpec:
    """One command: its arguments, the values of its OK reply, and what it does."""

    name: str
    args: tuple
    reply: tuple
    doc: str


SPECS = {spec.name: spec for spec in (
    CommandSpec("PING", (), (), "is the server alive"),
    CommandSpec("VERSION", (), (VERSION, PROGRAM), "protocol version and program name"),
    CommandSpec("COUNT", (), (COUNT,), "number of approved postures in the program"),
    CommandSpec("JOINTS", (), (ANGLE,) * 6, "CJointT(): axes 1..6, deg"),
    CommandSpec("POSE", (), (POSITION,) * 3,
                "CRobT(\\Tool:=tool0 \\WObj:=wobj0): takes a snapshot, replies its trans x y z (mm)"),
    CommandSpec("QUAT", (), (QUATERNION,) * 4, "rot q1..q4 of the snapshot taken by the last POSE"),
    CommandSpec("GOTO", (POSTURE,), (POSTURE,),
                "accept a move to approved posture k (MoveAbsJ ... fine); the move starts after the reply"),
    CommandSpec("STATUS", (), (STATE, POSTURE), "program state and current posture"),
    CommandSpec("ACK", (POSTURE,), (POSTURE,), "the PC is done at posture k (images grabbed)"),
    CommandSpec("KEY", (KEY,), (), "authorise tool writes for this session with the station's write key"),
    CommandSpec("TOOLPOS", (POSITION,) * 3, (), "stage the tool frame translation x y z (mm)"),
    CommandSpec("TOOLROT", (QUATERNION,) * 4, (), "stage the tool frame rotation q1..q4"),
    CommandSpec("TOOLLOAD", (MASS,) + (POSITION,) * 3, (), "stage the tool mass (kg) and centre of gravity (mm)"),
    CommandSpec("TOOLSAVE", (), (), "check the three staged parts and write them to the PERS tooldata"),
    CommandSpec("GETTOOLPOS", (), (POSITION,) * 3, "tframe.trans of the PERS tooldata"),
    CommandSpec("GETTOOLROT", (), (QUATERNION,) * 4, "tframe.rot of the PERS tooldata"),
    CommandSpec("GETTOOLLOAD", (), (MASS,) + (POSITION,) * 3, "tload.mass and tload.cog of the PERS tooldata"),
    CommandSpec("BYE", (), (), "end the session (the socket server closes the connection)"),
    CommandSpec("GUIDE", (VERDICT, HINT), (POSTURE,),
                "guided program: the verdict on the last posture and the next hint; replies the postures offered so far"),
)}


class RequestError(ProtocolError):
    """A request the server cannot execute; ``id`` (0 when unreadable) and ``code`` for the ERR reply."""

    def __init__(self, message: str, request_id: int = 0, code: int = E_SYNTAX):
        super().__init__(message)
        self.request_id = request_id
        self.code = code


@dataclass(frozen=True)
class Request:
    id: int
    command: str
    args: tuple = ()

    def encode(self) -> bytes:
        return encode_request(self.id, self.command, *self.args)


@dataclass(frozen=True)
class Reply:
    """A parsed reply. ``tokens`` are the raw values of an OK reply; ``code``/``message`` of an ERR."""

    id: int
    ok: bool
    tokens: tuple = ()
    code: int = 0
    message: str = ""


def _check_id(request_id) -> int:
    if isinstance(request_id, bool) or not isinstance(request_id, int) or not 1 <= request_id <= MAX_ID:
        raise ValueError(f"request id must be an integer 1..{MAX_ID}; got {request_id!r}")
    return request_id


def _finish(text: str) -> bytes:
    if len(text) > MAX_MESSAGE:
        raise ValueError(f"message of {len(text)} characters exceeds the protocol limit of {MAX_MESSAGE}: {text!r}")
    return text.encode("ascii") + b"\n"


def decode_line(raw: object) -> str:
    """One received line (LF and an optional CR stripped) as text, checked for length and characters."""
    if isinstance(raw, str):
        raw = raw.encode("utf-8", errors="replace")
    if not isinstance(raw, (bytes, bytearray)):
        raise ProtocolError(f"expected bytes; got {type(raw).__name__}")
    data = bytes(raw)
    if data.endswith(b"\n"):
        data = data[:-1]
    if data.endswith(b"\r"):
        data = data[:-1]
    if len(data) > MAX_MESSAGE:
        raise ProtocolError(f"line of {len(data)} characters exceeds {MAX_MESSAGE}: {data[:40]!r}...")
    if not data:
        raise ProtocolError("empty line")
    if any(b < 0x20 or b > 0x7E for b in data):
        raise ProtocolError(f"line holds non-printable or non-ASCII bytes: {data[:40]!r}")
    return data.decode("ascii")


def encode_request(request_id: int, command: str, *args: object) -> bytes:
    """``<id> <COMMAND> <args>`` + LF, each argument formatted by its field.

    Raises
    ------
    ValueError
        Unknown command, wrong number of arguments, or a value the protocol cannot carry.
    """
    spec = SPECS.get(command)
    if spec is None:
        raise ValueError(f"unknown command {command!r}")
    if len(args) != len(spec.args):
        raise ValueError(f"{command} takes {len(spec.args)} arguments; got {len(args)}")
    parts = [str(_check_id(request_id)), command] + [f.format(a) for f, a in zip(spec.args, args)]
    return _finish(" ".join(parts))


def parse_request(raw: object) -> Request:
    """Server side: a request line to a :class:`Request` with typed arguments.

    Raises
    ------
    RequestError
        With the id (0 if unreadable) and the error code for the ERR reply.
    """
    try:
        text = decode_line(raw)
    except ProtocolError as exc:
        raise RequestError(str(exc), 0, E_SYNTAX) from None
    tokens = text.split(" ")
    if not _DIGITS.fullmatch(tokens[0]):
        raise RequestError(f"request must start with an id 1..{MAX_ID}: {text[:30]!r}", 0, E_SYNTAX)
    request_id = int(tokens[0])
    if request_id == 0:
        raise RequestError("request id 0 is reserved", 0, E_SYNTAX)
    if len(tokens) < 2 or not tokens[1]:
        raise RequestError("no command after the id", request_id, E_SYNTAX)
    spec = SPECS.get(tokens[1])
    if spec is None:
        raise RequestError(f"unknown command {tokens[1][:16]!r}", request_id, E_UNKNOWN)
    if len(tokens) - 2 != len(spec.args):
        raise RequestError(f"{spec.name} takes {len(spec.args)} arguments; got {len(tokens) - 2}", request_id, E_ARGS)
    try:
        args = tuple(f.parse(t) for f, t in zip(spec.args, tokens[2:]))
    except ProtocolError as exc:
        raise RequestError(f"{spec.name}: {exc}", request_id, E_ARGS) from None
    return Request(request_id, spec.name, args)


def encode_ok(request: Request, *values: object) -> bytes:
    """The OK reply to ``request`` carrying ``values`` formatted by the command's reply fields."""
    spec = SPECS[request.command]
    if len(values) != len(spec.reply):
        raise ValueError(f"{spec.name} reply carries {len(spec.reply)} values; got {len(values)}")
    parts = [str(_check_id(request.id)), "OK"] + [f.format(v) for f, v in zip(spec.reply, values)]
    return _finish(" ".join(parts))


def encode_error(request_id: int, code: int, message: str) -> bytes:
    """``<id> ERR <code> <message>``; the message is made printable ASCII and cut to fit."""
    if not isinstance(request_id, int) or not 0 <= request_id <= MAX_ID:
        request_id = 0
    head = f"{request_id} ERR {int(code)}"
    text = "".join(ch if " " <= ch <= "~" else "?" for ch in " ".join(str(message).split()))
    room = MAX_MESSAGE - len(head) - 1
    return _finish(f"{head} {text[:room]}" if text and room > 0 else head)


def parse_reply(raw: object) -> Reply:
    """A reply line to a :class:`Reply` (values left as text; see :func:`decode_values`).

    Raises
    ------
    ProtocolError
        For anything that is not ``<id> OK ...`` or ``<id> ERR <code> ...``.
    """
    text = decode_line(raw)
    tokens = text.split(" ")
    if len(tokens) < 2 or not _DIGITS.fullmatch(tokens[0]):
        raise ProtocolError(f"not a reply (expected '<id> OK|ERR ...'): {text[:40]!r}")
    reply_id = int(tokens[0])
    if tokens[1] == "OK":
        values = tuple(tokens[2:])
        if any(not t for t in values):
            raise ProtocolError(f"reply has empty fields (double spaces): {text[:40]!r}")
        return Reply(reply_id, True, values)
    if tokens[1] == "ERR":
        if len(tokens) < 3 or not re.fullmatch(r"\d{1,2}", tokens[2]):
            raise ProtocolError(f"ERR reply without an error code: {text[:40]!r}")
        return Reply(reply_id, False, (), int(tokens[2]), " ".join(tokens[3:]))
    raise ProtocolError(f"not a reply (expected OK or ERR after the id): {text[:40]!r}")


def decode_values(command: str, reply: Reply) -> tuple:
    """The typed values of an OK ``reply`` to ``command``.

    Raises
    ------
    ProtocolError
        Wrong number of values or a value of the wrong form.
    """
    spec = SPECS[command]
    if not reply.ok:
        raise ProtocolError(f"{command}: expected an OK reply; got ERR {reply.code}")
    if len(reply.tokens) != len(spec.reply):
        raise ProtocolError(f"{command} reply must carry {len(spec.reply)} values; got {len(reply.tokens)}: "
                            f"{' '.join(reply.tokens)[:40]!r}")
    return tuple(f.parse(t) for f, t in zip(spec.reply, reply.tokens))
