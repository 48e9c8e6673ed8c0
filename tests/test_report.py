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


def test_report_shows_the_measured_noise_the_tuned_filter_and_the_fuzzy_bound(tmp_path):
    """Seed 003 on the application (the default run docs/fuzzy.md's figures come from): what TUNE measured
    and sized, and the fuzzy adapter's Ms bound, read over Modbus, reach metrics.json and summary.md."""
    from modbus_bridge import docfigures

    runs = docfigures.default_run()
    by_name = {r.variant.name: {pm.phase: pm for pm in pms} for r, pms in runs}
    tune = by_name["fuzzy PID"]["tune"].values
    assert 0.0 < tune["identified_noise_pp_c"] < 1.0  # 12-bit NTC at 200 degC: about one count, 0.12 degC
    # a new reading every control cycle (0.1 s) at most, held longer where the NTC's count repeats
    assert tune["identified_noise_interval_s"] >= 0.1 * (1 - 1e-3)
    assert tune["tuned_filter_s"] >= 0.0 and tune["tuned_ms"] > 1.0
    assert 0.0 < tune["identified_fit_rms_pct"] < 5.0  # a first-order plant: its model follows the record
    for phase in ("step", "load"):  # the adapter runs; its bound holds at the cost of scale and box
        v = by_name["fuzzy PID"][phase].values
        assert 1.0 < v["fuzzy_ms_reachable"] <= v["fuzzy_ms_max"] * (1 + 1e-3)
        assert 0.0 < v["fuzzy_gain_scale"] < 1.0 and 0.0 < v["fuzzy_box_share"] <= 1.0
    assert not any(k.startswith("fuzzy_") for pm in by_name["PID (self-tuned)"].values() for k in pm.values)

    written = write_reports(runs, tmp_path)
    doc = json.loads(written["metrics"].read_text(encoding="utf-8"))
    fuzzy_phases = {p["phase"]: p["metrics"] for p in doc["variants"][0]["phases"]}
    assert fuzzy_phases["tune"]["identified_noise_pp_c"] == pytest.approx(tune["identified_noise_pp_c"])
    step = by_name["fuzzy PID"]["step"].values
    assert fuzzy_phases["step"]["fuzzy_ms_reachable"] == pytest.approx(step["fuzzy_ms_reachable"])
    md = written["summary_md"].read_text(encoding="utf-8")
    tuned_header = next(line for line in md.splitlines() if line.startswith("| variant | zone | phase | Ks"))
    assert "noise p-p (°C)" in tuned_header and "filter (s)" in tuned_header and "| Ms |" in tuned_header
    assert "fit rms (% of rise)" in tuned_header
    assert "noise held (s)" in tuned_header
    assert (f"| {tune['identified_noise_pp_c']:.4g} | {tune['identified_noise_interval_s']:.4g} | "
            f"{tune['tuned_filter_s']:.4g} |") in md
    section = md[md.index("## Fuzzy adapter: Ms over the gain sets it can reach"):md.index("## All metrics")]
    assert (f"| fuzzy PID | nozzle | step | {step['fuzzy_ms_reachable']:.4g} | {step['fuzzy_ms_max']:.3g} | "
            f"{step['fuzzy_gain_scale']:.3g} | {100 * step['fuzzy_box_share']:.0f} % |") in section
    assert "PID (self-tuned)" not in section
    for key in ("identified_noise_pp_c", "identified_noise_interval_s", "identified_fit_rms_pct",
                "tuned_filter_s", "tuned_ms", "fuzzy_ms_reachable", "fuzzy_gain_scale", "fuzzy_box_share"):
        assert f"| {key} |" in md  # the side-by-side table of every metric


def test_a_cooling_zone_s_plot_draws_the_cooling_set_it_ran_on() -> None:
    from modbus_bridge.loop import ZoneTrace
    from modbus_bridge.plots import gain_lines

    gains = {"kp": [10.0, 10.0], "kp_eff": [10.0, 10.0], "kp_cool": [34.6, 30.1], "tn": [150.0, 150.0],
             "tn_cool": [465.0, 400.0]}
    cooling = ZoneTrace("platform", 2, t=[0.0, 1.0], u=[-50.0, -40.0], gains=gains)
    kp_axis, tn_axis = gain_lines(cooling)
    assert ("kp_cool", "Kp, cooling") in kp_axis and ("kp", "Kp, heating") in kp_axis
    assert ("tn_cool", "Tn, cooling") in tn_axis
    assert ("kp_eff", "Kp in use") in kp_axis  # the set the PID ran on, whichever side that was
    heating = ZoneTrace("nozzle", 1, t=[0.0, 1.0], u=[50.0, 40.0], gains=gains)
    kp_axis, _ = gain_lines(heating)
    assert kp_axis == [("kp", "Kp"), ("kp_eff", "Kp in use")]
