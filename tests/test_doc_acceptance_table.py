"""docs/harness.md's table of the acceptance suite states each file's goals in words. They are tied to the
constants the tests assert with: every acceptance test file has a row, every goal constant shows in its
row as the test holds it, and every figure the row states (a ratio, a share, a time, a temperature, a
count) is one of those goals or a fact of the scenario the file runs. A tightened bound with the table
left behind fails here."""

from __future__ import annotations

import functools
import importlib
import re
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

from modbus_bridge.optimise.robustness import scored_step
from modbus_bridge.regmap import load_register_map
from modbus_bridge.scenario import Scenario, load_scenario, resolve_scenario

ROOT = Path(__file__).resolve().parents[1]
HARNESS_DOC = ROOT / "docs" / "harness.md"
ACCEPTANCE = ROOT / "tests" / "acceptance"
SECTION = "## Acceptance suite"
# a figure with its unit; the unit-less numbers of a row (bit numbers, seeds) are not goals
FIGURE = re.compile(r"(?<![\w.,])(\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?)\s?(×|%|s\b|°C)?")
METRIC_TERMS = ("2 % settling", "2 % band")  # the metric's name, not a goal (metrics.py)
COUNT_WORDS = {2: "two", 3: "three", 8: "eight"}
FACTOR_WORDS = {0.5: "half", 2.0: "twice"}


def with_unit(unit: str) -> Callable[[float], str]:
    """A figure as the table writes it: 1.05×, 0.5 %, 60 s, 0.2 °C."""
    return lambda v: f"{v:g}{unit}"


ratio, pct, seconds, degc = with_unit("×"), with_unit(" %"), with_unit(" s"), with_unit(" °C")


def share(v: float) -> str:
    return pct(v * 100)


def change(scale: float) -> str:
    """A plant parameter times `scale`, as a row says it: 30 % for 0.7 and 1.3."""
    return f"{abs(scale - 1.0) * 100:.0f} %"


def count(v: int) -> str:
    return f"{v:,}"


@functools.cache
def scenario(name: str) -> Scenario:
    return load_scenario(resolve_scenario(name))


def step_of(name: str) -> str:
    _, y0, r = scored_step(scenario(name))
    return f"{y0:g} → {r:g} °C"


def noise_of(name: str) -> str:
    return degc(scenario(name).zones[0].sensor.noise_sigma_c)


def module(name: str) -> ModuleType:
    """The acceptance test file's module."""
    return importlib.import_module(f"tests.acceptance.{name.removesuffix('.py')}")


def _fuzz_writes_in_makefile() -> int:
    found = re.search(r"THERMOST_FUZZ_WRITES=(\d+)", (ROOT / "Makefile").read_text(encoding="utf-8"))
    assert found, "Makefile: no THERMOST_FUZZ_WRITES in the fuzz target"
    return int(found.group(1))


# per file: the texts its row must hold, each made from the constant the file asserts with (or the
# scenario it runs); every figure of the row must come from one of them
def goals() -> dict[str, Callable[[ModuleType], list[str]]]:
    """File name -> the texts its row must hold, from the file's module (or the scenario it runs)."""
    return {
        "test_acceptance.py": lambda m: [
            share(m.IDENTIFICATION_TOLERANCE), pct(m.PAPER_OVERSHOOT_PCT), seconds(m.PAPER_SETTLING_S),
            seconds(m.PAPER_RECOVERY_S), seconds(m.SENSOR_DETECTION_S), seconds(m.REACTION_S)],
        "test_fault_injection.py": lambda m: [
            f"L + {seconds(m.GOAL_AFTER_DEAD_TIME_S)}", seconds(m.FROZEN_GOAL_S),
            f"watchdog time + {seconds(m.STALE_MARGIN_S)}"],
        "test_heatup.py": lambda m: [
            ratio(m.NOMINAL_RATIO), pct(m.NOMINAL_OVERSHOOT_PCT), ratio(m.MISMATCH_RATIO),
            pct(m.MISMATCH_OVERSHOOT_PCT), *{f"T ±{change(s)}" for s in m.SCALES}],
        "test_heatup_oven.py": lambda m: [
            ratio(m.BOUND_RATIO), pct(m.OVERSHOOT_PCT), f"{FACTOR_WORDS[m.PID_ALONE_SLOWER]} as long",
            *{change(s) for s in m.LAGS_AFTER_TUNE},
            *{"longer" if s > 1 else "shorter" for s in m.LAGS_AFTER_TUNE}],
        "test_fuzzy_mismatch.py": lambda m: [
            f"Ms ≤ {load_register_map()['fFuzzyMsMaxZone1'].meta.default:g}",
            f"{change(_dead_time_scale('seed003_mismatch_L130'))} longer", step_of("seed003_mismatch_L130")],
        "test_fuzzy_platform.py": lambda m: [
            step_of("seed000_forming_platform"), share(m.BAND_SHARE) + " band", seconds(m.TAIL_S),
            f"{FACTOR_WORDS[m.TAIL_SPAN_SHARE]} the band", pct(m.OVERSHOOT_LIMIT_PCT) + " overshoot limit"],
        "test_heatup_platform.py": lambda m: [
            step_of("seed000_forming_platform"), ratio(m.BOUND_RATIO), pct(m.OVERSHOOT_PCT)],
        "test_heatup_tclab.py": lambda m: [
            step_of("t4_tclab"), ratio(m.BOUND_RATIO), pct(m.MISMATCH_OVERSHOOT_PCT),
            pct(m.NOMINAL_OVERSHOOT_PCT), pct(_zone1_write("t4_tclab", "fEndTunePercentZone1")),
            f"{COUNT_WORDS[len(m.DRAWS)]} other noise draws"],
        "test_heatup_mismatch.py": lambda m: [
            *{change(s) for s in m.SCALES}, pct(m.MISMATCH_OVERSHOOT_PCT), ratio(m.MISMATCH_BOUND_RATIO)],
        "test_shared_body.py": lambda m: [],
        "test_noise_draws.py": lambda m: [f"{COUNT_WORDS[len(m.SEEDS)]} noise draws", noise_of("t4_tclab")],
        "test_noise.py": lambda m: [
            degc(m.SENSOR_NOISE_C), pct(m.OUTPUT_STD_GOAL_PCT), f"±{degc(m.RIPPLE_GOAL_C)}"],
        "test_nominal_sweep.py": lambda m: [
            *{f"±{change(s)}" for pair in module("test_model_mismatch.py").SCALES for s in pair}],
        "test_model_mismatch.py": lambda m: [],
        "test_write_fuzz.py": lambda m: [count(m.DEFAULT_WRITES), count(_fuzz_writes_in_makefile())],
        "test_persist.py": lambda m: [],
        "test_one_plc.py": lambda m: [],
    }


