"""Alarm bit names and texts: one source (the FB_CtrlAlarms header), the docs table generated from it."""

from __future__ import annotations

import re
from pathlib import Path

from modbus_bridge.alarms import ALARMS_ST, DOCS_BEGIN, DOCS_END, alarm_bits, describe, markdown_table

DOC = Path(__file__).resolve().parents[1] / "docs" / "library.md"


def test_every_dword_constant_of_the_alarm_block_has_a_text():
    source = ALARMS_ST.read_text()
    masks = {int(m, 16) for m in re.findall(r"dw\w+ : DWORD := 16#([0-9A-F]{8});", source)} - {0}
    documented = {b.mask for b in alarm_bits().values()}
    assert masks <= documented, f"bits without a text: {[hex(m) for m in masks - documented]}"
    names = [b.name for b in alarm_bits().values()]
    assert len(names) == len(set(names))


def test_monitor_and_watchdog_bits_have_their_own_texts():
    bits = alarm_bits()
    for name, bit in (("heater_open", 18), ("sensor_detached", 19), ("stuck_on", 20), ("pv_frozen", 21),
                      ("pv_stale", 22)):
        assert bits[name].bit == bit
    assert describe((1 << 18) | 1) == [bits["sensor_open"].text, bits["heater_open"].text]


def test_docs_table_is_generated_from_the_source():
    text = DOC.read_text(encoding="utf-8")
    block = text.split(DOCS_BEGIN, 1)[1].split(DOCS_END, 1)[0].strip()
    assert block == markdown_table(), "run `python -m modbus_bridge.alarms --markdown` into docs/library.md"


def test_harness_unlock_key_is_the_applications():
    from modbus_bridge.binding import UNLOCK_KEY

    gen = (Path(__file__).resolve().parents[1] / "plc" / "app" / "gen_application.py").read_text()
    m = re.search(r"nUnlockKeyValue : DINT := 16#([0-9A-F]+);", gen)
    assert m and int(m.group(1), 16) == UNLOCK_KEY
