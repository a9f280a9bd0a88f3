"""The Modbus register map (YAML) and the 32-bit float <-> register conversion, used by the client and the mock.

A map names every register the handshake uses (see ``modbus_map.yaml``, the default): its 0-based
holding-register address, type (``uint16``, ``uint32`` or ``float32``), count, who writes it (``robot`` or
``pc``) and the controller signal a gateway maps it to. Floats and 32-bit integers take two registers in the map's
``word_order``: ``big`` = high word first ("ABCD"), ``little`` = low word first ("CDAB").
"""

from __future__ import annotations

import os
import re
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ...base import brief
from ...base import parse_yaml, read_text_file
from .errors import ConfigError

__all__ = ["Register", "RegisterMap", "load_register_map", "DEFAULT_MAP", "STATE_CODES", "STATE_NAMES", "GUIDED_REGISTERS",
           "floats_to_registers", "registers_to_floats", "REQUIRED"]

DEFAULT_MAP = Path(__file__).with_name("modbus_map.yaml")

#: ``state`` register values.
STATE_CODES = {"READY": 0, "MOVING": 1, "AT": 2, "LATE": 3, "ACKED": 4, "ERROR": 5, "PROMPT": 6, "JOG": 7, "DONE": 8}
#: Registers only the guided program (HeIo rendered by ``rapid generate --guided``) uses.
GUIDED_REGISTERS = ("guide_verdict", "guide_hint")
STATE_NAMES = {v: k for k, v in STATE_CODES.items()}

#: Register name -> (type, count, access) every map must provide.
REQUIRED = {
    "protocol_version": ("uint16", 1, "robot"), "posture_count": ("uint16", 1, "robot"),
    "state": ("uint16", 1, "robot"), "posture": ("uint16", 1, "robot"), "at_posture": ("uint16", 1, "robot"),
    "error": ("uint16", 1, "robot"), "heartbeat": ("uint16", 1, "robot"), "tool_ack": ("uint16", 1, "robot"),
    "tool_error": ("uint16", 1, "robot"), "joints": ("float32", 6, "robot"), "tool0_position": ("float32", 3, "robot"),
    "tool0_quaternion": ("float32", 4, "robot"), "tool_readback": ("float32", 11, "robot"),
    "request": ("uint16", 1, "pc"), "grabbed": ("uint16", 1, "pc"), "tool_command": ("uint16", 1, "pc"),
    "tool_values": ("float32", 11, "pc"), "tool_key": ("uint32", 1, "pc"),
}
_WIDTH = {"uint16": 1, "uint32": 2, "float32": 2}


def floats_to_registers(values: Iterable[float], word_order: str = "big") -> list[int]:
    """IEEE-754 float32 values to 16-bit registers, two per value, in ``word_order``."""
    out = []
    for v in values:
        high, low = struct.unpack(">HH", struct.pack(">f", float(v)))
        out += [high, low] if word_order == "big" else [low, high]
    return out


def registers_to_floats(registers: Sequence[int], word_order: str = "big") -> list[float]:
    """16-bit registers (two per value, in ``word_order``) to float32 values (as Python floats)."""
    regs = list(registers)
    if len(regs) % 2:
        raise ValueError(f"float32 values need an even number of registers; got {len(regs)}")
    out = []
    for i in range(0, len(regs), 2):
        a, b = regs[i], regs[i + 1]
        high, low = (a, b) if word_order == "big" else (b, a)
        out.append(struct.unpack(">f", struct.pack(">HH", high & 0xFFFF, low & 0xFFFF))[0])
    return out


@dataclass(frozen=True)
class Register:
    name: str
    address: int
    type: str
    count: int
    access: str
    signal: str = ""

    @property
    def size(self) -> int:
        """Number of 16-bit registers."""
        return self.count * _WIDTH[self.type]

    @property
    def end(self) -> int:
        return self.address + self.size

    def signals(self) -> list[str]:
        """Controller signal names, ranges expanded: ``aoHeJ1..aoHeJ6``, ``aoHeX..aoHeZ``."""
        if ".." not in self.signal:
            return [self.signal] if self.signal else []
        first, last = self.signal.split("..")
        m1, m2 = re.fullmatch(r"(.*?)(\d+)", first), re.fullmatch(r"(.*?)(\d+)", last)
        if m1 and m2 and m1.group(1) == m2.group(1):
            return [f"{m1.group(1)}{i}" for i in range(int(m1.group(2)), int(m2.group(2)) + 1)]
        if first[:-1] == last[:-1]:
            return [first[:-1] + chr(c) for c in range(ord(first[-1]), ord(last[-1]) + 1)]
        raise ValueError(f"register {self.name}: cannot expand signal range {self.signal!r}")


