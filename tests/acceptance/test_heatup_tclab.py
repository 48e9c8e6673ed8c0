"""The model-based setpoint response through Modbus on the TCLab (scenario t4_tclab, variant "model-based
PID"): two heaters on one board, zone 1 tuned while zone 2 is idle, then stepped 45 -> 60 degC while zone 2
holds its own setpoint. TUNE fits two unequal lags to a plant of three coupled states, so the model the
plan starts from is not the plant the step meets; the rise's line re-plans on the lags it shows. Goals on
the true temperature: 2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which
overshoots about 2 % to enter the band early), overshoot <= 2 % (the mismatch goal) and <= 0.5 % (the
nominal goal, not met: the known shortfall below)."""

from __future__ import annotations

import dataclasses

import pytest

from modbus_bridge.optimise.robustness import plant_model, scored_step
from modbus_bridge.plants.response import bang_hold_bound
from modbus_bridge.scenario import load_scenario, resolve_scenario

from .conftest import run_scenario

SCENARIO = "t4_tclab"
VARIANT = "model-based PID"
BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, NOMINAL_OVERSHOOT_PCT = 1.05, 2.0, 0.5
SHORTFALL = (
    "0.74 % true overshoot: the identified gain is 1.7 % below the plant's at the step, so the plan switches "
    "about 2.6 s later than one on the true plant would and holds 0.5 % of output too much, which the PID's "
    "integral starts taking off only once the path is inside the settling band"
)


@pytest.fixture(scope="module")
def tclab_step(harness) -> tuple[dict, float]:
    """The step phase's metrics and the bound, from one run for both tests."""
    sc = load_scenario(resolve_scenario(SCENARIO))
    sc = dataclasses.replace(sc, variants=[v for v in sc.variants if v.name == VARIANT])
    [(result, metrics)] = run_scenario(harness, sc)
    assert result.error is None, result.error
    scored, y0, r = scored_step(sc)
    horizon = sc.zones[0].phases[scored].duration_s
    bound = bang_hold_bound(plant_model(sc), y0, r, sc.dt_s, horizon)
    step = {m.phase: m for m in metrics}[sc.zones[0].phases[scored].name].values
    print(f"{SCENARIO}: bound {bound.settling_s:.1f} s (one switch, {bound.overshoot_pct:.2f} %); "
          f"model-based {step['true_settling_time_2pct_s']:.1f} s = "
          f"{step['true_settling_time_2pct_s'] / bound.settling_s:.2f} x, "
          f"true overshoot {step['true_overshoot_pct']:.2f} %")
    return step, bound.settling_s


def test_the_tclab_step_enters_the_band_with_the_bound_and_within_the_mismatch_overshoot(tclab_step):
    step, bound_s = tclab_step
    assert step["true_settling_time_2pct_s"] <= BOUND_RATIO * bound_s
    assert step["true_overshoot_pct"] <= MISMATCH_OVERSHOOT_PCT


@pytest.mark.xfail(reason=f"known shortfall: {SHORTFALL}", strict=True)
def test_the_tclab_step_meets_the_nominal_overshoot(tclab_step):
    step, _ = tclab_step
    assert step["true_overshoot_pct"] <= NOMINAL_OVERSHOOT_PCT
