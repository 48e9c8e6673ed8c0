"""The model-based setpoint response through Modbus on the TCLab (scenario t4_tclab, variant "model-based
PID"): two heaters on one board, zone 1 tuned while zone 2 is idle, then stepped 45 -> 60 degC while zone 2
holds its own setpoint. TUNE fits two unequal lags to a plant of three coupled states, so the model the
plan starts from is not the plant the step meets; the rise's line re-plans on the lags it shows. Goals on
the true temperature: 2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which
overshoots about 2 % to enter the band early), overshoot <= 2 % (the mismatch goal) and <= 0.5 % (the
nominal goal). The identified gain is below the plant's at the step, so the plan switches late and holds a
little too much power; what keeps the peak within 0.5 % is a PID whose output follows the sensor noise less
(P and D sized together for the noise goal; with the D part alone held to it, the step overshot by more than
0.5 %). Other noise draws scatter the model and the overshoot with it (docs/library.md)."""

from __future__ import annotations

import pytest

from modbus_bridge.scenario import load_scenario, resolve_scenario

from .heatup_step import ScoredStep, model_based_step

SCENARIO = "t4_tclab"
BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, NOMINAL_OVERSHOOT_PCT = 1.05, 2.0, 0.5


@pytest.fixture(scope="module")
def tclab_step(harness) -> ScoredStep:
    """One run for both tests."""
    return model_based_step(harness, load_scenario(resolve_scenario(SCENARIO)), SCENARIO)


def test_the_tclab_step_enters_the_band_with_the_bound_and_within_the_mismatch_overshoot(tclab_step):
    assert tclab_step.settling_s <= BOUND_RATIO * tclab_step.bound_s
    assert tclab_step.overshoot_pct <= MISMATCH_OVERSHOOT_PCT


def test_the_tclab_step_meets_the_nominal_overshoot(tclab_step):
    assert tclab_step.overshoot_pct <= NOMINAL_OVERSHOOT_PCT
