"""OpenPLC v3's Modbus TCP address map (reference/openplc.md, verified register by register).

| location | table | address | words |
|---|---|---|---|
| %IXa.b | discrete input | 8a+b | bit, read only |
| %QXa.b | coil | 8a+b | bit |
| %IWn | input register | n (0..1023) | 1, read only |
| %QWn | holding | n (0..1023) | 1 |
| %MWn | holding | 1024+n | 1 |
| %MDn | holding | 2048+2n | 2, high word first |
| %MLn | holding | 4096+4n | 4, most significant first |

Table sizes follow OpenPLC's buffers (1024 entries per area): coils and discrete inputs
0..8191, input registers 0..1023, holding registers 0..8191; anything beyond answers
ILLEGAL DATA ADDRESS.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

AREA_ENTRIES = 1024  # OpenPLC BUFFER_SIZE: entries per located area
BITS_PER_BYTE_ADDRESS = 8  # %QXa.b -> 8a+b
BIT_TABLE_SIZE = AREA_ENTRIES * BITS_PER_BYTE_ADDRESS
INPUT_REGISTER_TABLE_SIZE = AREA_ENTRIES
HOLDING_QW_BASE = 0
HOLDING_MW_BASE = 1024
HOLDING_MD_BASE = 2048
HOLDING_ML_BASE = 4096
HOLDING_TABLE_SIZE = 8192


class Table(IntEnum):
    """The four Modbus data tables."""

    COIL = 1
    DISCRETE_INPUT = 2
    HOLDING = 3
    INPUT_REGISTER = 4


class ModbusError(IntEnum):
    """Modbus exception codes this server answers with."""

    ILLEGAL_FUNCTION = 1
    ILLEGAL_ADDRESS = 2
    ILLEGAL_VALUE = 3
    DEVICE_FAILURE = 4


@dataclass(frozen=True)
class ModbusPlace:
    """Where a located variable lives: table, first address, width in words (bits: 1)."""

    table: Table
    address: int
    n_words: int


@dataclass(frozen=True)
class _AreaRule:
    table: Table
    base: int
    words: int  # words per entry; 0 for bits


_RULES: dict[tuple[str, str], _AreaRule] = {
    ("I", "X"): _AreaRule(Table.DISCRETE_INPUT, 0, 0),
    ("Q", "X"): _AreaRule(Table.COIL, 0, 0),
    ("I", "W"): _AreaRule(Table.INPUT_REGISTER, 0, 1),
    ("Q", "W"): _AreaRule(Table.HOLDING, HOLDING_QW_BASE, 1),
    ("M", "W"): _AreaRule(Table.HOLDING, HOLDING_MW_BASE, 1),
    ("M", "D"): _AreaRule(Table.HOLDING, HOLDING_MD_BASE, 2),
    ("M", "L"): _AreaRule(Table.HOLDING, HOLDING_ML_BASE, 4),
}


def place_of(area: str, size: str, index: int, bit: int | None) -> ModbusPlace | str:
    """Modbus place of an IEC location, or a reason string when OpenPLC does not serve it."""
    rule = _RULES.get((area.upper(), size.upper()))
    if rule is None:
        return f"%{area}{size} locations are not in OpenPLC's Modbus map"
    if not 0 <= index < AREA_ENTRIES:
        return f"index {index} outside 0..{AREA_ENTRIES - 1}"
    if rule.words == 0:
        bit_no = bit or 0
        if not 0 <= bit_no < BITS_PER_BYTE_ADDRESS:
            return f"bit {bit_no} outside 0..{BITS_PER_BYTE_ADDRESS - 1}"
        return ModbusPlace(rule.table, BITS_PER_BYTE_ADDRESS * index + bit_no, 0)
    return ModbusPlace(rule.table, rule.base + rule.words * index, rule.words)


def table_size(table: Table) -> int:
    """Number of addresses OpenPLC answers in a table."""
    if table in (Table.COIL, Table.DISCRETE_INPUT):
        return BIT_TABLE_SIZE
    if table is Table.INPUT_REGISTER:
        return INPUT_REGISTER_TABLE_SIZE
    return HOLDING_TABLE_SIZE
