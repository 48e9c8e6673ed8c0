"""IEC values <-> 16-bit Modbus words as OpenPLC serves them (most significant word first)."""

from __future__ import annotations

import struct

from plc.st import rt

WORDS = {
    "BOOL": 1,
    "SINT": 1,
    "USINT": 1,
    "BYTE": 1,
    "INT": 1,
    "UINT": 1,
    "WORD": 1,
    "DINT": 2,
    "UDINT": 2,
    "DWORD": 2,
    "REAL": 2,
    "TIME": 2,
    "LINT": 4,
    "ULINT": 4,
    "LWORD": 4,
    "LREAL": 4,
}
SIGNED = {"SINT", "INT", "DINT", "LINT"}
BITS = {
    "SINT": 8,
    "USINT": 8,
    "BYTE": 8,
    "INT": 16,
    "UINT": 16,
    "WORD": 16,
    "DINT": 32,
    "UDINT": 32,
    "DWORD": 32,
    "LINT": 64,
    "ULINT": 64,
    "LWORD": 64,
}


def to_words(value, iec_type: str, count: int | None = None) -> list[int]:
    """Encode a value into `count` words (default: the type's natural size)."""
    n = count or WORDS.get(iec_type, 1)
    if iec_type == "BOOL":
        return [1 if value else 0]
    if iec_type == "REAL":
        raw = struct.unpack(">I", struct.pack(">f", rt.f32(float(value))))[0]
    elif iec_type == "LREAL":
        raw = struct.unpack(">Q", struct.pack(">d", float(value)))[0]
    else:
        raw = int(value) & ((1 << (16 * n)) - 1)
    return [(raw >> (16 * (n - 1 - i))) & 0xFFFF for i in range(n)]


def from_words(words: list[int], iec_type: str):
    raw = 0
    for w in words:
        raw = (raw << 16) | (w & 0xFFFF)
    if iec_type == "BOOL":
        return bool(raw)
    if iec_type == "REAL":
        return struct.unpack(">f", struct.pack(">I", raw & 0xFFFFFFFF))[0]
    if iec_type == "LREAL":
        return struct.unpack(">d", struct.pack(">Q", raw))[0]
    bits = 16 * len(words)
    if iec_type in SIGNED and raw >= 1 << (bits - 1):
        raw -= 1 << bits
    return raw
