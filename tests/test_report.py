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


def test_summary_starts_with_the_verdict(tmp_path, runs):
    import dataclasses

    from modbus_bridge.scenario import Target

    sc = runs[0][0].scenario
    targets = [Target(phase="step", metric="overshoot_pct", paper=1e9, goal=1e9),  # surely met
               Target(phase="step", metric="overshoot_pct", paper=0.0, goal=0.0)]  # surely missed
    judged = [(dataclasses.replace(r, scenario=dataclasses.replace(sc, targets=targets)), m) for r, m in runs]
    written = write_reports(judged, tmp_path, command="thermost run x.toml")
    md = written["summary_md"].read_text(encoding="utf-8").splitlines()
    verdict_at = md.index("## Verdict")
    assert verdict_at < md.index("## All metrics") and verdict_at <= 4  # right after the title
    table = [line for line in md[verdict_at:md.index("## Variants compared")] if line.startswith("| PI")]
    # identification is judged only for plants with known parameters (fopdt: yes) - here the fixture
    # "tunes" without identifying, so only the two targets per variant are judged
    assert [line.split("|")[-2].strip() for line in table] == ["pass", "FAIL", "pass", "FAIL"]
    text = "\n".join(md)
    assert "`thermost run x.toml`" in text and "tool: thermost" in text and "date: " in text
    assert "plant: fopdt gain_c_per_pct = 1.0" in text
    assert written["png:compare"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    html = written["summary_html"].read_text(encoding="utf-8")
    assert html.index("Verdict") < html.index("All metrics") and "class='FAIL'" in html
    doc = json.loads(written["metrics"].read_text(encoding="utf-8"))
    assert [v["verdict"] for v in doc["verdict"]] == ["pass", "FAIL", "pass", "FAIL"]


def test_partial_report_says_so(tmp_path, runs):
    import dataclasses

    cut = [(dataclasses.replace(runs[0][0], error="interrupted by SIGINT", interrupted=True), runs[0][1])]
    written = write_reports(cut, tmp_path)
    md = written["summary_md"].read_text(encoding="utf-8").splitlines()
    assert md[2].startswith("> **PARTIAL REPORT**") and "interrupted by SIGINT" in md[2]
    assert json.loads(written["metrics"].read_text(encoding="utf-8"))["complete"] is False
