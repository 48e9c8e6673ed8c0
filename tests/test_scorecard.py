"""`thermost scorecard`: the report's structure and its figures' consistency on a small scenario, bad
input, and the committed docs/scorecard.md block (structure only: its figures take a long run)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from modbus_bridge.scenario import load_scenario, resolve_scenario, shipped_scenarios
from modbus_bridge.scorecard.build import applicable
from modbus_bridge.scorecard.report import HEADER
from plc.cli import main

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "harness_fixtures" / "small_fopdt.toml"
HEADER_LINE = "| " + " | ".join(HEADER) + " |"


def _with_hold(tmp_path: Path) -> Path:
    """The small FOPDT scenario with a hold between tuning and the step, so the step is scored."""
    text = FIXTURE.read_text(encoding="utf-8").replace(
        '[[zone.phase]]\nname = "step"\nmode = "ACTIVE"',
        '[[zone.phase]]\nname = "hold"\nmode = "ACTIVE"\nduration_s = 20.0\n\n[[zone.phase]]\nname = "step"',
    )
    path = tmp_path / "small_hold.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _images(md: str) -> list[str]:
    return re.findall(r"^!\[[^\]]*\]\(([^)]+)\)$", md, flags=re.MULTILINE)


def _rows(md: str) -> dict[str, list[str]]:
    rows = {}
    for line in md.splitlines():
        if line.startswith("| ") and not line.startswith("| controller"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            rows[cells[0]] = cells
    return rows


def test_scorecard_report_on_a_small_scenario(tmp_path, capsys):
    scen = _with_hold(tmp_path)
    doc = tmp_path / "doc.md"
    doc.write_text(
        "# Doc\n\nprose stays\n\n<!-- figures:scorecard -->\nSTALE-BLOCK\n<!-- /figures:scorecard -->\n"
    )
    out = tmp_path / "out"
    args = ["scorecard", str(scen), "--evals", "4", "-o", str(out), "--markdown", str(doc), "--quiet"]
    assert main([*args, "--workers", "2"]) == 0
    md = (out / "scorecard.md").read_text(encoding="utf-8")
    assert HEADER_LINE in md and "setpoint step 70 → 70" not in md
    rows = _rows(md)
    names = list(rows)
    assert names[0] == "bound (bang-hold, true model)"
    assert names[1].startswith("best fixed PID (")
    assert {"SIMC (true model)", "AMIGO (true model)", "as written"} <= set(names)
    bound = float(rows[names[0]][1])
    assert 0.0 < bound < 40.0  # the step phase is 40 s long
    for name, cells in rows.items():
        settling, ratio = cells[1], cells[6]
        if settling not in ("–", "not settled") and name != names[0]:
            assert float(settling) >= bound - 0.1  # nothing beats the bound
            assert float(ratio) == pytest.approx(float(settling) / bound, abs=0.01)
    assert rows[names[1]][7] == "1.00"
    png = out / "scorecard_small_fopdt.png"
    assert png.stat().st_size > 10_000
    assert "<table>" in (out / "scorecard.html").read_text(encoding="utf-8")
    updated = doc.read_text(encoding="utf-8")
    assert "prose stays" in updated and "STALE-BLOCK" not in updated and HEADER_LINE in updated
    assert _images(updated) == ["img/scorecard_small_fopdt.png"]  # drawn beside the markdown file
    assert (tmp_path / "img" / "scorecard_small_fopdt.png").stat().st_size > 10_000
    assert "Produced by `thermost scorecard" in updated
    assert "best fixed PID" in capsys.readouterr().out


@pytest.mark.parametrize(("args", "why"), [(["--evals", "3"], "--evals"), (["nosuch"], "no such scenario")])
def test_bad_input_is_one_line(args, why, capsys):
    assert main(["scorecard", *args, "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and why in err


def test_fault_scenario_is_not_scored():
    assert "fault" in applicable(load_scenario(resolve_scenario("seed003_sensor_fault")))
    assert applicable(load_scenario(resolve_scenario("seed003_hotend_fuzzy"))) is None


def test_committed_docs_block_has_the_report_structure():
    text = (ROOT / "docs" / "scorecard.md").read_text(encoding="utf-8")
    m = re.search(r"<!-- figures:scorecard -->\n(.*?)<!-- /figures:scorecard -->", text, re.DOTALL)
    assert m, "docs/scorecard.md lost its figures block"
    block = m.group(1)
    assert block.startswith("Produced by `thermost scorecard")
    shipped = {p.stem for p in shipped_scenarios()}
    sections = re.split(r"^### ", block, flags=re.MULTILINE)[1:]
    assert sections, "the block has no scenario (regenerate it with the command it names)"
    for sec in sections:
        name = sec.splitlines()[0].strip()
        assert name in shipped
        if "Not scored:" in sec:
            continue
        assert HEADER_LINE in sec
        images = _images(sec)
        assert len(images) == 1, f"{name}: one figure of the traces, got {images}"
        assert (ROOT / "docs" / images[0]).is_file(), f"{name}: {images[0]} is missing"
        rows = _rows(sec)
        assert any(r.startswith("best fixed PID") for r in rows)
        if re.search(r"; setpoint step \S+ → ", sec):
            assert "bound (bang-hold, true model)" in rows


@pytest.fixture(scope="module")
def seed003_outcomes():
    """Every variant of the default scenario (seed 003, stepped; the run docs/fuzzy.md's figures come from),
    as the scorecard sees them: zone 1 from the scored step, and the Ms of a set on the true model."""
    pytest.importorskip("plc.runtime.server", reason="the soft-PLC runtime is needed")
    from modbus_bridge import docfigures
    from modbus_bridge.optimise.experiment import outcome_of
    from modbus_bridge.optimise.robustness import loop_model, scored_step

    runs = docfigures.default_run()
    sc = runs[0][0].scenario
    scored_from = scored_step(sc)[0]
    outcomes = {r.variant.name: (r.variant, outcome_of(r.variant.name, r, m, scored_from)) for r, m in runs}
    return outcomes, loop_model(sc).ms


def test_fuzzy_row_shows_the_worst_reachable_ms_not_the_base_sets(seed003_outcomes):
    from modbus_bridge.scorecard.build import _tuned_gains, variant_row
    from modbus_bridge.scorecard.report import row_cells

    outcomes, ms_of = seed003_outcomes
    variant, o = outcomes["fuzzy PID"]
    bound = next(m.values for m in o.scored_metrics() if "fuzzy_ms_reachable" in m.values)
    reachable, limit = bound["fuzzy_ms_reachable"], bound["fuzzy_ms_max"]
    base_ms = ms_of(_tuned_gains(o))
    assert base_ms > 4.0  # seed 003's Cohen-Coon set: the number the row must not show
    assert 1.0 < reachable <= limit * (1 + 1e-3) and bound["fuzzy_gain_scale"] < 1.0  # the bound acted
    row = variant_row(variant, o, ms_of)
    assert row.ms == pytest.approx(reachable) and abs(row.ms - base_ms) > 1.0
    cells = row_cells(row)
    assert cells[5] == f"{reachable:.2f} (worst reachable)"
    assert "base set" not in row.note and f"bound {limit:.3g}" in row.note
    assert f"base gains × {bound['fuzzy_gain_scale']:.3g}" in row.note
    assert "outside the search limits" not in row.note
    # the fixed PID keeps its own set's Ms, unlabelled
    pid_variant, pid = outcomes["PID (self-tuned)"]
    pid_row = variant_row(pid_variant, pid, ms_of)
    assert pid_row.ms == pytest.approx(base_ms) and row_cells(pid_row)[5] == f"{base_ms:.2f}"


def test_fuzzy_row_without_a_bound_says_it_shows_the_base_set(seed003_outcomes):
    import dataclasses

    from modbus_bridge.scorecard.build import variant_row
    from modbus_bridge.scorecard.report import row_cells

    outcomes, ms_of = seed003_outcomes
    variant, o = outcomes["fuzzy PID"]
    unbounded = [
        dataclasses.replace(m, values={k: v for k, v in m.values.items() if not k.startswith("fuzzy_")})
        for m in o.metrics
    ]
    row = variant_row(variant, dataclasses.replace(o, metrics=unbounded), ms_of)
    assert row_cells(row)[5].endswith("(base set)") and "no Ms bound in use" in row.note


def _ratio_defaults() -> tuple[float, float]:
    """The fuzzy adapter's configured ratio bounds: ST_FuzzyParameter's defaults, which the scenario keeps."""
    text = (ROOT / "st_lib" / "fuzzy" / "ST_FuzzyParameter.st").read_text(encoding="utf-8")
    lo, hi = (float(re.search(rf"fKpRatio{w} : REAL := ([0-9.]+);", text).group(1)) for w in ("Min", "Max"))
    return lo, hi


def test_the_figure_draws_the_gains_of_the_adapting_row_within_the_box_its_bound_kept(seed003_outcomes):
    """The gain panel: Kp and Ki in use over the base set, for the fuzzy row only, and inside the box the PLC
    reported (the base set scaled by the Ms bound, a share of the configured ratio bounds kept)."""
    from modbus_bridge.scorecard.build import variant_row
    from modbus_bridge.scorecard.figure import gain_ratios

    outcomes, ms_of = seed003_outcomes
    variant, o = outcomes["fuzzy PID"]
    bound = next(m.values for m in o.scored_metrics() if "fuzzy_box_share" in m.values)
    scale, share = bound["fuzzy_gain_scale"], bound["fuzzy_box_share"]
    lo, hi = _ratio_defaults()
    box = (scale * (1.0 + share * (lo - 1.0)), scale * (1.0 + share * (hi - 1.0)))
    g = gain_ratios(variant_row(variant, o, ms_of), "step")
    assert g is not None and g.ki is not None and g.t[0] == pytest.approx(0.0)
    for ratio in (g.kp, g.ki):
        assert box[0] * (1 - 1e-3) <= np.nanmin(ratio) and np.nanmax(ratio) <= box[1] * (1 + 1e-3)
    print(f"fuzzy PID, Kp / base {np.nanmin(g.kp):.3f} .. {np.nanmax(g.kp):.3f}, "
          f"box {box[0]:.3f} .. {box[1]:.3f}")
    for name in ("PID (self-tuned)", "model-based PID"):
        v, out = outcomes[name]
        assert gain_ratios(variant_row(v, out, ms_of), "step") is None  # fixed gains: no panel


def test_rows_are_judged_on_the_true_temperature_as_the_bound_is(seed003_outcomes):
    from modbus_bridge.scorecard.build import _row

    outcomes, ms_of = seed003_outcomes
    _, o = outcomes["PID (self-tuned)"]
    step = next(m.values for m in o.scored_metrics() if m.kind == "step")
    row = _row("PID", o, None, ms_of)
    assert row.settling_s == pytest.approx(step["true_settling_time_2pct_s"])
    assert row.overshoot_pct == pytest.approx(step["true_overshoot_pct"])


def test_the_bound_of_a_coupled_plant_holds_its_step_beside_the_other_heater():
    """TCLab's two heaters share a body: the holding power of heater 1 is the one that holds 60 degC while
    heater 2 keeps the input that held the start (both at the same input it would sit below the step)."""
    from modbus_bridge.plants.response import bang_hold_bound
    from modbus_bridge.scorecard.build import plant_model

    sc = load_scenario(resolve_scenario("t4_tclab"))
    y0, r = 45.0, 60.0
    b = bang_hold_bound(plant_model(sc), y0, r, sc.dt_s, 1500.0)
    assert 0.0 < b.switch_s < b.settling_s < 1500.0
    assert abs(b.y[-1] - r) < 0.02 * (r - y0)
    assert b.overshoot_pct < 2.0
