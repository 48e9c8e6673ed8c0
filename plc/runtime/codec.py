"""Conversion between IEC values and Modbus 16-bit words, the way OpenPLC serves them.

REAL = IEEE binary32, LREAL = IEEE binary64, integers two's complement; multi-word values
are big-endian (most significant word first), as measured on OpenPLC v3
(reference/openplc.md: REAL 2.5 in %MD1 reads `[0x4020, 0x0000]`).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass

WORD_BITS = 16
WORD_MASK = 0xFFFF


@dataclass(frozen=True)
class IecTypeInfo:
    """Bit width and kind of an elementary IEC type served over Modbus."""

    bits: int
    kind: str  # "bool", "signed", "unsigned", "real"


IEC_TYPES: dict[str, IecTypeInfo] = {
    "BOOL": IecTypeInfo(1, "bool"),
    "SINT": IecTypeInfo(8, "signed"),
    "INT": IecTypeInfo(16, "signed"),
    "DINT": IecTypeInfo(32, "signed"),
    "LINT": IecTypeInfo(64, "signed"),
    "USINT": IecTypeInfo(8, "unsigned"),
    "UINT": IecTypeInfo(16, "unsigned"),
    "UDINT": IecTypeInfo(32, "unsigned"),
    "ULINT": IecTypeInfo(64, "unsigned"),
    "BYTE": IecTypeInfo(8, "unsigned"),
    "WORD": IecTypeInfo(16, "unsigned"),
    "DWORD": IecTypeInfo(32, "unsigned"),
    "LWORD": IecTypeInfo(64, "unsigned"),
    "REAL": IecTypeInfo(32, "real"),
    "LREAL": IecTypeInfo(64, "real"),
}

_FLOAT_FORMATS = {32: ">f", 64: ">d"}


def type_info(iec_type: str) -> IecTypeInfo | None:
    """Info for an elementary type name (case-insensitive), None when it cannot be served."""
    return IEC_TYPES.get(iec_type.upper())


def int_to_words(raw: int, n_words: int) -> list[int]:
    """Split the low `16 * n_words` bits of `raw` into words, most significant first."""
    return [(raw >> (WORD_BITS * (n_words - 1 - i))) & WORD_MASK for i in range(n_words)]


def words_to_int(words: list[int]) -> int:
    """Join words (most significant first) into an unsigned integer."""
    raw = 0
    for word in words:
        raw = (raw << WORD_BITS) | (word & WORD_MASK)
    return raw


def wrap_integer(raw: int, info: IecTypeInfo) -> int:
    """Cut `raw` to the type's width, then read it signed or unsigned like a C cast."""
    mask = (1 << info.bits) - 1
    raw &= mask
    if info.kind == "signed" and raw >> (info.bits - 1):
        raw -= 1 << info.bits
    return raw


def encode(value: object, info: IecTypeInfo, n_words: int) -> list[int]:
    """Words for a PLC value (bool/int/float) of the given type, location `n_words` wide."""
    if info.kind == "real":
        packed = struct.pack(_FLOAT_FORMATS[info.bits], float(value))  # type: ignore[arg-type]
        return int_to_words(int.from_bytes(packed, "big"), n_words)
    return int_to_words(int(value), n_words)  # type: ignore[call-overload]


def decode(words: list[int], info: IecTypeInfo) -> object:
    """PLC value of the given type from its words (most significant first)."""
    raw = words_to_int(words)
    if info.kind == "real":
        data = (raw & ((1 << info.bits) - 1)).to_bytes(info.bits // 8, "big")
        return struct.unpack(_FLOAT_FORMATS[info.bits], data)[0]
    if info.kind == "bool":
        return bool(raw & 1)
    return wrap_integer(raw, info)


def text_to_words(text: str, n_words: int) -> list[int]:
    """ASCII text, two characters per word (high byte first), NUL padded and cut to fit."""
    data = text.encode("ascii", "replace")[: 2 * n_words].ljust(2 * n_words, b"\0")
    return [(data[2 * i] << 8) | data[2 * i + 1] for i in range(n_words)]


def words_to_text(words: list[int]) -> str:
    """Inverse of `text_to_words` (stops at the first NUL)."""
    data = b"".join(bytes(((w >> 8) & 0xFF, w & 0xFF)) for w in words)
    return data.split(b"\0", 1)[0].decode("ascii", "replace")


_RAW_FORMATS = {1: ">H", 2: ">I", 4: ">Q"}


def word_encoder(info: IecTypeInfo, n_words: int) -> Callable[[object], tuple[int, ...]]:
    """A fast `encode` for one (type, width) pair: precompiled struct formats, no loops."""
    words_format = struct.Struct(">" + "H" * n_words)
    if info.kind == "real":
        value_format = struct.Struct(_FLOAT_FORMATS[info.bits])
        return lambda value: words_format.unpack(value_format.pack(value))  # type: ignore[arg-type]
    raw_format = struct.Struct(_RAW_FORMATS[n_words])
    mask = (1 << (WORD_BITS * n_words)) - 1
    return lambda value: words_format.unpack(raw_format.pack(int(value) & mask))  # type: ignore[call-overload]
