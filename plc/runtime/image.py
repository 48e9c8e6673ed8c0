"""Located memory of a PLC program seen as OpenPLC's four Modbus tables.

Like OpenPLC, a Modbus access goes straight to the located variables (between scans; the
caller holds the engine lock). Addresses with no located variable are a plain buffer:
they read 0 until written, and a write is kept. A write that covers only part of a
multi-word variable (one word of a %MD) keeps the other words, as OpenPLC does.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

from plc.runtime import codec
from plc.runtime.addressmap import ModbusError, ModbusPlace, Table, place_of, table_size

log = logging.getLogger("thermost.plc")


class LocatedLike(Protocol):
    """The attributes of `plc.st` LocatedVar this module uses."""

    name: str
    location: str
    area: str
    size: str
    index: int
    bit: int | None
    iec_type: str
    get: Callable[[], object]
    set: Callable[[object], None]


@dataclass
class Slot:
    """One located variable in a table: its place, type and accessors."""

    var: LocatedLike
    place: ModbusPlace
    info: codec.IecTypeInfo
    encoder: Callable[[object], tuple[int, ...]] | None = None

    def words(self) -> list[int]:
        if self.encoder is None:
            self.encoder = codec.word_encoder(self.info, self.place.n_words)
        return list(self.encoder(self.var.get()))

    def store_words(self, words: list[int]) -> None:
        self.var.set(codec.decode(words, self.info))


@dataclass(frozen=True)
class Unserved:
    """A located variable that no Modbus address reaches, and why."""

    location: str
    name: str
    reason: str


_LOCATION_BITS = {"X": 1, "W": 16, "D": 32, "L": 64}


def _check_type(size: str, info: codec.IecTypeInfo | None) -> str | None:
    if info is None:
        return "type is not an elementary Modbus-servable type"
    expected_bits = _LOCATION_BITS[size.upper()]
    if info.bits != expected_bits:
        return f"a {info.bits}-bit type in a {expected_bits}-bit location"
    return None


class ModbusImage:
    """Reads and writes of the four tables, backed by located variables and plain buffers."""

    def __init__(self, located: Sequence[LocatedLike]):
        self.unserved: list[Unserved] = []
        self._bit_slots: dict[Table, dict[int, Slot]] = {Table.COIL: {}, Table.DISCRETE_INPUT: {}}
        self._bit_buffers: dict[Table, bytearray] = {
            t: bytearray(table_size(t)) for t in (Table.COIL, Table.DISCRETE_INPUT)
        }
        # register address -> (slot, word offset inside the slot)
        self._reg_slots: dict[Table, dict[int, tuple[Slot, int]]] = {
            Table.HOLDING: {},
            Table.INPUT_REGISTER: {},
        }
        self._reg_buffers: dict[Table, list[int]] = {
            t: [0] * table_size(t) for t in (Table.HOLDING, Table.INPUT_REGISTER)
        }
        for var in located:
            self._add(var)
        for item in self.unserved:
            log.warning("%s (%s) is not served over Modbus: %s", item.location, item.name, item.reason)

    def _add(self, var: LocatedLike) -> None:
        place = place_of(var.area, var.size, var.index, var.bit)
        if isinstance(place, str):
            self.unserved.append(Unserved(var.location, var.name, place))
            return
        info = codec.type_info(var.iec_type)
        problem = _check_type(var.size, info)
        if problem is not None or info is None:
            self.unserved.append(Unserved(var.location, var.name, problem or "unknown type"))
            return
        slot = Slot(var, place, info)
        if place.n_words == 0:
            self._bit_slots[place.table][place.address] = slot
            return
        for offset in range(place.n_words):
            self._reg_slots[place.table][place.address + offset] = (slot, offset)

    def slots(self) -> list[Slot]:
        """Every served located variable (for documentation and tests)."""
        found = {id(s): s for s in self._bit_slots[Table.COIL].values()}
        found.update({id(s): s for s in self._bit_slots[Table.DISCRETE_INPUT].values()})
        for table in (Table.HOLDING, Table.INPUT_REGISTER):
            found.update({id(slot): slot for slot, _ in self._reg_slots[table].values()})
        return list(found.values())

    @staticmethod
    def _in_range(table: Table, address: int, count: int) -> bool:
        return count >= 1 and address >= 0 and address + count <= table_size(table)

    def read_bits(self, table: Table, address: int, count: int) -> list[bool] | ModbusError:
        if not self._in_range(table, address, count):
            return ModbusError.ILLEGAL_ADDRESS
        slots = self._bit_slots[table]
        buffer = self._bit_buffers[table]
        out: list[bool] = []
        for addr in range(address, address + count):
            slot = slots.get(addr)
            out.append(bool(slot.var.get()) if slot is not None else bool(buffer[addr]))
        return out

    def write_bits(self, table: Table, address: int, values: Sequence[bool]) -> ModbusError | None:
        if table is not Table.COIL:
            return ModbusError.ILLEGAL_FUNCTION
        if not self._in_range(table, address, len(values)):
            return ModbusError.ILLEGAL_ADDRESS
        slots = self._bit_slots[table]
        buffer = self._bit_buffers[table]
        for addr, value in zip(range(address, address + len(values)), values, strict=True):
            slot = slots.get(addr)
            if slot is not None:
                slot.var.set(bool(value))
            else:
                buffer[addr] = 1 if value else 0
        return None

    def read_registers(self, table: Table, address: int, count: int) -> list[int] | ModbusError:
        if not self._in_range(table, address, count):
            return ModbusError.ILLEGAL_ADDRESS
        slots = self._reg_slots[table]
        buffer = self._reg_buffers[table]
        out: list[int] = []
        addr, end = address, address + count
        while addr < end:
            entry = slots.get(addr)
            if entry is None:
                out.append(buffer[addr])
                addr += 1
                continue
            slot, offset = entry
            take = min(slot.place.n_words - offset, end - addr)
            out += slot.words()[offset : offset + take]
            addr += take
        return out

    def write_registers(self, table: Table, address: int, values: Sequence[int]) -> ModbusError | None:
        if table is not Table.HOLDING:
            return ModbusError.ILLEGAL_FUNCTION
        if not self._in_range(table, address, len(values)):
            return ModbusError.ILLEGAL_ADDRESS
        if any(not 0 <= v <= codec.WORD_MASK for v in values):
            return ModbusError.ILLEGAL_VALUE
        slots = self._reg_slots[table]
        buffer = self._reg_buffers[table]
        pending: dict[int, tuple[Slot, list[int]]] = {}
        for addr, value in zip(range(address, address + len(values)), values, strict=True):
            entry = slots.get(addr)
            if entry is None:
                buffer[addr] = value
                continue
            slot, offset = entry
            if id(slot) not in pending:
                pending[id(slot)] = (slot, slot.words())
            pending[id(slot)][1][offset] = value
        for slot, words in pending.values():
            slot.store_words(words)
        return None
