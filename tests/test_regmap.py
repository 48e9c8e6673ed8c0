"""Register map: OpenPLC's address mapping, parsing of located variables, the generated document."""

from __future__ import annotations

from pathlib import Path

import pytest

from modbus_bridge.client import decode, encode
from modbus_bridge.regmap import (
    APP_DIR,
    COIL,
    DISCRETE,
    HOLDING,
    INPUT,
    RegisterMapError,
    load_register_map,
    markdown,
    modbus_address,
)

FIXTURES = Path(__file__).parent / "harness_fixtures"
PROGRAM = (FIXTURES / "p_harness_test.st").read_text(encoding="utf-8")
DOC = Path(__file__).resolve().parents[1] / "docs" / "register-map.md"


@pytest.mark.parametrize(
    ("area", "size", "index", "bit", "expected"),
    [
        ("I", "X", 2, 3, (DISCRETE, 19, False)),
        ("Q", "X", 1, 2, (COIL, 10, True)),
        ("I", "W", 7, None, (INPUT, 7, False)),
        ("Q", "W", 7, None, (HOLDING, 7, True)),
        ("M", "W", 7, None, (HOLDING, 1031, True)),
        ("M", "D", 1, None, (HOLDING, 2050, True)),
        ("M", "L", 2, None, (HOLDING, 4104, True)),
        ("I", "D", 0, None, None),
    ],
)
def test_openplc_address_mapping(area, size, index, bit, expected):
    assert modbus_address(area, size, index, bit) == expected


def test_fixture_program_located_variables():
    rm = load_register_map(sources=[("p_harness_test.st", PROGRAM)])
    pv = rm["fPvZone1"]
    assert (pv.table, pv.address, pv.words, pv.iec_type) == (HOLDING, 2048 + 20, 2, "REAL")
    assert pv.comment == "process value zone 1, degC"
    assert rm["nModeZone1"].address == 1024
    assert (rm["bPwmHeatZone1"].table, rm["bPwmHeatZone1"].address) == (COIL, 1)
    assert "fI" not in rm  # ordinary variables are not in the map
    with pytest.raises(RegisterMapError, match="not in the register map"):
        rm["fNope"]


def test_real_word_order_is_high_word_first():
    rm = load_register_map(sources=[("p_harness_test.st", PROGRAM)])
    assert encode(rm["fPvZone1"], 2.5) == [0x4020, 0x0000]  # openplc.md example
    assert decode(rm["fPvZone1"], [0x4020, 0x0000]) == 2.5
    assert encode(rm["nModeZone1"], -1) == [0xFFFF]
    with pytest.raises(ValueError, match="does not fit INT"):
        encode(rm["nModeZone1"], 40000)


def test_overlap_and_type_mismatch_are_refused():
    overlap = PROGRAM.replace("fYZone1 AT %MD12", "fYZone1 AT %MD11")
    with pytest.raises(RegisterMapError, match="overlaps"):
        load_register_map(sources=[("x.st", overlap)])
    wrong = PROGRAM.replace("nModeZone1 AT %MW0 : INT", "nModeZone1 AT %MW0 : REAL")
    with pytest.raises(RegisterMapError, match="cannot sit at %MW0"):
        load_register_map(sources=[("x.st", wrong)])


def test_markdown_lists_every_tag():
    rm = load_register_map(sources=[("p_harness_test.st", PROGRAM)])
    md = markdown(rm)
    for name in rm.tags:
        assert f"`{name}`" in md


def test_committed_register_map_document_is_up_to_date():
    if not list(APP_DIR.glob("*.st")):
        pytest.skip(f"no application in {APP_DIR} yet: nothing to compare docs/register-map.md with")
    expected = markdown(load_register_map())
    fix = "run `thermost regmap --markdown -o docs/register-map.md`"
    assert DOC.exists(), f"docs/register-map.md missing: {fix}"
    assert DOC.read_text(encoding="utf-8") == expected, f"docs/register-map.md is stale: {fix}"


def test_every_application_register_carries_metadata() -> None:
    from modbus_bridge.regmap import OWNERS, load_register_map

    regmap = load_register_map()
    for tag in regmap.tags.values():
        assert tag.meta.owner in OWNERS, tag.name
        assert "{" not in tag.comment, tag.name
        if tag.meta.owner == "client" and tag.iec_type == "REAL" and tag.name.startswith(("fK", "fT", "fY")):
            assert tag.meta.default is not None, tag.name
    kp1, kp2 = regmap["fKpZone1"].meta, regmap["fKpZone2"].meta
    assert (kp1.unit, kp1.min, kp1.default, kp1.zone) == ("%/degC", 0.0, 3.7, 1)
    assert kp2.default == 10.0 and kp2.zone == 2
    assert regmap["nStateZone1"].meta.owner == "plc"
    assert regmap["nModeZone1"].meta.enum[2] == "ACTIVE"
    assert regmap["bAckZone1"].meta.owner == "command"
    assert regmap["fPvZone1"].meta.owner == "input"


def test_bad_metadata_names_the_register() -> None:
    from modbus_bridge.regmap import RegisterMapError, parse_meta

    with pytest.raises(RegisterMapError, match=r"P.st:3: fKp: bad metadata 'min=abc'"):
        parse_meta("gain {unit=%; min=abc}", "fKp", "P.st:3")
    with pytest.raises(RegisterMapError, match="owner must be one of"):
        parse_meta("gain {owner=nobody}", "fKp", "P.st:3")
    text, meta = parse_meta("gain {unit=%; min=-1; enum=0:A,1:B; owner=plc}", "fKpZone2", "P.st:3")
    assert text == "gain" and meta.min == -1.0 and meta.enum == {0: "A", 1: "B"} and meta.zone == 2
