"""OpenPLC's Modbus map over located memory: codec, addresses, partial writes, plain buffers."""

from __future__ import annotations

import math
import struct

import pytest

from plc.runtime import codec
from plc.runtime.addressmap import ModbusError, Table, place_of
from plc.runtime.image import ModbusImage
from tests.test_runtime_fake import FakeApplication


def real_words(value: float) -> list[int]:
    return list(struct.unpack(">HH", struct.pack(">f", value)))


def test_reference_example_real_2_5_in_md1():
    # reference/openplc.md: REAL 2.5 in %MD1 reads as holding 2050..2051 = [0x4020, 0x0000]
    app = FakeApplication()
    app.values["in_real"] = 2.5
    assert ModbusImage(app.located).read_registers(Table.HOLDING, 2050, 2) == [0x4020, 0x0000]


@pytest.mark.parametrize(
    ("area", "size", "index", "bit", "table", "address"),
    [
        ("I", "X", 0, 3, Table.DISCRETE_INPUT, 3),
        ("Q", "X", 1, 2, Table.COIL, 10),
        ("Q", "X", 1023, 7, Table.COIL, 8191),
        ("I", "W", 5, None, Table.INPUT_REGISTER, 5),
        ("Q", "W", 1023, None, Table.HOLDING, 1023),
        ("M", "W", 0, None, Table.HOLDING, 1024),
        ("M", "D", 3, None, Table.HOLDING, 2054),
        ("M", "L", 1, None, Table.HOLDING, 4100),
        ("M", "L", 1023, None, Table.HOLDING, 8188),
    ],
)
def test_openplc_address_map(area, size, index, bit, table, address):
    place = place_of(area, size, index, bit)
    assert not isinstance(place, str)
    assert (place.table, place.address) == (table, address)


@pytest.mark.parametrize(
    ("area", "size", "index"), [("M", "X", 0), ("I", "B", 0), ("Q", "D", 0), ("M", "W", 1024)]
)
def test_locations_outside_the_map_are_reported(area, size, index):
    assert isinstance(place_of(area, size, index, 0), str)


def test_unserved_located_variable_is_listed():
    image = ModbusImage(FakeApplication().located)
    assert [u.location for u in image.unserved] == ["%IB0"]


def test_values_of_every_width_and_signedness():
    app = FakeApplication()
    image = ModbusImage(app.located)
    app.values.update(cnt=-2, ud=4000000000, big=-5, lr=2.5, in_int=-1)
    assert image.read_registers(Table.HOLDING, 2048, 2) == [0xFFFF, 0xFFFE]
    assert image.read_registers(Table.HOLDING, 2058, 2) == list(divmod(4000000000, 0x10000))
    assert image.read_registers(Table.HOLDING, 4104, 4) == [0xFFFF, 0xFFFF, 0xFFFF, 0xFFFB]
    lreal_bits = struct.unpack(">Q", struct.pack(">d", 2.5))[0]
    assert image.read_registers(Table.HOLDING, 4108, 4) == codec.int_to_words(lreal_bits, 4)
    assert image.read_registers(Table.HOLDING, 1024, 1) == [0xFFFF]
    assert image.read_registers(Table.HOLDING, 0, 1) == [0xBEEF]
    assert image.read_registers(Table.INPUT_REGISTER, 5, 1) == [0xFFFE]
    assert image.read_bits(Table.DISCRETE_INPUT, 0, 4) == [False, False, False, True]


def test_writes_reach_located_variables_with_types():
    app = FakeApplication()
    image = ModbusImage(app.located)
    assert image.write_registers(Table.HOLDING, 2050, real_words(-0.0)) is None
    assert math.copysign(1.0, app.values["in_real"]) == -1.0
    assert image.write_registers(Table.HOLDING, 1024, [0x8000]) is None
    assert app.values["in_int"] == -32768
    assert image.write_registers(Table.HOLDING, 4104, [0x8000, 0, 0, 0]) is None
    assert app.values["big"] == -(2**63)
    assert image.write_bits(Table.COIL, 10, [True]) is None
    assert app.values["q_copy"] is True


def test_partial_write_of_a_dword_keeps_the_other_word():
    app = FakeApplication()
    image = ModbusImage(app.located)
    app.values["in_real"] = 2.5  # 0x4020_0000
    assert image.write_registers(Table.HOLDING, 2051, [0x0001]) is None  # low word only
    assert image.read_registers(Table.HOLDING, 2050, 2) == [0x4020, 0x0001]
    assert app.values["in_real"] == struct.unpack(">f", bytes.fromhex("40200001"))[0]
    assert image.write_registers(Table.HOLDING, 2049, [0x1234, 0x3F80]) is None  # straddles cnt and in_real
    assert app.values["cnt"] & 0xFFFF == 0x1234
    assert image.read_registers(Table.HOLDING, 2050, 2) == [0x3F80, 0x0001]


def test_unmapped_addresses_read_zero_and_keep_writes():
    image = ModbusImage(FakeApplication().located)
    assert image.read_registers(Table.HOLDING, 3000, 3) == [0, 0, 0]
    assert image.write_registers(Table.HOLDING, 3000, [7, 8, 9]) is None
    assert image.read_registers(Table.HOLDING, 2999, 4) == [0, 7, 8, 9]
    assert image.write_bits(Table.COIL, 100, [True, False, True]) is None
    assert image.read_bits(Table.COIL, 100, 3) == [True, False, True]


@pytest.mark.parametrize(
    ("table", "address", "count"),
    [(Table.INPUT_REGISTER, 1024, 1), (Table.INPUT_REGISTER, 1023, 2), (Table.HOLDING, 8192, 1),
     (Table.HOLDING, 8190, 3), (Table.COIL, 8192, 1), (Table.DISCRETE_INPUT, 8191, 2)],
)
def test_addresses_outside_openplc_tables_are_illegal(table, address, count):
    image = ModbusImage(FakeApplication().located)
    reader = image.read_bits if table in (Table.COIL, Table.DISCRETE_INPUT) else image.read_registers
    assert reader(table, address, count) is ModbusError.ILLEGAL_ADDRESS


def test_inputs_are_read_only():
    image = ModbusImage(FakeApplication().located)
    assert image.write_registers(Table.INPUT_REGISTER, 5, [1]) is ModbusError.ILLEGAL_FUNCTION
    assert image.write_bits(Table.DISCRETE_INPUT, 3, [False]) is ModbusError.ILLEGAL_FUNCTION


def test_codec_round_trips_and_wraps():
    info = codec.type_info("INT")
    assert info is not None
    assert codec.decode(codec.encode(-300, info, 1), info) == -300
    assert codec.decode([0xFFFF], codec.IEC_TYPES["UINT"]) == 65535
    assert codec.words_to_text(codec.text_to_words("division by zero", 8)) == "division by zero"
    assert codec.text_to_words("abc", 2) == [0x6162, 0x6300]


@pytest.mark.parametrize(
    ("iec_type", "n_words", "value"),
    [("REAL", 2, -(2.0**-140)), ("REAL", 2, float("inf")), ("LREAL", 4, -0.1), ("DINT", 2, -2147483648),
     ("UDINT", 2, 4294967295), ("INT", 1, -1), ("WORD", 1, 0xABCD), ("LINT", 4, -(2**63)),
     ("ULINT", 4, 2**64 - 1)],
)
def test_fast_encoder_matches_the_reference_codec(iec_type, n_words, value):
    info = codec.IEC_TYPES[iec_type]
    words = list(codec.word_encoder(info, n_words)(value))
    assert words == codec.encode(value, info, n_words)
    assert codec.decode(words, info) == value
