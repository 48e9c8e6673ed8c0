"""`thermost params save|load`: the parameter set of a PLC to a file and back, over Modbus; a value the PLC
refuses is reported (exit 1); a bad file is one line (exit 2)."""

from __future__ import annotations

import json

import pytest

from modbus_bridge.params import parameter_names
from modbus_bridge.regmap import load_register_map
from plc.cli import main


@pytest.fixture(scope="module")
def plc():
    from plc.bundle import bundle_text
    from plc.runtime.server import SoftPlcThread

    with SoftPlcThread(bundle_text(), stepped=True) as soft:
        with soft.engine.lock:
            soft.engine.step(2)  # a PLC that has been running: its parameters show their defaults
        yield f"127.0.0.1:{soft.port}"


def test_save_then_load_round_trip(plc, tmp_path, capsys):
    regmap = load_register_map()
    names = parameter_names(regmap)
    assert "fKpZone1" in names and "nModeZone1" not in names and "fSetpointZone1" not in names
    saved = tmp_path / "p.json"
    assert main(["params", "save", "--plc", plc, str(saved)]) == 0
    doc = json.loads(saved.read_text(encoding="utf-8"))
    assert set(doc["parameters"]) == set(names)
    doc["parameters"]["fKpZone1"]["value"] = 5.25  # a tuned value to bring back
    doc["parameters"]["fTnZone1"]["value"] = 61.5
    saved.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["params", "load", "--plc", plc, str(saved)]) == 0
    again = tmp_path / "again.json"
    assert main(["params", "save", "--plc", plc, str(again)]) == 0
    back = json.loads(again.read_text(encoding="utf-8"))["parameters"]
    assert back["fKpZone1"]["value"] == 5.25 and back["fTnZone1"]["value"] == 61.5
    capsys.readouterr()


def test_refused_value_is_reported(plc, tmp_path, capsys):
    saved = tmp_path / "p.json"
    assert main(["params", "save", "--plc", plc, str(saved)]) == 0
    doc = json.loads(saved.read_text(encoding="utf-8"))
    doc["parameters"]["fKpZone1"]["value"] = -5.0  # the PLC refuses a negative gain
    saved.write_text(json.dumps(doc), encoding="utf-8")
    capsys.readouterr()
    assert main(["params", "load", "--plc", plc, str(saved)]) == 1
    assert "refused: fKpZone1: wrote -5.0" in capsys.readouterr().out


HEAD = '{"format": "thermost parameters 1", "parameters": '
BAD_FILES = [
    "",
    "{",
    '{"format": "x"}',
    HEAD + '{"nope": {"value": 1}}}',
    HEAD + '{"nStateZone1": {"value": 1}}}',
    HEAD + '{"fKpZone1": {"value": "high"}}}',
]


@pytest.mark.parametrize("content", BAD_FILES)
def test_bad_file_is_one_line(plc, tmp_path, capsys, content):
    bad = tmp_path / "bad.json"
    bad.write_text(content, encoding="utf-8")
    assert main(["params", "load", "--plc", plc, str(bad)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
