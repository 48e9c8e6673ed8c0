"""Figures of docs/fuzzy.md (registered in `docfigures.PRODUCERS` when that module is imported).

The verification figures come from the computations the fuzzy tests assert on (tests/test_fuzzy_*.py),
cached there, so a test session pays for each once; the oracle needs the dev extra (scikit-fuzzy).
The scan cost is measured (`measured=True`): `make docs` rewrites it, the test only checks it is filled.
"""

from __future__ import annotations

import re

import numpy as np

from .docfigures import ROOT, _phase, adapter_cost_rows, default_run, producer, tests_on_path

SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _oracle_available() -> None:
    import importlib.util

    from plc.cli import UserError

    if importlib.util.find_spec("skfuzzy") is None:
        raise UserError("the fuzzy verification figures need scikit-fuzzy (pip install -e '.[dev]')")


def sci(x: float) -> str:
    """2.0·10⁻⁷ for 2e-7."""
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"{mantissa}·10{str(int(exponent)).translate(SUPERSCRIPT)}"


def st_default(relpath: str, name: str) -> float:
    """The initial value of a REAL declared in an ST file (`name : REAL := value;`)."""
    text = (ROOT / relpath).read_text(encoding="utf-8")
    m = re.search(rf"\b{name}\s*:\s*REAL\s*:=\s*([-+0-9.eE]+)\s*;", text)
    if m is None:
        raise ValueError(f"{relpath}: no REAL {name} with an initial value")
    return float(m.group(1))


@producer("fuzzy-universe")
def fuzzy_universe() -> str:
    """Where the 2 % band and the load upset of the default scenario fall on the universe, full span vs
    headroom (the reasoning behind fHeadroomShare in FC_FuzzyScalingFromPlant)."""
    runs = default_run()
    scenario = runs[0][0].scenario
    tune = _phase(runs[0][1], "tune")
    fuzzy = next(pms for result, pms in runs if result.variant.fuzzy)
    load = _phase(fuzzy, "load")
    step_index = next(i for i, p in enumerate(scenario.zones[0].phases) if p.name == "step")
    w1 = scenario.zones[0].phases[step_index].setpoint_c
    w0 = [p.setpoint_c for p in scenario.zones[0].phases[:step_index] if p.setpoint_c is not None][-1]
    if tune is None or load is None or w0 is None or w1 is None:
        raise ValueError(f"{scenario.name}: no tune, step or load phase")
    kp0 = tune.values["tuned_kp_pct_per_c"]
    u = st_default("st_lib/fuzzy/ST_FuzzyParameter.st", "fUniverse")
    share = st_default("st_lib/fuzzy/FC_FuzzyScalingFromPlant.st", "fHeadroomShare")
    span = st_default("st_lib/types/ST_ControllerParameter.st", "fYMax") - max(
        st_default("st_lib/types/ST_ControllerParameter.st", "fYMin"), 0.0)
    band = 0.02 * abs(w1 - w0)
    upset = abs(load.values["max_deviation_c"])
    spacing = u / 3.0
    lines = [
        f"Default scenario `{scenario.name}` (`thermost run`, stepped): tuned Kp0 {kp0:.2f} %/°C, "
        f"step {w0:g} → {w1:g} °C (2 % band ±{band:.2f} °C), largest deviation after the load step "
        f"{upset:.2f} °C (fuzzy PID); U = {u:g}, triangular sets, ZO covers |E| < {spacing:g}.",
        "",
        "| ΔY | e_max = ΔY/Kp0 | 2 % band: \\|E\\| (μ_ZO) | load upset: \\|E\\| (μ_ZO) |",
        "|---|---|---|---|",
    ]
    for label, dy in ((f"full span, {span:g} %", span),
                      (f"headroom, {share * span:g} % (default)", share * span)):
        e_max = dy / kp0
        cells = []
        for e in (band, upset):
            q = u * e / e_max
            cells.append(f"{q:.2f} ({max(0.0, 1.0 - q / spacing):.2f})")
        lines.append(f"| {label} | {e_max:.1f} °C | {cells[0]} | {cells[1]} |")
    return "\n".join(lines) + "\n"


@producer("fuzzy-oracle")
def fuzzy_oracle() -> str:
    """ST inference vs the independent oracle (tests/test_fuzzy_inference.py, tests/test_fuzzy_oracle.py)."""
    tests_on_path()
    _oracle_available()
    from tests.test_fuzzy_inference import CONFIGS, TOLERANCE, grid, oracle_deviation
    from tests.test_fuzzy_oracle import GAUSS_HALF_CROSSING, discretisation_error

    points = {len(grid(cfg.universe, seed=len(cfg.preset) + cfg.output_points)) for cfg in CONFIGS}
    lines = [
        f"`tests/test_fuzzy_inference.py`: {'/'.join(map(str, sorted(points)))} (E, EC) points per "
        "configuration (every other set centre on both axes and random points, some outside the universe); "
        f"largest |ST − oracle| as a share of the output range, limit {sci(TOLERANCE)}:",
        "",
        "| membership | preset | defuzzification | U | N | largest \\|ST − oracle\\| |",
        "|---|---|---|---|---|---|",
    ]
    for cfg in CONFIGS:
        kind = cfg.kind
        if kind != "triangular" and abs(cfg.gauss_width - GAUSS_HALF_CROSSING) > 1e-3:
            kind += f" σ = {cfg.gauss_width:.2f}·d"
        n = cfg.output_points if cfg.defuzz == "centroid" else "–"
        worst, _ = oracle_deviation(cfg)
        lines.append(f"| {kind} | {cfg.preset} | {cfg.defuzz} | {cfg.universe:g} | {n} | {sci(worst)} |")
    lines += [
        "",
        f"Discretisation of the centroid (`tests/test_fuzzy_oracle.py`: the oracle on 61 output samples vs. "
        f"a 24 001-point centroid, 15 random points per membership kind): at most "
        f"{sci(discretisation_error())} of the output range.",
    ]
    return "\n".join(lines) + "\n"


