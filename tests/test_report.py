"""Reports: CSV trace, PNG, metrics.json (valid JSON, names with units), markdown/HTML summary."""

from __future__ import annotations

import asyncio
import csv
import json
from pathlib import Path

import pytest

from modbus_bridge.binding import ControllerCodes
from modbus_bridge.regmap import load_register_map
from modbus_bridge.report import summary_rows, text_table, write_reports
from modbus_bridge.runner import HarnessSetup, run_variants
from modbus_bridge.scenario import Variant, load_scenario

pytest.importorskip("plc.runtime.server", reason="the soft-PLC runtime is needed")

FIXTURES = Path(__file__).parent / "harness_fixtures"
PROGRAM = (FIXTURES / "p_harness_test.st").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def runs():
    sc = load_scenario(FIXTURES / "small_fopdt.toml")
    sc.variants = [Variant("PI fixed", fuzzy=False), Variant("PI again", fuzzy=False)]
    setup = HarnessSetup(regmap=load_register_map(sources=[("p.st", PROGRAM)]), codes=ControllerCodes.load(),
                         program=PROGRAM)
    return asyncio.run(run_variants(sc, setup))


def test_reports_are_written(tmp_path, runs):
    written = write_reports(runs, tmp_path)
    for key in ("metrics", "summary_md", "summary_html", "csv:pi_fixed", "png:pi_fixed", "png:pi_again"):
        assert written[key].exists() and written[key].stat().st_size > 0
    assert written["png:pi_fixed"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with written["csv:pi_fixed"].open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == runs[0][0].steps
    assert {"t_s", "pv_c", "setpoint_c", "output_pct", "kp", "tn"} <= set(rows[0])
    doc = json.loads(written["metrics"].read_text(encoding="utf-8"))  # strict JSON: no NaN
    assert [v["name"] for v in doc["variants"]] == ["PI fixed", "PI again"]
    phases = doc["variants"][0]["phases"]
    assert [(p["zone"], p["phase"]) for p in phases] == [("z1", "tune"), ("z1", "step"), ("z1", "load")]
    step = phases[1]["metrics"]
    assert step["overshoot_pct"] > 0 and "settling_time_2pct_s" in step and "iae_c_s" in step
    md = written["summary_md"].read_text(encoding="utf-8")
    assert "| PI fixed | PI again |" in md and "overshoot_pct" in md


def test_side_by_side_identical_variants_agree(runs):
    header, rows = summary_rows(runs)
    assert header[-2:] == ["PI fixed", "PI again"]
    for row in rows:
        assert row[-1] == row[-2], row  # stepped mode is deterministic
    assert "overshoot_pct" in text_table(header, rows)
