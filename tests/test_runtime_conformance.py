"""Every conformance case read over Modbus gives the same words as reading the located
variables in-process (so the soft-PLC's map serves exactly what the interpreter computed),
and for `exact` results whose in-process words match the OpenPLC recording, Modbus does too."""

from __future__ import annotations

import json

import pytest

from plc.bench import conformance_dir
from plc.runtime.rawclient import RawModbusClient
from plc.runtime.server import SoftPlcThread
from plc.st.compiler import load_application
from plc.st.words import to_words

FOLDER = conformance_dir()
CASES = sorted(p.name.removesuffix(".st") for p in FOLDER.glob("*.st")) if FOLDER else []


def read_result(client: RawModbusClient, modbus: dict) -> list[int]:
    if modbus["table"] == "coil":
        return [int(b) for b in client.read_coils(modbus["address"], modbus["count"])]
    return client.read_holding(modbus["address"], modbus["count"])


@pytest.mark.skipif(FOLDER is None, reason="conformance corpus not found (THERMOST_SHARED or ../shared)")
@pytest.mark.parametrize("case", CASES)
def test_conformance_case_over_modbus_matches_in_process(case):
    assert FOLDER is not None
    path = FOLDER / f"{case}.st"
    expected = json.loads((FOLDER / f"{case}.expected.json").read_text())
    reference = load_application([(str(path), path.read_text())])
    for _ in range(expected["scans"]):
        reference.scan()
    by_location = {v.location: v for v in reference.located}
    oracle_hits = 0
    with SoftPlcThread(path, stepped=True) as plc, RawModbusClient("127.0.0.1", plc.port) as client:
        client.step(expected["scans"])
        assert client.status().scan_count == expected["scans"]
        done_flag = {**expected["done_flag"], "iec_type": "BOOL", "raw": [1]}
        for result in [*expected["results"], done_flag]:
            modbus = result["modbus"]
            var = by_location[result["location"]]
            in_process = to_words(var.get(), result["iec_type"], modbus["count"])
            over_modbus = read_result(client, modbus)
            assert over_modbus == in_process, result["var"]
            oracle_hits += result.get("raw") == over_modbus
    assert oracle_hits > 0