@producer("fuzzy-closed-loop")
def fuzzy_closed_loop() -> str:
    """The closed loop of tests/test_fuzzy_adapter.py: FB_CtrlPid + FOPDT, fixed set vs adapter."""
    tests_on_path()
    from tests import test_fuzzy_adapter as t

    loops = t.closed_loops()
    ratios = np.array(loops["fuzzy"].ratios)
    steps = t.gain_caused_steps(loops["fuzzy"])
    iae_fixed, iae_fuzzy = t.iae(loops["fixed"]), t.iae(loops["fuzzy"])
    ranges = ", ".join(
        f"{name} {ratios[:, i].min():.2f}..{ratios[:, i].max():.2f}"
        for i, name in enumerate(("Kp", "Ki", "Kd"))
    )
    return (
        f"FOPDT K = {t.PLANT_K:g} °C/%, T = {t.PLANT_T:g} s, L = {t.PLANT_L:g} s, CHR base set Kp "
        f"{t.BASE['fKp']:g} %/°C, Tn {t.BASE['fTn']:g} s, Tv {t.BASE['fTv']:g} s; textbook table as printed, "
        f"plant-linked scaling, no Ms bound; {t.AMBIENT:g} → {t.SETPOINT:g} °C and a {t.LOAD_STEP:g} % load "
        f"step halfway:\n\n"
        f"- ratios moved {ranges} (bounds 0.5..1.5);\n"
        f"- largest output step caused by a gain change (output of the cycle minus the output the PID law "
        f"gives with the previous cycle's gains): {steps.max():.3f} % of the range "
        f"(limit {t.BUMP_LIMIT:g} %); "
        f"|ΔKp·e| at most {t.kp_change_steps(loops['fuzzy']).max():.3f} % per cycle "
        f"(`fMaxOutputStep` {t.MAX_OUTPUT_STEP:g} %);\n"
        f"- IAE fixed PID {iae_fixed:.0f} °C·s, fuzzy {iae_fuzzy:.0f} °C·s "
        f"({(iae_fuzzy / iae_fixed - 1.0) * 100:+.1f} %).\n"
    )


@producer("fuzzy-seed003")
def fuzzy_seed003() -> str:
    """Seed 003's example point and table 2 against the library (tests/test_fuzzy_seed003.py)."""
    tests_on_path()
    from tests import test_fuzzy_seed003 as t

    got = t.example_point()
    paper = t.PAPER_EXAMPLE
    dev = np.array(t.table2_deviations())
    gap, cfg, (e, ec) = t.closest_setup()
    width = "" if cfg.kind == "triangular" else f", σ = {cfg.gauss_width:g}·spacing"
    return (
        f"- E = −1, EC = −3: library (ST) **ΔKp = {got[0]:+.3f}, ΔKi = {got[1]:+.3f}, ΔKd = {got[2]:+.3f}**; "
        f"paper {paper[0]:+.3f}, {paper[1]:+.3f}, {paper[2]:+.3f}.\n"
        f"- Closest of the swept setups ({len(t.SWEEP_KINDS)} membership kinds, σ ∈ "
        f"{{{', '.join(f'{w:g}' for w in t.SWEEP_WIDTHS)}}}·spacing, both defuzzifiers, inputs as printed, "
        f"transposed and sign-flipped): {cfg.kind}{width}, {cfg.defuzz}, (E, EC) = ({e:g}, {ec:g}), still "
        f"{gap:.2f} off (largest component).\n"
        f"- Table 2, {dev.size // 3} printed cells × 3 outputs: |library − paper| {dev.mean():.3f} "
        f"on average, "
        f"median {np.median(dev):.3f}, {np.mean(dev <= 0.05) * 100:.0f} % of the values within 0.05.\n"
    )


@producer("fuzzy-scan-cost", measured=True)
def fuzzy_scan_cost() -> str:
    """docs/fuzzy.md: FB_FuzzyGainAdapter per call in the soft-PLC (the adapter rows of softplc-bench)."""
    import os

    from plc.bench_adapter import CYCLE_BUDGET_US

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    rows = ["| mode | µs per call | share of 10 ms |", "|---|---|---|"]
    for mode, cost, status in adapter_cost_rows():
        if cost is None:
            rows.append(f"| {mode} | {status} | |")
        else:
            rows.append(f"| {mode} | {cost:,.0f} | {cost / CYCLE_BUDGET_US * 100:.1f} % |")
    return (f"Measured by `make docs` on {os.cpu_count()} cores, load average {load:.1f} at the start (CPU "
            "time, baseline program subtracted):\n\n" + "\n".join(rows) + "\n")

