"""`thermost regmap --format ...`: the exports carry the map and its metadata, and decode correctly."""

from __future__ import annotations

import csv
import io
import json
import shutil
import subprocess

import pytest
from pymodbus.client import AsyncModbusTcpClient

from modbus_bridge.regmap import COIL, HOLDING, load_register_map
from modbus_bridge.regmap_export import COLUMNS, ExportOptions, export, node_red_decoder, rows


@pytest.fixture(scope="module")
def regmap():
    return load_register_map()


def test_csv_has_every_tag_and_column(regmap) -> None:
    data = list(csv.DictReader(io.StringIO(export(regmap, "csv"))))
    assert [c for c in data[0]] == list(COLUMNS)
    assert {r["tag"] for r in data} == set(regmap.tags)
    pv = next(r for r in data if r["tag"] == "fPvZone1")
    assert (pv["table"], pv["address"], pv["address_1based"], pv["data_type"]) == (HOLDING, "2048", "2049",
                                                                                   "Float32")
    assert pv["word_order"] == "high word first"
    state = next(r for r in data if r["tag"] == "nStateZone1")
    assert state["access"] == "read" and state["hmi_level"] == "none"  # PLC-owned status
    assert "ACTIVE" in state["enum"]
    ack = next(r for r in data if r["tag"] == "bAckZone1")
    assert ack["access"] == "self-resetting command" and ack["hmi_level"] == "operator"
    kp = next(r for r in data if r["tag"] == "fKpZone1")
    assert kp["hmi_level"] == "engineer" and kp["unit"] == "%/degC" and kp["min"] == "0.0"
    alarm = next(r for r in data if r["tag"] == "dwAlarmZone1")
    assert "0=sensor open" in alarm["alarm_bits"]


def test_json_matches_csv(regmap) -> None:
    doc = json.loads(export(regmap, "json"))
    assert len(doc["tags"]) == len(regmap.tags)
    assert doc["tags"] == rows(regmap)


def test_fuxa_csv_follows_its_import_format(regmap) -> None:
    text = export(regmap, "fuxa", ExportOptions(host="10.0.0.5", port=502))
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    headers = [ln.split(",")[1:] for ln in lines if ln.startswith("@header")]
    assert headers[0][:4] == ["id", "name", "enabled", "type"] and headers[1][0] == "deviceId"
    device = next(ln for ln in lines if ln.startswith("D@")).split(",")[1:]
    dev = dict(zip(headers[0], device, strict=True))
    assert (dev["type"], dev["property.address"], dev["property.port"]) == ("ModbusTCP", "10.0.0.5", "502")
    tags = {}
    for ln in lines:
        if ln.startswith("T@"):
            cells = ln.split(",")[1:]
            assert len(cells) == len(headers[1]), ln  # a comma inside a value would break the row
            tags[cells[2]] = dict(zip(headers[1], cells, strict=True))
    assert set(tags) == set(regmap.tags)
    assert (tags["fPvZone1"]["memaddress"], tags["fPvZone1"]["address"], tags["fPvZone1"]["type"]) == (
        "400000", "2049", "Float32")
    assert (tags["bAckZone1"]["memaddress"], tags["bAckZone1"]["address"]) == ("000000", "4")
    assert tags["dwAlarmZone1"]["type"] == "UInt32"


def test_node_red_flow_reads_zone_blocks(regmap) -> None:
    flow = json.loads(export(regmap, "node-red"))
    readers = [n for n in flow if n["type"] == "modbus-read"]
    assert readers and all(int(n["quantity"]) <= 125 or n["dataType"] == "Coil" for n in readers)
    covered = set()
    for n in readers:
        fn = next(f for f in flow if f["id"] == n["wires"][0][0])
        assert fn["type"] == "function"
        covered |= set(json.loads("[" + ",".join(
            line.split("[", 1)[1].split("]", 1)[0] for line in fn["func"].splitlines()
            if line.startswith("out[")) + "]"))
    zone_tags = {t.name for t in regmap.tags.values()
                 if t.meta.zone is not None and t.table in (HOLDING, COIL)}
    assert covered == zone_tags
    client = next(n for n in flow if n["type"] == "modbus-client")
    assert (client["tcpHost"], client["tcpPort"]) == ("127.0.0.1", "5020")


def test_node_red_decoder_decodes_openplc_words(regmap) -> None:
    """Run the generated function body in node with the words OpenPLC would send."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed: the generated JavaScript decoder is not executed")
    tags = [regmap[n] for n in ("fPvZone1", "fSetpointZone1", "dwAlarmZone1")]
    start = tags[0].address
    words = [0] * (tags[-1].address + 2 - start)
    values = {"fPvZone1": 123.5, "fSetpointZone1": -40.25, "dwAlarmZone1": 0x80010041}
    dt = AsyncModbusTcpClient.DATATYPE
    for t in tags:
        kind = dt.FLOAT32 if t.iec_type == "REAL" else dt.UINT32
        regs = AsyncModbusTcpClient.convert_to_registers(values[t.name], kind, word_order="big")
        words[t.address - start: t.address - start + 2] = regs
    script = "\n".join((f"const msg = {{payload: {json.dumps(words)}}};", "const f = () => {",
                        node_red_decoder(tags, start), "};",
                        "process.stdout.write(JSON.stringify(f().payload));"))
    out = subprocess.run([node, "-e", script], capture_output=True, text=True, timeout=30, check=True)
    assert json.loads(out.stdout) == values


def test_cli_refuses_unknown_format_and_bad_plc(tmp_path) -> None:
    from plc.cli import main

    assert main(["regmap", "--format", "fuxa", "--plc", "nope"]) == 2
    target = tmp_path / "map.csv"
    assert main(["regmap", "--format", "csv", "-o", str(target)]) == 0
    assert target.read_text().startswith("tag,zone,")
