"""The model-based setpoint response through Modbus on seed 000's forming platform (scenario
seed000_forming_platform, variant "model-based PID"): a bath about 1,800 s behind a loop of about 50 s, which
TUNE identifies as two unequal lags on its cooling side, then a further cooling step 4 -> 2 degC. The plan is
a pulse of full cooling, a brake of full heating and the holding power. Goals on the true temperature:
2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which overshoots 2 % to enter
the band early), overshoot <= 0.5 %."""

from __future__ import annotations

import dataclasses

from modbus_bridge.optimise.robustness import plant_model, scored_step
from modbus_bridge.plants.response import bang_hold_bound
from modbus_bridge.scenario import load_scenario, resolve_scenario

from .conftest import run_scenario

SCENARIO = "seed000_forming_platform"
VARIANT = "model-based PID"
BOUND_RATIO, OVERSHOOT_PCT = 1.05, 0.5


def test_the_platform_s_cool_down_enters_the_band_before_one_switch_could(harness):
    sc = load_scenario(resolve_scenario(SCENARIO))
    sc = dataclasses.replace(sc, variants=[v for v in sc.variants if v.name == VARIANT])
    [(result, metrics)] = run_scenario(harness, sc)
    assert result.error is None, result.error
    step = {m.phase: m for m in metrics}["step"].values
    scored, y0, r = scored_step(sc)
    horizon = sc.zones[0].phases[scored].duration_s  # the bound over the step phase the test judges
    bound = bang_hold_bound(plant_model(sc), y0, r, sc.dt_s, horizon)
    settling = step["true_settling_time_2pct_s"]
    print(f"{SCENARIO}: bound {bound.settling_s:.1f} s (one switch, {bound.overshoot_pct:.2f} %); "
          f"model-based {settling:.1f} s = {settling / bound.settling_s:.2f} x, "
          f"true overshoot {step['true_overshoot_pct']:.2f} %")
    assert settling <= BOUND_RATIO * bound.settling_s
    assert step["true_overshoot_pct"] <= OVERSHOOT_PCT
