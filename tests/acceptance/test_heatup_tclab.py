"""The model-based setpoint response through Modbus on the TCLab (scenario t4_tclab, variant "model-based
PID"): two heaters on one board, zone 1 tuned while zone 2 is idle, then stepped 45 -> 60 degC while zone 2
holds its own setpoint. TUNE fits two unequal lags to a plant of three coupled states, so the model the
plan starts from is not the plant the step meets; the rise's line re-plans on the lags it shows. Goals on
the true temperature: 2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which
overshoots about 2 % to enter the band early), overshoot <= 2 % (the mismatch goal) and <= 0.5 % (the
nominal goal, not met yet: SHORTFALLS). The rise reads a slow lag longer than the model's, and a slower
rise is planned between the two (a slower sensor wants the lag read, a weaker heater the model's): on this
board the pulse then carries the plant past W. The 0.5 % was met while the PID's integrator started the
path about 2 % below the holding power, the tuned filter's lag on the rising X read as X behind the path;
that offset also left other noise draws below W for minutes (docs/library.md)."""

from __future__ import annotations

import pytest

from modbus_bridge.scenario import load_scenario, resolve_scenario

from .conftest import skip_known_shortfall
from .heatup_step import ScoredStep, model_based_step

SCENARIO = "t4_tclab"
BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, NOMINAL_OVERSHOOT_PCT = 1.05, 2.0, 0.5
# goals not met yet: skipped in CI with the reason, strict expected failures with THERMOST_SLOW=1
SHORTFALLS = {
    "nominal overshoot": "the rise reads a slow lag 18 % longer than the model's and the plan between the "
    "two carries the true temperature 1.24 % past W",
}


@pytest.fixture(scope="module")
def tclab_step(harness) -> ScoredStep:
    """One run for both tests."""
    return model_based_step(harness, load_scenario(resolve_scenario(SCENARIO)), SCENARIO)


def test_the_tclab_step_enters_the_band_with_the_bound_and_within_the_mismatch_overshoot(tclab_step):
    assert tclab_step.settling_s <= BOUND_RATIO * tclab_step.bound_s
    assert tclab_step.overshoot_pct <= MISMATCH_OVERSHOOT_PCT


@pytest.mark.xfail(reason=f"known shortfall: {SHORTFALLS['nominal overshoot']}", strict=True)
def test_the_tclab_step_meets_the_nominal_overshoot(tclab_step):
    skip_known_shortfall(f"{SCENARIO} nominal overshoot", SHORTFALLS["nominal overshoot"])
    assert tclab_step.overshoot_pct <= NOMINAL_OVERSHOOT_PCT