def goals_of(name: str) -> list[str]:
    return GOALS[name](module(name))


def _zone1_write(name: str, register: str) -> float:
    values = [float(p.writes[register]) for p in scenario(name).zones[0].phases if register in p.writes]
    assert len(values) == 1, f"{name}: expected one write of {register} in zone 1, found {values}"
    return values[0]


def _dead_time_scale(name: str) -> float:
    scales = [float(d.value) for p in scenario(name).zones[0].phases for d in p.disturbances
              if d.kind == "dead_time_mismatch"]
    assert len(scales) == 1, f"{name}: expected one dead-time change, found {scales}"
    return scales[0]


def table_rows() -> dict[str, tuple[str, list[str]]]:
    """File name -> the text of its row and the files the row names (a row naming two files belongs to
    both, and states the goals of both)."""
    text = HARNESS_DOC.read_text(encoding="utf-8")
    assert SECTION in text, f"{HARNESS_DOC.name}: no '{SECTION}' section"
    section = text.split(SECTION, 1)[1].split("\n## ", 1)[0]
    rows: dict[str, str] = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 2 or not cells[0].startswith("`test_"):
            continue
        names = re.findall(r"`(test_\w+\.py)`", cells[0])
        for name in names:
            rows[name] = (" | ".join(cells[1:]), names)
    return rows


def figures(text: str) -> list[str]:
    """The figures a row states: numbers with a unit, and counts written with thousands separators."""
    text = re.sub(r"`[^`]*`", "", text)  # register and file names
    for term in METRIC_TERMS:
        text = text.replace(term, "")
    out = []
    for number, unit in FIGURE.findall(text):
        if unit:
            out.append(f"{number}{unit}" if unit == "×" else f"{number} {unit}")
        elif "," in number:
            out.append(number)
    return out


ROWS = table_rows()
GOALS = goals()


def test_every_acceptance_file_has_a_row():
    files = sorted(p.name for p in ACCEPTANCE.glob("test_*.py"))
    missing = [f for f in files if f not in ROWS]
    assert not missing, f"{HARNESS_DOC.name}: no row in the acceptance table for {missing}"
    unknown = [f for f in ROWS if f not in files]
    assert not unknown, f"{HARNESS_DOC.name}: rows for files that do not exist: {unknown}"
    untied = [f for f in files if f not in GOALS]
    assert not untied, f"no goals listed here for {untied}: say which constants their rows state"


@pytest.mark.parametrize("name", sorted(GOALS))
def test_the_row_states_the_goals_the_file_holds(name: str):
    assert name in ROWS, f"{HARNESS_DOC.name}: no row for {name}"
    row, shared_with = ROWS[name]
    wanted = goals_of(name)
    missing = [w for w in wanted if w not in row]
    assert not missing, f"{HARNESS_DOC.name}, row {name}: does not say {missing} (the file holds them)"
    explained = set(figures(" ; ".join(w for other in shared_with for w in goals_of(other))))
    untied = [f for f in figures(row) if f not in explained]
    assert not untied, (f"{HARNESS_DOC.name}, row {name}: {untied} is not a goal of the file nor a fact "
                        f"of its scenario (it holds {wanted})")
