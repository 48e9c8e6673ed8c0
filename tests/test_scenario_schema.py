"""The published JSON Schema of scenario files (docs/scenario.schema.json) is what the code validates with,
and every plant kind of plants.PLANT_MODELS is in its discriminated union."""

from __future__ import annotations

import json
from pathlib import Path

from modbus_bridge.cli import schema_text
from modbus_bridge.plants import PLANT_MODELS
from modbus_bridge.scenario import shipped_scenarios

SCHEMA = Path(__file__).resolve().parents[1] / "docs" / "scenario.schema.json"


def test_published_schema_is_current():
    assert SCHEMA.read_text(encoding="utf-8") == schema_text(), (
        "docs/scenario.schema.json is stale: run `thermost scenarios --schema -o docs/scenario.schema.json` "
        "(or `make docs`)"
    )


def test_plant_union_covers_every_plant_kind():
    schema = json.loads(schema_text())
    mapping = schema["properties"]["plant"]["discriminator"]["mapping"]
    assert set(mapping) == set(PLANT_MODELS)


def test_shipped_scenarios_satisfy_the_schema_structure():
    """Shipped files use only keys the schema documents (a spot check without a JSON Schema library)."""
    import tomllib

    schema = json.loads(schema_text())
    top = set(schema["properties"])
    for path in shipped_scenarios():
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        assert set(data) <= top, path
