"""The model-based setpoint response through Modbus on seed 000's forming platform (scenario
seed000_forming_platform, variant "model-based PID"): a bath about 1,800 s behind a loop of about 50 s, which
TUNE identifies as two unequal lags on its cooling side, then a further cooling step 4 -> 2 degC. The plan is
a pulse of full cooling, a brake of full heating and the holding power. Goals on the true temperature:
2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which overshoots 2 % to enter
the band early), overshoot <= 0.5 %."""

from __future__ import annotations

from modbus_bridge.scenario import load_scenario, resolve_scenario

from .heatup_step import model_based_step

SCENARIO = "seed000_forming_platform"
BOUND_RATIO, OVERSHOOT_PCT = 1.05, 0.5


def test_the_platform_s_cool_down_enters_the_band_before_one_switch_could(harness):
    step = model_based_step(harness, load_scenario(resolve_scenario(SCENARIO)), SCENARIO)
    assert step.settling_s <= BOUND_RATIO * step.bound_s
    assert step.overshoot_pct <= OVERSHOOT_PCT
