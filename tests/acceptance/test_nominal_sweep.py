"""Nominal shipped scenarios (noise, load steps, plant-time-constant mismatch) over Modbus: no alarm bit
ever set, so 0 trips and 0 latched warnings. CI runs seed 003's PID variant and T3; THERMOST_SLOW=1 runs
every shipped scenario and variant."""

from __future__ import annotations

import dataclasses

import pytest

from modbus_bridge.scenario import load_scenario, resolve_scenario, shipped_scenarios
from tests.slow_cases import skip_known_shortfall, skip_unless_slow, slow_enabled

from .conftest import assert_no_alarm, run_scenario

QUICK = {"seed003_hotend_fuzzy": "PID (self-tuned)", "t3_marlin_hotend": None}
NOT_NOMINAL = ("seed003_sensor_fault",)  # the fault-injection scenario
# goals not met yet: skipped in CI with the reason, expected failures with THERMOST_SLOW=1
SHORTFALLS: dict[str, str] = {}


def names():
    return [p.stem for p in shipped_scenarios() if p.stem not in NOT_NOMINAL]


def cases():
    for name in names():
        marks = [pytest.mark.xfail(reason=f"known shortfall: {SHORTFALLS[name]}", strict=True)] \
            if name in SHORTFALLS else []
        yield pytest.param(name, marks=marks)


@pytest.mark.parametrize("name", list(cases()))
def test_nominal_scenario_raises_no_alarm(harness, name):
    if name in SHORTFALLS:
        skip_known_shortfall(name, SHORTFALLS[name])
    if name not in QUICK:
        skip_unless_slow(f"{name}: full nominal sweep")
    sc = load_scenario(resolve_scenario(name))
    if QUICK.get(name) and not slow_enabled():
        sc = dataclasses.replace(sc, variants=[v for v in sc.variants if v.name == QUICK[name]])
    assert sc.variants, f"{name}: no variant to run"
    runs = run_scenario(harness, sc)
    assert len(runs) == len(sc.variants)
    for result, _ in runs:
        assert_no_alarm(result, f"{name} / {result.variant.name}")