@dataclass(frozen=True)
class RegisterMap:
    device_id: int
    word_order: str
    registers: dict
    source: str = "built-in"

    def __getitem__(self, name: str) -> Register:
        return self.registers[name]

    def span(self, *names: str) -> tuple[int, int]:
        """``(first address, count)`` of one read covering ``names``."""
        regs = [self.registers[n] for n in names]
        start = min(r.address for r in regs)
        return start, max(r.end for r in regs) - start

    @property
    def size(self) -> int:
        """Registers needed to hold every address of the map."""
        return max(r.end for r in self.registers.values())

    def encode(self, name: str, values: float | list[float] | tuple[float, ...]) -> list[int]:
        reg = self.registers[name]
        items = list(values) if isinstance(values, (list, tuple)) else [values]
        if len(items) != reg.count:
            raise ValueError(f"register {name} holds {reg.count} values; got {len(items)}")
        if reg.type == "float32":
            return floats_to_registers(items, self.word_order)
        if reg.type == "uint32":
            out = []
            for v in items:
                high, low = (int(v) >> 16) & 0xFFFF, int(v) & 0xFFFF
                out += [high, low] if self.word_order == "big" else [low, high]
            return out
        return [int(v) & 0xFFFF for v in items]

    def decode(self, name: str, registers: Sequence[int], start: int | None = None) -> list:
        """Values of ``name`` from a block of ``registers`` read from address ``start``."""
        reg = self.registers[name]
        offset = reg.address - (reg.address if start is None else start)
        chunk = list(registers)[offset:offset + reg.size]
        if len(chunk) != reg.size:
            raise ValueError(f"block does not cover register {name}")
        if reg.type == "float32":
            return registers_to_floats(chunk, self.word_order)
        if reg.type == "uint32":
            pairs = [(chunk[i], chunk[i + 1]) for i in range(0, len(chunk), 2)]
            return [((a << 16) | b) if self.word_order == "big" else ((b << 16) | a) for a, b in pairs]
        return chunk


def _bad(source, message):
    return ConfigError(f"register map {source}: {message}", backend="modbus")


def load_register_map(path: str | os.PathLike[str] | RegisterMap | None = None) -> RegisterMap:
    """Read and check a register map (default: the built-in ``modbus_map.yaml``).

    Raises
    ------
    ConfigError
        Missing registers, wrong types or counts, overlapping addresses, bad word order.
    """
    if isinstance(path, RegisterMap):
        return path
    file = Path(path) if path is not None else DEFAULT_MAP
    source = str(file) if path is not None else "built-in"
    data = parse_yaml(read_text_file(file, "register map", ConfigError), f"register map {source}", ConfigError)
    if not isinstance(data, dict) or data.get("format") != "handeye-modbus-map/1":
        raise _bad(source, "expected 'format: handeye-modbus-map/1'")
    word_order = data.get("word_order")
    if word_order not in ("big", "little"):
        raise _bad(source, f"word_order must be 'big' or 'little'; got {brief(word_order)}")
    device_id = data.get("device_id", 1)
    if isinstance(device_id, bool) or not isinstance(device_id, int) or not 0 <= device_id <= 247:
        raise _bad(source, f"device_id must be 0..247; got {brief(device_id)}")
    entries = data.get("registers")
    if not isinstance(entries, dict):
        raise _bad(source, "missing 'registers'")
    registers = {}
    for name, spec in entries.items():
        if not isinstance(spec, dict):
            raise _bad(source, f"register {name} must be a mapping")
        unknown = set(spec) - {"address", "type", "count", "access", "signal"}
        if unknown:
            raise _bad(source, f"register {name}: unknown keys {sorted(unknown)}")
        address, kind, count = spec.get("address"), spec.get("type"), spec.get("count", 1)
        if isinstance(address, bool) or not isinstance(address, int) or not 0 <= address <= 65535:
            raise _bad(source, f"register {name}: address must be 0..65535; got {brief(address)}")
        if kind not in _WIDTH:
            raise _bad(source, f"register {name}: type must be uint16, uint32 or float32; got {brief(kind)}")
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise _bad(source, f"register {name}: count must be >= 1; got {count!r}")
        access = spec.get("access")
        if access not in ("robot", "pc"):
            raise _bad(source, f"register {name}: access must be 'robot' or 'pc'; got {access!r}")
        registers[name] = Register(name, address, kind, count, access, str(spec.get("signal", "")))
    for name, (kind, count, access) in REQUIRED.items():
        reg = registers.get(name)
        if reg is None:
            raise _bad(source, f"register {name} is missing")
        if (reg.type, reg.count, reg.access) != (kind, count, access):
            raise _bad(source, f"register {name} must be {count} x {kind} written by the {access}; "
                               f"got {reg.count} x {reg.type} by the {reg.access}")
    ordered = sorted(registers.values(), key=lambda r: r.address)
    for a, b in zip(ordered, ordered[1:]):
        if b.address < a.end:
            raise _bad(source, f"registers {a.name} and {b.name} overlap at address {b.address}")
    if max(r.end for r in ordered) > 65536:
        raise _bad(source, "registers run past address 65535")
    return RegisterMap(device_id, word_order, registers, source)
